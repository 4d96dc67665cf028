// Point clouds from a depth map (point_cloud.h): geometry against the truth of a sphere, counts with
// steps, infinity and a confidence threshold, colours against the panorama, the PLY file byte for byte.
#include "omma/io/point_cloud.h"

#include <cstring>
#include <fstream>
#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>

#include "omma/core/io.h"
#include "omma/core/version.h"
#include "omma/design/prototype.h"
#include "omma/pano/surface.h"

namespace omma::io {
namespace {
namespace fs = std::filesystem;

fs::path temp_dir(const std::string& tag) {
  const fs::path d = fs::temp_directory_path() / ("omma-ply-" + tag + "-" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

cv::Mat random_colour(const PanoGrid& g, int seed) {
  cv::Mat m(g.height, g.width, CV_8UC3);
  cv::theRNG().state = uint64_t(seed);
  cv::randu(m, 0, 256);
  return m;
}

constexpr float kInf = std::numeric_limits<float>::infinity();

// A sphere of radius R around the dome centre, seen from an observer q off the centre
// (pano::sphere_depth solves |q + D w| = R): every point lies at |X| = R.
TEST(PointCloud, SphereDepthGivesPointsOnTheSphere) {
  const Rig rig = design::load_rig_or_builtin("thesis-24");
  for (const PanoGrid g : {PanoGrid{Projection::kVr180, 48, 48}, PanoGrid{Projection::kEquirectFull, 64, 32},
                           PanoGrid{Projection::kEquirect100, 72, 20}}) {
    for (const Vec3& q : {Vec3(0, 0, 0), Vec3(1.0, -2.0, 0.5)}) {
      const double R = 80;
      const cv::Mat depth = pano::sphere_depth(rig, g, R, q);
      PointCloudOptions opt;
      opt.q = q;
      const PointCloud c = depth_to_points(depth, random_colour(g, 1), g, opt);
      ASSERT_EQ(c.size(), size_t(g.width) * g.height);
      double worst = 0;
      for (const auto& p : c.xyz) worst = std::max(worst, std::abs(Vec3(p[0], p[1], p[2]).norm() - R));
      EXPECT_LT(worst, 1e-3) << to_string(g.projection) << " q " << q.transpose();
      // The first point is pixel (0, 0): q + D w exactly (to float precision).
      const Vec3 X = q + double(depth.at<float>(0, 0)) * g.pixel_direction(0, 0);
      for (int k = 0; k < 3; ++k) EXPECT_NEAR(c.xyz[0][k], X[k], 1e-4);
    }
  }
}

// Vertex count = the finite-depth pixels among the kept ones: W H / step^2 when the step divides the
// size; infinite pixels and those below the confidence threshold have no point.
TEST(PointCloud, CountsFollowStepInfinityAndConfidence) {
  const PanoGrid g{Projection::kVr180, 60, 60};
  cv::Mat depth(g.height, g.width, CV_32FC1, cv::Scalar(100));
  depth(cv::Rect(0, 0, 60, 12)).setTo(kInf);  // the top 12 rows at infinity
  const cv::Mat colour = random_colour(g, 2);
  for (int step : {1, 2, 3, 4, 6, 12}) {  // divisors of 12 and 60
    PointCloudOptions opt;
    opt.step = step;
    const PointCloud c = depth_to_points(depth, colour, g, opt);
    EXPECT_EQ(c.size(), size_t((60 - 12) * 60 / (step * step))) << "step " << step;
  }
  // Confidence: a ramp over the columns, col / 60; min 0.5 keeps columns 30..59.
  cv::Mat conf(g.height, g.width, CV_32FC1);
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) conf.at<float>(y, x) = float(x) / 60.0f;
  PointCloudOptions opt;
  opt.min_confidence = 0.5;
  EXPECT_EQ(depth_to_points(depth, colour, g, opt, conf).size(), size_t(48 * 30));
  opt.step = 2;
  EXPECT_EQ(depth_to_points(depth, colour, g, opt, conf).size(), size_t(24 * 15));
  // No depth (the scene at infinity): no points.
  EXPECT_EQ(depth_to_points(cv::Mat(), colour, g).size(), 0u);
}

// The colours are the panorama's pixels (OpenCV's BGR turned into the PLY's red, green, blue), in
// row-major order of the kept pixels; a gray panorama gives r = g = b.
TEST(PointCloud, ColoursAreThePanoramas) {
  const PanoGrid g{Projection::kEquirectFull, 40, 20};
  const cv::Mat depth(g.height, g.width, CV_32FC1, cv::Scalar(250));
  const cv::Mat colour = random_colour(g, 3);
  PointCloudOptions opt;
  opt.step = 3;
  const PointCloud c = depth_to_points(depth, colour, g, opt);
  size_t i = 0;
  for (int y = 0; y < g.height; y += 3)
    for (int x = 0; x < g.width; x += 3, ++i) {
      ASSERT_LT(i, c.size());
      const cv::Vec3b bgr = colour.at<cv::Vec3b>(y, x);
      EXPECT_EQ(c.rgb[i][0], bgr[2]);
      EXPECT_EQ(c.rgb[i][1], bgr[1]);
      EXPECT_EQ(c.rgb[i][2], bgr[0]);
    }
  EXPECT_EQ(i, c.size());
  cv::Mat gray;
  cv::extractChannel(colour, gray, 1);
  const PointCloud cg = depth_to_points(depth, gray, g);
  EXPECT_EQ(cg.rgb[5][0], gray.at<uint8_t>(0, 5));
  EXPECT_EQ(cg.rgb[5][2], gray.at<uint8_t>(0, 5));
}

// The PLY: the header of point_cloud.h, 15 bytes a vertex, and the same floats and colours read back.
TEST(PointCloud, PlyRoundTripsExactly) {
  const fs::path d = temp_dir("roundtrip");
  const PanoGrid g{Projection::kVr180, 32, 32};
  cv::Mat depth(g.height, g.width, CV_32FC1);
  cv::randu(depth, 20, 3000);
  depth.at<float>(3, 4) = kInf;
  PointCloud c = depth_to_points(depth, random_colour(g, 4), g, {Vec3(0.25, 0, -1)});
  c.comments = {"source test"};
  ASSERT_EQ(c.size(), 32u * 32u - 1u);
  const fs::path p = d / "c.ply";
  write_ply(p, c, Vec3(0.25, 0, -1));
  const std::string bytes = read_text_file(p, kMaxDataFileBytes);
  const size_t body = bytes.find("end_header\n") + 11;
  EXPECT_EQ(bytes.size(), body + 15 * c.size());
  EXPECT_EQ(bytes.rfind("ply\nformat binary_little_endian 1.0\ncomment omma " + version(), 0), 0u);
  EXPECT_NE(bytes.find("millimetres in the rig (dome) frame"), std::string::npos);
  EXPECT_NE(bytes.find("q = (0.25, 0, -1) mm"), std::string::npos);
  EXPECT_NE(bytes.find("element vertex 1023\nproperty float x\nproperty float y\nproperty float z\n"
                       "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n"),
            std::string::npos);
  const PointCloud r = read_ply(p);
  ASSERT_EQ(r.size(), c.size());
  for (size_t i = 0; i < c.size(); ++i) {
    ASSERT_EQ(std::memcmp(r.xyz[i].data(), c.xyz[i].data(), 12), 0) << i;
    ASSERT_EQ(r.rgb[i], c.rgb[i]) << i;
  }
  EXPECT_EQ(r.comments.back(), "source test");
  // Another tool's layout: ascii, doubles, extra properties, colours first.
  const PointCloud a = parse_ply(
      "ply\nformat ascii 1.0\nelement vertex 2\nproperty uchar red\nproperty uchar green\nproperty uchar "
      "blue\n"
      "property double x\nproperty double y\nproperty double z\nproperty float nx\nend_header\n"
      "1 2 3 4.5 5.5 6.5 0\n255 0 7 -1 -2 -3 1\n");
  ASSERT_EQ(a.size(), 2u);
  EXPECT_EQ(a.xyz[1][2], -3.0f);
  EXPECT_EQ(a.rgb[1][2], 7);
  fs::remove_all(d);
}

TEST(PointCloud, BadInputIsRefused) {
  const PanoGrid g{Projection::kVr180, 8, 8};
  const cv::Mat colour = random_colour(g, 5);
  cv::Mat depth(8, 8, CV_32FC1, cv::Scalar(50));
  PointCloudOptions opt;
  opt.step = 0;
  EXPECT_THROW(depth_to_points(depth, colour, g, opt), std::invalid_argument);
  opt = {};
  opt.min_confidence = 1.5;
  EXPECT_THROW(depth_to_points(depth, colour, g, opt), std::invalid_argument);
  EXPECT_THROW(depth_to_points(depth, colour, PanoGrid{Projection::kVr180, 9, 8}), std::invalid_argument);
  EXPECT_THROW(depth_to_points(cv::Mat(8, 8, CV_64FC1, cv::Scalar(1)), colour, g), std::invalid_argument);
  depth.at<float>(2, 2) = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(depth_to_points(depth, colour, g), std::invalid_argument);
  depth.at<float>(2, 2) = -1;
  EXPECT_THROW(depth_to_points(depth, colour, g), std::invalid_argument);
  // Files: truncated, no colour, not a PLY, big-endian; a folder that does not exist leaves nothing.
  PointCloud c;
  c.xyz = {{1, 2, 3}};
  c.rgb = {{4, 5, 6}};
  const std::string bytes = encode_ply(c);
  EXPECT_THROW(parse_ply(bytes.substr(0, bytes.size() - 1)), IoError);
  EXPECT_THROW(parse_ply("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                         "property float z\nend_header\n1 2 3\n"),
               IoError);
  EXPECT_THROW(parse_ply("PK\x03\x04"), IoError);
  EXPECT_THROW(parse_ply("ply\nformat binary_big_endian 1.0\nelement vertex 0\nend_header\n"), IoError);
  c.comments = {"two\nlines"};
  EXPECT_THROW(encode_ply(c), std::invalid_argument);
  c.comments.clear();
  EXPECT_THROW(write_ply("/nonexistent-omma-dir/c.ply", c), IoError);
  EXPECT_THROW(read_ply("/nonexistent-omma-dir/c.ply"), IoError);
}

}  // namespace
}  // namespace omma::io
