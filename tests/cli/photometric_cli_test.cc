// Photometric calibration and correction from the command line:
// `omma calibrate --photometric` on a far-field scene, then `omma stitch` (8-bit and --raw frames)
// with the model applied by default and `--no-photometric`, against ideal-photometry frames; and
// the bad input of shots, flat fields and photometric rig values.
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "omma/core/rig.h"
#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {
namespace fs = std::filesystem;

TEST(PhotometricCli, CalibratedPhotometryBringsTheStitchToIdealFrames) {
  const fs::path d = temp_dir("photometric");
  const std::string scene =
      " --scene photo:" + data_dir() + "/lake.jpg --projection vr180 --truth-size 256x256 ";
  RunResult r = run_omma("simulate --raw --out " + (d / "real").string() + scene);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_omma("simulate --no-truth --vignetting 0 --color-gain 0 --out " + (d / "ideal").string() + scene);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string rig = (d / "real" / "rig.json").string(), ph = (d / "rig_ph.json").string();
  r = run_omma("calibrate --rig " + rig + " --frames " + (d / "real").string() + " --out " + ph +
               " --no-geometric --photometric --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = r.json();
  EXPECT_EQ(j.at("photometric").at("source"), "overlaps");
  EXPECT_LT(j.at("photometric").at("rms_log").get<double>(),
            0.5 * j.at("photometric").at("initial_rms_log").get<double>());
  ASSERT_TRUE(load_rig(ph).cameras[5].photometric.has_value());
  auto stitch = [&](const std::string& rig_path, const std::string& frames, const std::string& out,
                    const std::string& extra = "") {
    const RunResult s = run_omma("stitch --rig " + rig_path + " --frames " + frames +
                                 " --method linear --projection vr180 --size 256x256 --json --out " +
                                 (d / out).string() + extra);
    EXPECT_EQ(s.exit_code, 0) << s.err;
    return s.exit_code == 0 ? s.json() : nlohmann::json{};
  };
  EXPECT_TRUE(stitch(ph, (d / "real").string(), "estimated.png").at("photometric").get<bool>());
  EXPECT_FALSE(stitch(ph, (d / "real").string(), "uncorrected.png", " --no-photometric")
                   .at("photometric")
                   .get<bool>());
  stitch(rig, (d / "ideal").string(), "ideal.png");
  stitch(ph, (d / "real").string(), "raw.png", " --raw --demosaic cc");
  const fs::path truth = d / "real" / "truth.png";
  const double e = eval_psnr(d / "estimated.png", truth), u = eval_psnr(d / "uncorrected.png", truth);
  const double i = eval_psnr(d / "ideal.png", truth), raw = eval_psnr(d / "raw.png", truth);
  std::printf(
      "linear, vr180 256x256: uncorrected %.2f dB, estimated photometry %.2f dB (raw + ISP %.2f dB), ideal "
      "photometry %.2f dB\n",
      u, e, raw, i);
  EXPECT_GT(e, u + 1.0);    // the correction matters ...
  EXPECT_GT(e, i - 1.0);    // ... and brings the panorama within 1 dB of ideal photometry
  EXPECT_GT(raw, e - 2.0);  // the raw path with the model as flat gain: close (demosaicing costs a little)
  fs::remove_all(d);
}

TEST(PhotometricCli, BadShotsFlatFieldsAndPhotometricValues) {
  const fs::path d = temp_dir("photometric_bad");
  RunResult r = run_omma("simulate --scene flat --shots 2 --no-truth --out " + (d / "flat").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_TRUE(fs::exists(d / "flat" / "shot_01" / "cam_23.png"));
  const std::string rig = (d / "flat" / "shot_00" / "rig.json").string();
  // A flat field from the shots folder works (both shots averaged) ...
  r = run_omma("calibrate --rig " + rig + " --frames " + (d / "flat" / "shot_00").string() + " --flat " +
               (d / "flat").string() + " --no-geometric --out " + (d / "ph.json").string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.json().at("photometric").at("source"), "flat-field");
  // ... but not with a frame of the wrong size (named), nor with a camera missing in one shot.
  cv::imwrite((d / "flat" / "shot_01" / "cam_03.png").string(),
              cv::Mat(100, 250, CV_8UC3, cv::Scalar(90, 90, 90)));
  r = run_omma("calibrate --rig " + rig + " --frames " + (d / "flat" / "shot_00").string() + " --flat " +
               (d / "flat").string() + " --no-geometric --out " + (d / "bad.json").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("omma: error:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("cam_03.png"), std::string::npos) << r.err;
  fs::remove(d / "flat" / "shot_01" / "cam_03.png");
  r = run_omma("calibrate --rig " + rig + " --frames " + (d / "flat").string() + " --out " +
               (d / "bad.json").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("cam_03.png"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(d / "bad.json"));
  // Photometric calibration from the overlaps of a flat, featureless scene works (every sample
  // agrees); of black frames it fails: too little overlap.
  r = run_omma("simulate --scene flat:0.0001 --no-truth --out " + (d / "black").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_omma("calibrate --rig " + rig + " --frames " + (d / "black").string() +
               " --photometric --no-geometric --out " + (d / "bad.json").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("too little overlap"), std::string::npos) << r.err;
  // A rig with a non-positive gain or a falloff that reaches zero: a clear error naming the camera.
  for (int which = 0; which < 2; ++which) {
    std::ifstream in(d / "ph.json");
    nlohmann::json j = nlohmann::json::parse(in);
    if (which == 0)
      j["cameras"][4]["photometric"]["gains_bgr"] = {1, 0, 1};
    else
      j["cameras"][4]["photometric"]["vignetting"] = {-1.5, 0, 0};
    std::ofstream(d / "badrig.json") << j.dump(1);
    r = run_omma("stitch --rig " + (d / "badrig.json").string() + " --frames " +
                 (d / "flat" / "shot_00").string() + " --size 64x64 --out " + (d / "x.png").string());
    EXPECT_EQ(r.exit_code, 1) << which;
    EXPECT_NE(r.err.find("camera 4"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(d / "x.png"));
  }
  r = run_omma("simulate --scene tube --shots 0 --out " + (d / "t").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--shots"), std::string::npos) << r.err;
  fs::remove_all(d);
}

}  // namespace
}  // namespace omma::test
