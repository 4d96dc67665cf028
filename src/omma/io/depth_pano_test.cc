// Depth panoramas (depth_pano.h): the 16-bit millimetre PNG round trip, Google's depth map in the colour
// JPEG and PNG, and what exiftool (Debian libimage-exiftool-perl) reads from them.
#include "omma/io/depth_pano.h"

#include <cstdio>
#include <fstream>
#include <limits>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "omma/core/io.h"
#include "omma/io/metadata.h"

namespace omma::io {
namespace {
namespace fs = std::filesystem;

constexpr float kInf = std::numeric_limits<float>::infinity();

fs::path temp_dir(const std::string& tag) {
  const fs::path d = fs::temp_directory_path() / ("omma-depthpano-" + tag + "-" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::string run(const std::string& cmd) {
  std::string out;
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return out;
  char buf[4096];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
  ::pclose(p);
  return out;
}

bool have_exiftool() { return std::system("command -v exiftool >/dev/null 2>&1") == 0; }

// A depth map from 20 mm to 60 m with some directions at infinity.
cv::Mat test_depth(const PanoGrid& g) {
  cv::Mat d(g.height, g.width, CV_32FC1);
  cv::theRNG().state = 7;
  cv::randu(d, 20, 60000);
  d(cv::Rect(0, 0, g.width, 3)).setTo(kInf);
  return d;
}

TEST(DepthPano, Png16RoundTripsWithinHalfAMillimetre) {
  const PanoGrid g{Projection::kEquirectFull, 64, 32};
  cv::Mat d = test_depth(g);
  d.at<float>(10, 10) = 70000;  // saturates
  d.at<float>(10, 11) = 0.2f;   // reads 1
  const cv::Mat back = depth_from_png16(depth_to_png16(d));
  double worst = 0;
  long infinite = 0;
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) {
      const float a = d.at<float>(y, x), b = back.at<float>(y, x);
      if (std::isinf(a)) {
        EXPECT_TRUE(std::isinf(b));
        ++infinite;
      } else if (a <= kDepthPngMaxMm && a >= 1) {
        worst = std::max(worst, double(std::abs(a - b)));
      }
    }
  EXPECT_LE(worst, 0.5);
  EXPECT_EQ(infinite, 3 * 64);
  EXPECT_EQ(depth_to_png16(d).at<uint16_t>(0, 0), 0);
  EXPECT_EQ(back.at<float>(10, 10), 65535.0f);
  EXPECT_EQ(back.at<float>(10, 11), 1.0f);
  cv::Mat bad = d.clone();
  bad.at<float>(1, 1) = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(depth_to_png16(bad), std::invalid_argument);
}

TEST(DepthPano, DepthPngFileCarriesItsDescriptionForExiftool) {
  const fs::path dir = temp_dir("png");
  const PanoGrid g{Projection::kEquirectFull, 64, 32};  // square pixels: GPano too
  const cv::Mat d = test_depth(g);
  write_depth_png(dir / "depth.png", d, g);
  const cv::Mat back = read_depth_png(dir / "depth.png");
  ASSERT_EQ(back.size(), d.size());
  EXPECT_EQ(cv::norm(back != back), 0.0);  // no NaN
  EXPECT_EQ(back.at<float>(5, 5), std::round(d.at<float>(5, 5)));
  EXPECT_TRUE(std::isinf(back.at<float>(0, 0)));
  EXPECT_THROW(write_depth_png(dir / "depth.jpg", d, g), std::invalid_argument);
  EXPECT_THROW(write_depth_png(dir / "small.png", d(cv::Rect(0, 0, 8, 8)).clone(), g), std::invalid_argument);
  if (!have_exiftool()) GTEST_SKIP() << "exiftool not installed (scripts/install-deps.sh --test)";
  const auto j = nlohmann::json::parse(
      run("exiftool -j -n -XMP-GDepth:All -XMP-GPano:All -XMP-dc:Description -BitDepth " +
          (dir / "depth.png").string()))[0];
  EXPECT_EQ(j.at("Format"), "RangeLinear");
  EXPECT_EQ(j.at("Near").get<double>(), 0.0);
  EXPECT_EQ(j.at("Far").get<double>(), 65535.0);
  EXPECT_EQ(j.at("Units"), "mm");
  EXPECT_EQ(j.at("MeasureType"), "OpticRay");
  EXPECT_EQ(j.at("BitDepth").get<int>(), 16);
  EXPECT_EQ(j.at("FullPanoWidthPixels").get<int>(), 64);
  EXPECT_EQ(j.at("FullPanoHeightPixels").get<int>(), 32);
  EXPECT_NE(j.at("Description").get<std::string>().find("0 = unknown or infinity"), std::string::npos);
  fs::remove_all(dir);
}

// Google's depth map inside the colour panorama: exiftool reads Near and Far (the finite range), the
// format, and the data, which decodes (RangeInverse) to the depth within the 16-bit quantisation
// (relative error (Far - Near) D / (Far Near) / 65535 / 2 <= 3000 / 65535 / 2 = 2.3 % at most, at D = Far
// with this range; measured below: the bound per pixel).
TEST(DepthPano, ColourPanoramaCarriesGoogleDepthMap) {
  const fs::path dir = temp_dir("gdepth");
  const PanoGrid g{Projection::kVr180, 200, 200};  // a depth PNG of > 64 KB: Extended XMP in the JPEG
  const cv::Mat d = test_depth(g);
  cv::Mat colour(g.height, g.width, CV_8UC3);
  cv::randu(colour, 0, 256);
  const DepthRange r = depth_range(d);
  EXPECT_EQ(r.finite, 200 * 197);
  write_panorama_with_depth(dir / "p.jpg", colour, d, g);
  write_panorama_with_depth(dir / "p.png", colour, d, g);
  EXPECT_THROW(write_panorama_with_depth(dir / "p.tif", colour, d, g), std::invalid_argument);
  // The images are the colour panorama.
  EXPECT_EQ(cv::norm(cv::imread((dir / "p.png").string()), colour, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::imread((dir / "p.jpg").string()).size(), colour.size());
  // The encoding itself: decoded within the quantisation, infinity as Far.
  const cv::Mat enc = gdepth_encode_inverse(d, r);
  const cv::Mat dec = gdepth_decode_inverse(enc, r.near_mm, r.far_mm);
  for (int y = 0; y < g.height; y += 7)
    for (int x = 0; x < g.width; x += 5) {
      const double D = std::isinf(d.at<float>(y, x)) ? r.far_mm : d.at<float>(y, x);
      const double bound = (r.far_mm - r.near_mm) * D / (r.far_mm * r.near_mm) / 65535 * D * 0.51 + 1e-3 * D;
      ASSERT_NEAR(dec.at<float>(y, x), D, bound) << x << "," << y;
    }
  if (!have_exiftool()) GTEST_SKIP() << "exiftool not installed (scripts/install-deps.sh --test)";
  for (const char* name : {"p.jpg", "p.png"}) {
    const fs::path p = dir / name;
    const auto j = nlohmann::json::parse(
        run("exiftool -j -n -validate -warning -a -XMP-GDepth:Format -XMP-GDepth:Near -XMP-GDepth:Far "
            "-XMP-GDepth:Units -XMP-GDepth:Mime -XMP-GDepth:MeasureType -XMP-GPano:FullPanoWidthPixels " +
            p.string()))[0];
    EXPECT_EQ(j.at("Format"), "RangeInverse") << name;
    EXPECT_EQ(j.at("Near").get<double>(), r.near_mm) << name;
    EXPECT_EQ(j.at("Far").get<double>(), r.far_mm) << name;
    EXPECT_EQ(j.at("Units"), "mm") << name;
    EXPECT_EQ(j.at("Mime"), "image/png") << name;
    EXPECT_EQ(j.at("MeasureType"), "OpticRay") << name;
    EXPECT_EQ(j.at("FullPanoWidthPixels").get<int>(), 400) << name;
    EXPECT_FALSE(j.contains("Warning")) << name << ": " << j.dump();
    // The data (GDepth:Data, exiftool calls it DepthImage), as exiftool extracts it (from Extended XMP in the
    // JPEG), is the encoded depth.
    const fs::path data = dir / (std::string(name) + "-depth.png");
    ASSERT_EQ(
        std::system(("exiftool -b -XMP-GDepth:DepthImage " + p.string() + " > " + data.string()).c_str()), 0);
    const cv::Mat png = cv::imread(data.string(), cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(png.empty()) << name << ": no GDepth:Data";
    EXPECT_EQ(cv::norm(png, enc, cv::NORM_INF), 0.0) << name;
  }
  fs::remove_all(dir);
}

TEST(DepthPano, Base64AndTheExtendedXmpGuid) {
  EXPECT_EQ(base64_encode("Man"), "TWFu");
  EXPECT_EQ(base64_encode("Ma"), "TWE=");
  EXPECT_EQ(base64_encode("M"), "TQ==");
  EXPECT_EQ(base64_encode(""), "");
  EXPECT_EQ(extended_xmp_guid("abc"), "900150983CD24FB0D6963F7D28E17F72");  // RFC 1321's MD5("abc")
  // A sphere: Near = Far, every value 0 and decoded as the radius.
  const cv::Mat s(4, 4, CV_32FC1, cv::Scalar(123.5));
  const DepthRange r = depth_range(s);
  const cv::Mat dec = gdepth_decode_inverse(gdepth_encode_inverse(s, r), r.near_mm, r.far_mm);
  EXPECT_NEAR(dec.at<float>(2, 2), 123.5, 1e-4);
  EXPECT_EQ(depth_range(cv::Mat(3, 3, CV_32FC1, cv::Scalar(kInf))).finite, 0);
}

}  // namespace
}  // namespace omma::io
