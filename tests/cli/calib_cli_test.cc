// CLI tests for `omma calibrate`, `omma rig-diff` and `omma pto` (calibration, thesis §3.6).
// Frames come from the small far-field renderer of src/omma/testing/test_scenes.h.
#include <fstream>

#include <gtest/gtest.h>

#include "omma/core/frames.h"
#include "omma/sim/perturb.h"
#include "omma/testing/test_scenes.h"
#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {
namespace fs = std::filesystem;

// The thesis prototype rendered by the simulator with assumed manufacturing errors:
// DIR/sim/{cam_XX.png, rig.json (nominal), rig_true.json (perturbed)}.
fs::path make_far_field_case(const std::string& photo) {
  const fs::path dir = temp_dir("calib");
  const RunResult d =
      run_omma("design --method max-volume --cam-size 1x1x2 --out " + (dir / "proto.json").string());
  EXPECT_EQ(d.exit_code, 0) << d.err;
  const RunResult s =
      run_omma("simulate --rig " + (dir / "proto.json").string() + " --scene photo:" + data_dir() + "/" +
               photo + " --out " + (dir / "sim").string() +
               " --perturb orient=2,focal=0.03,center=5,k1=0.05 --projection equirect"
               " --truth-size 360x90 --supersample 2 --json");
  EXPECT_EQ(s.exit_code, 0) << s.err;
  return dir;
}

