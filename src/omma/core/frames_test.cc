// The frames folder with what real cameras write: JPEG and TIFF next to PNG, gray images, EXIF
// orientation, cameras of different sizes, and clear errors naming the file and the sizes.
#include "omma/core/frames.h"

#include <cstdlib>
#include <fstream>
#include <random>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "omma/core/io.h"

namespace omma {
namespace {
namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& tag) {
  const fs::path d = fs::temp_directory_path() / fmt::format("omma_frames_{}_{}", tag, ::getpid());
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

Rig rig_of_sizes(const std::vector<std::pair<int, int>>& sizes) {
  Rig rig;
  rig.name = "frames-test";
  for (size_t i = 0; i < sizes.size(); ++i) {
    RigCamera c;
    c.id = static_cast<int>(i);
    c.in.width = sizes[i].first;
    c.in.height = sizes[i].second;
    c.in.cu = c.in.width / 2.0;
    c.in.cv = c.in.height / 2.0;
    rig.cameras.push_back(c);
  }
  return rig;
}

// A picture whose four quadrants differ (so that a rotation shows).
cv::Mat quadrants(int w, int h) {
  cv::Mat m(h, w, CV_8UC3, cv::Scalar(0, 0, 0));
  m(cv::Rect(0, 0, w / 2, h / 2)).setTo(cv::Scalar(250, 250, 250));      // top left white
  m(cv::Rect(w / 2, 0, w - w / 2, h / 2)).setTo(cv::Scalar(0, 0, 250));  // top right red
  return m;
}

bool has_exiftool() { return std::system("exiftool -ver > /dev/null 2>&1") == 0; }

TEST(Frames, ReadsJpegTiffAndPngOfDifferentSizes) {
  const fs::path d = fresh_dir("formats");
  cv::imwrite((d / "cam_00.png").string(), quadrants(64, 48));
  cv::imwrite((d / "cam_01.jpg").string(), quadrants(80, 60), {cv::IMWRITE_JPEG_QUALITY, 95});
  cv::imwrite((d / "cam_02.TIFF").string(), quadrants(32, 40));
  cv::Mat gray(30, 20, CV_8UC1, cv::Scalar(77));
  cv::imwrite((d / "cam_03.jpeg").string(), gray);  // a gray JPEG
  const Rig rig = rig_of_sizes({{64, 48}, {80, 60}, {32, 40}, {20, 30}});
  const auto frames = load_frames(d, rig);
  ASSERT_EQ(frames.size(), 4u);
  for (size_t i = 0; i < frames.size(); ++i) {
    EXPECT_EQ(frames[i].channels(), 3) << i;
    EXPECT_EQ(frames[i].cols, rig.cameras[i].in.width) << i;
    EXPECT_EQ(frames[i].rows, rig.cameras[i].in.height) << i;
  }
  EXPECT_NEAR(frames[3].at<cv::Vec3b>(10, 10)[2], 77, 2);
  EXPECT_EQ(expand_shot_folders({d}).size(), 1u);  // a folder of JPEGs is a frames folder
  EXPECT_TRUE(is_frame_filename("cam_07.JPG"));
  EXPECT_FALSE(is_frame_filename("cam_07_raw.png"));
  EXPECT_FALSE(is_frame_filename("cam_.png"));
  fs::remove_all(d);
}

TEST(Frames, TwoFilesForOneCameraIsAnErrorNamingBoth) {
  const fs::path d = fresh_dir("ambiguous");
  cv::imwrite((d / "cam_00.png").string(), quadrants(16, 16));
  cv::imwrite((d / "cam_00.jpg").string(), quadrants(16, 16));
  try {
    load_frames(d, rig_of_sizes({{16, 16}}));
    FAIL() << "expected an error";
  } catch (const IoError& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("cam_00.png"), std::string::npos) << w;
    EXPECT_NE(w.find("cam_00.jpg"), std::string::npos) << w;
  }
  fs::remove_all(d);
}

TEST(Frames, MissingAndWrongSizeNameTheFileAndTheSizes) {
  const fs::path d = fresh_dir("errors");
  try {
    load_frames(d, rig_of_sizes({{16, 16}}));
    FAIL();
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("cam_00.png"), std::string::npos) << e.what();
  }
  cv::imwrite((d / "cam_00.jpg").string(), quadrants(40, 30));
  try {
    load_frames(d, rig_of_sizes({{30, 40}}));
    FAIL();
  } catch (const IoError& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("cam_00.jpg"), std::string::npos) << w;
    EXPECT_NE(w.find("40x30"), std::string::npos) << w;
    EXPECT_NE(w.find("30x40"), std::string::npos) << w;
  }
  fs::remove_all(d);
}

// A camera held upright writes a landscape JPEG with EXIF Orientation 6 ("rotate 90 deg clockwise
// to display"): the frame is the displayed, portrait picture, and the rig's size is the portrait one.
TEST(Frames, ExifOrientationIsApplied) {
  if (!has_exiftool()) GTEST_SKIP() << "exiftool not installed";
  const fs::path d = fresh_dir("exif");
  const cv::Mat stored = quadrants(40, 30);
  cv::imwrite((d / "cam_00.jpg").string(), stored, {cv::IMWRITE_JPEG_QUALITY, 98});
  ASSERT_EQ(std::system(
                ("exiftool -q -Orientation=6 -n -overwrite_original " + (d / "cam_00.jpg").string()).c_str()),
            0);
  const auto frames = load_frames(d, rig_of_sizes({{30, 40}}));
  ASSERT_EQ(frames[0].cols, 30);
  ASSERT_EQ(frames[0].rows, 40);
  cv::Mat rotated;
  cv::rotate(stored, rotated, cv::ROTATE_90_CLOCKWISE);
  cv::Mat diff;
  cv::absdiff(frames[0], rotated, diff);
  EXPECT_LT(cv::mean(diff)[0] + cv::mean(diff)[1] + cv::mean(diff)[2], 10.0);
  // The stored (unrotated) size is refused, naming both sizes.
  try {
    load_frames(d, rig_of_sizes({{40, 30}}));
    FAIL();
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("30x40"), std::string::npos) << e.what();
  }
  fs::remove_all(d);
}

TEST(Frames, SixteenBitGrayPngBecomesThreeChannels) {
  const fs::path d = fresh_dir("gray16");
  cv::Mat g(12, 10, CV_16UC1, cv::Scalar(40000));
  cv::imwrite((d / "cam_00.png").string(), g);
  const auto frames = load_frames(d, rig_of_sizes({{10, 12}}));
  EXPECT_EQ(frames[0].type(), CV_16UC3);
  EXPECT_EQ(frames[0].at<cv::Vec3w>(3, 3)[1], 40000);
  fs::remove_all(d);
}

}  // namespace
}  // namespace omma
