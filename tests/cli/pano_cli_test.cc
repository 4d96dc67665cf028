// CLI tests for `omma stitch` and `omma eval` on a rendered far-field scene (15-camera test rig).
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "omma/testing/test_scenes.h"
#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {
namespace fs = std::filesystem;

std::string stitch_args(const fs::path& d, const std::string& method, const fs::path& out,
                        const std::string& size = "128x128") {
  return "stitch --rig " + (d / "rig.json").string() + " --frames " + d.string() + " --method " + method +
         " --projection vr180 --size " + size + " --out " + out.string();
}

TEST(PanoCli, StitchAndEvalEveryMethod) {
  const fs::path d = louvre_frames_folder("stitch");
  for (const std::string m : {"nn", "linear", "gaussian", "mrf", "mrf-spherical", "sad"}) {
    const fs::path out = d / ("pano_" + m + ".png");
    const RunResult r = run_omma(stitch_args(d, m, out) + " --single-camera " + (d / "single.png").string() +
                                 " --boundary " + (d / "b.png").string() + " --json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto j = r.json();
    EXPECT_EQ(j.at("method"), m);
    EXPECT_EQ(j.at("width"), 128);
    EXPECT_EQ(j.at("height"), 128);
    EXPECT_GE(j.at("ms").get<double>(), 0.0);
    // Far field, no noise: the cameras agree up to resampling (measured 43.3 dB on this scene).
    EXPECT_GT(j.at("inter_camera_psnr_db").get<double>(), 41.0);
    const cv::Mat pano = cv::imread(out.string());
    ASSERT_EQ(pano.cols, 128);
    ASSERT_EQ(pano.rows, 128);
    EXPECT_EQ(cv::imread((d / "b_overlay.png").string()).cols, 128);

    const RunResult e = run_omma("eval --pano " + out.string() + " --truth " + (d / "truth.png").string() +
                                 " --mask " + (d / "single.png").string() + " --json");
    ASSERT_EQ(e.exit_code, 0) << e.err;
    const auto ej = e.json();
    // Measured 35.1 (nn) .. 35.8 (linear) dB, SSIM 0.980-0.983, seam 35.6-36.7 dB (64 px cameras
    // resampling a 360x180 photo, 8-bit files); thresholds ~1 dB below the worst method.
    EXPECT_GT(ej.at("psnr_db").get<double>(), 34.0) << m;
    EXPECT_GT(ej.at("ssim").get<double>(), 0.97) << m;
    EXPECT_GT(ej.at("seam_psnr_db").get<double>(), 34.5) << m;
    // The seam band from the rig is the same as the one from the single-camera map.
    const RunResult e2 = run_omma("eval --pano " + out.string() + " --truth " + (d / "truth.png").string() +
                                  " --rig " + (d / "rig.json").string() + " --projection vr180 --json");
    ASSERT_EQ(e2.exit_code, 0) << e2.err;
    EXPECT_NEAR(e2.json().at("seam_psnr_db").get<double>(), ej.at("seam_psnr_db").get<double>(), 1e-9);
  }
  const RunResult plain = run_omma("eval --pano " + (d / "pano_nn.png").string() + " --truth " +
                                   (d / "truth.png").string() + " --json");
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  EXPECT_TRUE(plain.json().at("seam_psnr_db").is_null());
  fs::remove_all(d);
}

TEST(PanoCli, StitchRejectsBadInput) {
  const fs::path d = louvre_frames_folder("badstitch");
  const fs::path out = d / "out.png";
  auto expect_fail = [&](const std::string& args, const std::string& needle) {
    const RunResult r = run_omma(args);
    EXPECT_EQ(r.exit_code, 1) << args;
    EXPECT_NE(r.err.find(needle), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out)) << args;
  };
  expect_fail(stitch_args(d, "bilateral", out), "unknown method");
  expect_fail(stitch_args(d, "nn", out, "0x12"), "size");
  expect_fail(stitch_args(d, "nn", out, "big"), "size");
  // A missing frame.
  fs::rename(d / "cam_03.png", d / "saved.png");
  expect_fail(stitch_args(d, "nn", out), "cam_03.png");
  fs::rename(d / "saved.png", d / "cam_03.png");
  // A frame of the wrong size.
  fs::copy_file(d / "cam_02.png", d / "saved.png");
  cv::imwrite((d / "cam_02.png").string(), cv::Mat(10, 12, CV_8UC3, cv::Scalar::all(9)));
  expect_fail(stitch_args(d, "nn", out), "cam_02.png");
  fs::copy_file(d / "saved.png", d / "cam_02.png", fs::copy_options::overwrite_existing);
  // An unreadable image.
  std::ofstream(d / "cam_05.png") << "not a png";
  expect_fail(stitch_args(d, "nn", out), "cam_05.png");
  // An empty rig.
  std::ofstream(d / "empty.json")
      << R"({"format": "omma-rig", "version": 1, "dome": {"radius_mm": 5}, "cameras": []})";
  expect_fail(
      "stitch --rig " + (d / "empty.json").string() + " --frames " + d.string() + " --out " + out.string(),
      "no cameras");
  fs::remove_all(d);
}

TEST(PanoCli, EvalRejectsBadInput) {
  const fs::path d = temp_dir("badeval");
  cv::imwrite((d / "a.png").string(), cv::Mat(20, 30, CV_8UC3, cv::Scalar::all(100)));
  cv::imwrite((d / "b.png").string(), cv::Mat(20, 31, CV_8UC3, cv::Scalar::all(100)));
  RunResult r = run_omma("eval --pano " + (d / "a.png").string() + " --truth " + (d / "b.png").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("30x20"), std::string::npos) << r.err;
  r = run_omma("eval --pano " + (d / "a.png").string() + " --truth " + (d / "none.png").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("none.png"), std::string::npos) << r.err;
  // Same image: PSNR is infinite (null in JSON), SSIM 1.
  r = run_omma("eval --pano " + (d / "a.png").string() + " --truth " + (d / "a.png").string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.json().at("psnr_db").is_null());
  EXPECT_NEAR(r.json().at("ssim").get<double>(), 1.0, 1e-6);
  fs::remove_all(d);
}

}  // namespace
}  // namespace omma::test
