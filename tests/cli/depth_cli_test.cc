// CLI tests for the projection surface (pano/surface.h): `omma stitch --depth ... --depth-out`, the
// simulator's true depth, `omma eval --depth`, and bad input.
#include <cmath>
#include <filesystem>
#include <limits>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "omma/core/conventions.h"
#include "omma/testing/test_scenes.h"
#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {
namespace fs = std::filesystem;

std::string stitch(const fs::path& d, const std::string& depth, const fs::path& out) {
  return "stitch --rig " + (d / "rig.json").string() + " --frames " + d.string() +
         " --method mrf --projection vr180 --size 128x128 --depth '" + depth + "' --out " + out.string();
}

TEST(DepthCli, DepthModesAndDepthOut) {
  const fs::path d = louvre_frames_folder("depth");
  // estimate: a far-field scene lies at infinity, and stitching through the estimate changes little.
  const RunResult r = run_omma(stitch(d, "estimate", d / "p_est.png") + " --depth-out " +
                               (d / "depth.png").string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = r.json();
  EXPECT_EQ(j.at("depth").at("mode"), "estimate");
  const cv::Mat data = cv::imread((d / "depth.tiff").string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(data.type(), CV_32FC1);
  ASSERT_EQ(data.size(), cv::Size(128, 128));
  double lo = 0;
  cv::minMaxLoc(data, &lo);
  EXPECT_GT(lo, 100.0);  // nothing near in a photo at infinity
  const cv::Mat picture = cv::imread((d / "depth.png").string());
  EXPECT_EQ(picture.cols, 360);  // colour map widened for the legend
  EXPECT_GT(picture.rows, 128);  // legend strip
  // truth:FILE reads the data back; sphere:R; inf.
  for (const std::string& mode :
       {"truth:" + (d / "depth.tiff").string(), std::string("sphere:1000"), std::string("inf")}) {
    const RunResult s = run_omma(stitch(d, mode, d / "p.png") + " --json");
    ASSERT_EQ(s.exit_code, 0) << mode << ": " << s.err;
  }
  const RunResult e = run_omma("eval --pano " + (d / "p_est.png").string() + " --truth " +
                               (d / "truth.png").string() + " --json");
  ASSERT_EQ(e.exit_code, 0) << e.err;
  EXPECT_GT(e.json().at("psnr_db").get<double>(), 33.0);  // measured 35.4 dB (inf: 35.5 dB)
}

TEST(DepthCli, BadInput) {
  const fs::path d = louvre_frames_folder("depth-bad");
  auto fails = [&](const std::string& depth, const std::string& message, const std::string& extra = "") {
    const fs::path out = d / "never.png";
    const RunResult r = run_omma(stitch(d, depth, out) + extra);
    EXPECT_EQ(r.exit_code, 1) << depth;
    EXPECT_NE(r.err.find("omma: error:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << depth << ": " << r.err;
    EXPECT_FALSE(fs::exists(out)) << depth;
    fs::remove(out);
  };
  fails("sphere:3", "inside the dome");  // the cameras sit at 5 mm
  fails("sphere:abc", "needs a radius");
  cv::imwrite((d / "small.tiff").string(), cv::Mat(10, 10, CV_32FC1, cv::Scalar(20)));
  fails("truth:" + (d / "small.tiff").string(), "is 10x10, the panorama is 128x128");
  cv::Mat neg(128, 128, CV_32FC1, cv::Scalar(20));
  neg.at<float>(5, 7) = -1;
  cv::imwrite((d / "neg.tiff").string(), neg);
  fails("truth:" + (d / "neg.tiff").string(), "must be > 0");
  fails("truth:" + (d / "missing.tiff").string(), "missing.tiff");
  fails("estimate:30,60", "excludes the scene");  // a far-field scene, swept only to 60 mm
  fails("estimate:4", "inside the dome");
  fails("estimate:20,10", "must exceed near");
  fails("estimate:8,x", "is not a number");
  fails("nearby", "must be inf, sphere:R, truth:FILE or estimate");
  fails("inf", "--depth-out names the picture", " --depth-out " + (d / "x.tiff").string());
}

// --depth-pitch: the sweep grid's pitch, an angle or the cameras' own pixel pitch (the test rig's 64 px
// cameras have fu = 51.2 px: atan(1 / 51.2) = 1.119 deg at the centre); the default stays 1.33 deg.
TEST(DepthCli, DepthPitch) {
  const fs::path d = louvre_frames_folder("depth-pitch");
  auto pitch = [&](const std::string& extra) {
    const RunResult r = run_omma(stitch(d, "estimate", d / "p.png") + extra + " --json");
    EXPECT_EQ(r.exit_code, 0) << extra << ": " << r.err;
    return r.exit_code == 0 ? r.json().at("depth").at("pitch_deg").get<double>() : -1.0;
  };
  EXPECT_NEAR(pitch(""), 1.33, 1e-9);
  EXPECT_NEAR(pitch(" --depth-pitch camera"), rad2deg(std::atan(1 / 51.2107)), 1e-3);
  EXPECT_NEAR(pitch(" --depth-pitch 2.5"), 2.5, 1e-9);
  for (const std::string& bad : {std::string(" --depth-pitch 0"), std::string(" --depth-pitch abc"),
                                 std::string(" --depth-pitch 100")}) {
    const RunResult r = run_omma(stitch(d, "estimate", d / "never.png") + bad);
    EXPECT_EQ(r.exit_code, 1) << bad;
    EXPECT_NE(r.err.find("--depth-pitch must be an angle"), std::string::npos) << r.err;
  }
  const RunResult r = run_omma(stitch(d, "inf", d / "never.png") + " --depth-pitch camera");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("applies to --depth estimate only"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(d / "never.png"));
}

// The simulator writes the true depth of every truth pixel: inside a sphere of 50 mm around the
// dome centre every direction is 50 mm away.
TEST(DepthCli, SimulatorWritesTrueDepth) {
  const fs::path d = temp_dir("depth-sim") / "sim";
  const RunResult r =
      run_omma("simulate --scene checker:50 --truth-size 64x64 --supersample 1 --out " + d.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const cv::Mat depth = cv::imread((d / "truth_depth.tiff").string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(depth.type(), CV_32FC1);
  ASSERT_EQ(depth.size(), cv::Size(64, 64));
  double lo = 0, hi = 0;
  cv::minMaxLoc(depth, &lo, &hi);
  EXPECT_NEAR(lo, 50.0, 1e-3);
  EXPECT_NEAR(hi, 50.0, 1e-3);
  const RunResult s =
      run_omma("stitch --rig " + (d / "rig.json").string() + " --frames " + d.string() +
               " --size 64x64 --depth truth:" + (d / "truth_depth.tiff").string() + " --out " +
               (d / "p.png").string() + " --depth-out " + (d / "used.png").string());
  ASSERT_EQ(s.exit_code, 0) << s.err;
  const RunResult e = run_omma(
      "eval --pano " + (d / "p.png").string() + " --truth " + (d / "truth.png").string() + " --truth-depth " +
      (d / "truth_depth.tiff").string() + " --depth " + (d / "used.tiff").string() + " --json");
  ASSERT_EQ(e.exit_code, 0) << e.err;
  EXPECT_LT(e.json().at("depth").at("median_rel").get<double>(), 1e-6);
}

}  // namespace
}  // namespace omma::test