TEST(CalibCli, CalibrateThenRigDiffMeetsTargets) {
  const fs::path dir = make_far_field_case("lake.jpg");
  const RunResult r = run_omma("calibrate --rig " + (dir / "sim/rig.json").string() + " --frames " +
                               (dir / "sim").string() + " --out " + (dir / "cal.json").string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = r.json();
  EXPECT_EQ(j["scene"], "far");
  EXPECT_EQ(j["cameras"], 24);
  EXPECT_GT(j["matches"].get<int>(), 1000);
  EXPECT_GT(j["inliers"].get<int>(), 1000);
  EXPECT_LE(j["inliers"].get<int>(), j["matches"].get<int>());
  EXPECT_LT(j["rms_px"].get<double>(), 0.5);
  ASSERT_EQ(j["per_camera"].size(), 24u);
  for (const auto& c : j["per_camera"]) {
    EXPECT_GT(c["matches"].get<int>(), 30) << c.dump();
    EXPECT_LT(c["rms_px"].get<double>(), 0.6) << c.dump();
  }
  EXPECT_TRUE(fs::exists(dir / "cal.json"));
  const RunResult d = run_omma("rig-diff " + (dir / "cal.json").string() + " " +
                               (dir / "sim/rig_true.json").string() + " --align --json");
  ASSERT_EQ(d.exit_code, 0) << d.err;
  const auto dj = d.json();
  std::printf(
      "calibrated vs true: orientation median %.4f deg max %.4f, focal median %.5f, centre median %.3f px\n",
      dj["orientation_error_deg"]["median"].get<double>(), dj["orientation_error_deg"]["max"].get<double>(),
      dj["focal_error_rel"]["median"].get<double>(), dj["center_error_px"]["median"].get<double>());
  EXPECT_LT(dj["orientation_error_deg"]["median"].get<double>(), 0.1);
  EXPECT_LT(dj["focal_error_rel"]["median"].get<double>(), 0.005);
  const RunResult n = run_omma("rig-diff " + (dir / "sim/rig.json").string() + " " +
                               (dir / "sim/rig_true.json").string() + " --align --json");
  ASSERT_EQ(n.exit_code, 0) << n.err;
  EXPECT_GT(n.json()["orientation_error_deg"]["median"].get<double>(), 0.5);  // the nominal rig is off
  // The calibrated rig feeds the stitcher unchanged: nn panorama vs the truth.
  auto pano_psnr = [&](const std::string& rig) {
    const RunResult st =
        run_omma("stitch --rig " + rig + " --frames " + (dir / "sim").string() +
                 " --method nn --projection equirect --size 360x90 --out " + (dir / "p.png").string());
    EXPECT_EQ(st.exit_code, 0) << st.err;
    const RunResult ev = run_omma("eval --pano " + (dir / "p.png").string() + " --truth " +
                                  (dir / "sim/truth.png").string() + " --json");
    EXPECT_EQ(ev.exit_code, 0) << ev.err;
    return ev.json()["psnr_db"].get<double>();
  };
  const double psnr_cal = pano_psnr((dir / "cal.json").string());
  const double psnr_nominal = pano_psnr((dir / "sim/rig.json").string());
  const double psnr_true = pano_psnr((dir / "sim/rig_true.json").string());
  std::printf("nn panorama PSNR vs truth: calibrated %.2f dB, nominal %.2f dB, true rig %.2f dB\n", psnr_cal,
              psnr_nominal, psnr_true);
  EXPECT_GT(psnr_cal, psnr_nominal + 5);  // (the rest of the gap to the true rig is the far-field gauge)
  fs::remove_all(dir);
}

TEST(CalibCli, TexturelessFramesFailWithoutOutput) {
  const fs::path dir = temp_dir("calib-flat");
  const Rig nominal = testing::test_rig_24();
  save_rig(nominal, dir / "rig.json");
  fs::create_directories(dir / "frames");
  for (const auto& c : nominal.cameras)
    cv::imwrite((dir / "frames" / frame_filename(c.id)).string(),
                cv::Mat(250, 250, CV_8UC3, cv::Scalar(80, 90, 100)));
  const RunResult r = run_omma("calibrate --rig " + (dir / "rig.json").string() + " --frames " +
                               (dir / "frames").string() + " --out " + (dir / "cal.json").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("textureless"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "cal.json"));
  // Rig and frames that do not match: a missing camera frame.
  fs::remove(dir / "frames" / frame_filename(5));
  const RunResult m = run_omma("calibrate --rig " + (dir / "rig.json").string() + " --frames " +
                               (dir / "frames").string() + " --out " + (dir / "cal.json").string());
  EXPECT_EQ(m.exit_code, 1);
  EXPECT_NE(m.err.find("cam_05.png"), std::string::npos) << m.err;
  EXPECT_FALSE(fs::exists(dir / "cal.json"));
  fs::remove_all(dir);
}

TEST(CalibCli, PtoExportImportRoundTripAndBadInput) {
  const fs::path dir = temp_dir("calib-pto");
  const Rig truth = sim::perturb_rig_rms(testing::test_rig_24(), testing::kCalibrationErrors, 3);
  save_rig(truth, dir / "rig.json");
  const RunResult e =
      run_omma("pto export " + (dir / "rig.json").string() + " " + (dir / "rig.pto").string() + " --json");
  ASSERT_EQ(e.exit_code, 0) << e.err;
  EXPECT_LT(e.json()["lens_fit_max_px"].get<double>(), 1e-6);
  const RunResult i =
      run_omma("pto import " + (dir / "rig.pto").string() + " " + (dir / "back.json").string() + " --json");
  ASSERT_EQ(i.exit_code, 0) << i.err;
  EXPECT_EQ(i.json()["cameras"], 24);
  const RunResult d =
      run_omma("rig-diff " + (dir / "back.json").string() + " " + (dir / "rig.json").string() + " --json");
  ASSERT_EQ(d.exit_code, 0) << d.err;
  EXPECT_LT(d.json()["orientation_error_deg"]["max"].get<double>(), 1e-6);
  EXPECT_LT(d.json()["focal_error_rel"]["max"].get<double>(), 1e-9);
  EXPECT_LT(d.json()["center_error_px"]["max"].get<double>(), 1e-9);
  // Unsupported lens type.
  std::ofstream(dir / "fish.pto") << "p f2 w100 h50 v360\ni w250 h250 f2 v180 y0 p0 r0 n\"cam_00.png\"\n";
  const RunResult f =
      run_omma("pto import " + (dir / "fish.pto").string() + " " + (dir / "fish.json").string());
  EXPECT_EQ(f.exit_code, 1);
  EXPECT_NE(f.err.find("lens type f2"), std::string::npos) << f.err;
  EXPECT_FALSE(fs::exists(dir / "fish.json"));
  // Missing images and no size: nothing can be imported.
  std::ofstream(dir / "nosize.pto") << "i f0 v60 y0 p0 r0 n\"missing.png\"\n";
  const RunResult s =
      run_omma("pto import " + (dir / "nosize.pto").string() + " " + (dir / "nosize.json").string());
  EXPECT_EQ(s.exit_code, 1);
  EXPECT_NE(s.err.find("missing"), std::string::npos) << s.err;
  EXPECT_FALSE(fs::exists(dir / "nosize.json"));
  // rig-diff of rigs with different cameras.
  Rig small = truth;
  small.cameras.resize(3);
  save_rig(small, dir / "small.json");
  const RunResult x =
      run_omma("rig-diff " + (dir / "small.json").string() + " " + (dir / "rig.json").string());
  EXPECT_EQ(x.exit_code, 1);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace omma::test
