// CLI tests for `omma calibrate`, `omma rig-diff` and `omma pto` (calibration, thesis §3.6).
// Frames come from the small far-field renderer of src/omma/testing/test_scenes.h, and real
// photographs from OpenCV's samples (testing/real_data.h).
#include <fstream>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "omma/core/frames.h"
#include "omma/core/rig.h"
#include "omma/sim/perturb.h"
#include "omma/testing/real_data.h"
#include "omma/testing/real_stereo.h"
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

// ---- A real stereo rig (OpenCV's samples left/right01..14, testing/real_data.h), pooled shots ----

// `omma calibrate` with pooled shots (auto: the board moves, the shots differ) and estimated
// positions on frames folders made from 5 real pairs (1, 3, 5, 7, 9), focal lengths and principal
// points held (a static pair does not determine them: calibrate.h stereo_calibration_options).
TEST(CalibCli, RealStereoPooledShots) {
  if (!fs::exists(testing::opencv_samples_dir() / "left01.jpg")) GTEST_SKIP() << "opencv-doc not installed";
  // The pairs and their chessboard truth, and the start a user would write: focal 3 % long,
  // principal point at the centre, no distortion, the right camera's rotation and baseline direction
  // 5 deg off about (1, 0, 1) (testing/real_stereo.h: x_r = R x_l + T, dome frame = the left
  // camera's OpenCV frame).
  const testing::StereoPairs rs = testing::load_stereo_pairs(testing::opencv_samples_dir());
  const testing::StereoTruth truth = testing::stereo_chessboard_truth(rs);
  const fs::path dir = temp_dir("stereo");
  testing::StereoStartOptions so;
  so.axis = Vec3(1, 0, 1);
  so.baseline_axis = Vec3(1, 0, 1).normalized();  // this test's start to the last bit (unit axis in b x a)
  so.name = "stereo-start";
  const Rig start = testing::stereo_start_rig(truth, so);
  save_rig(start, dir / "rig.json");
  std::string frames;
  for (size_t s = 0; s < rs.ids.size(); ++s) {
    if (rs.ids[s] > 9 || rs.ids[s] % 2 == 0) continue;
    const fs::path shot = dir / fmt::format("shot_{:02d}", rs.ids[s]);
    fs::create_directories(shot);
    cv::imwrite((shot / "cam_00.png").string(), rs.left[s]);
    cv::imwrite((shot / "cam_01.png").string(), rs.right[s]);
    frames += " --frames " + shot.string();
  }
  const std::string common = " --rig " + (dir / "rig.json").string() +
                             " --position estimate --focal fixed --center fixed --radial-terms 2 --scene near"
                             " --ransac-px 8 --self-ratio 0.7 --max-iterations 200 --threads 1 --json";
  const RunResult r = run_omma("calibrate" + frames + common + " --out " + (dir / "cal.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = r.json();
  EXPECT_EQ(j["shots"], 5);
  EXPECT_EQ(j["shot_mode"], "pool");
  EXPECT_EQ(j["scene"], "near");
  EXPECT_LT(j["rms_px"].get<double>(), 0.6);
  EXPECT_GT(j["tracks"].get<int>(), 500);
  const Rig cal = load_rig(dir / "cal.json");
  const testing::StereoErrors err0 = testing::stereo_errors(start, truth);
  const testing::StereoErrors err = testing::stereo_errors(cal, truth);
  const double rot0 = err0.relative_rotation_deg, base0 = err0.baseline_direction_deg;
  const double rot = err.relative_rotation_deg, base = err.baseline_direction_deg;
  std::printf(
      "start: rotation %.3f deg, baseline %.3f deg; pooled: rotation %.3f deg, baseline %.3f deg, k1 %.3f / "
      "%.3f\n",
      rot0, base0, rot, base, cal.cameras[0].in.k[0], cal.cameras[1].in.k[0]);
  EXPECT_GT(rot0, 4.9);
  EXPECT_LT(rot, 1.8);   // measured 1.36 / 1.46 deg (stereo_real_test.cc: 1.29-1.36 over subsets)
  EXPECT_LT(base, 2.2);  // measured 1.69 deg (0.33-1.69 over subsets)
  EXPECT_LT(cal.cameras[0].in.k[0], -0.15);

  // The cameras see different scenes: a clear error that names them and their matches.
  const fs::path bad = dir / "bad";
  fs::create_directories(bad);
  cv::imwrite((bad / "cam_00.png").string(), rs.left[0]);
  cv::Mat other = cv::imread((testing::opencv_samples_dir() / "aloeL.jpg").string());
  cv::resize(other, other, {640, 480});
  cv::imwrite((bad / "cam_01.png").string(), other);
  const RunResult e =
      run_omma("calibrate --frames " + bad.string() + common + " --out " + (dir / "bad.json").string());
  expect_error(e, "cameras 0 and 1:", "different scenes");
  EXPECT_TRUE(has(e.err, "camera 0:") && has(e.err, "camera 1:")) << e.err;
  EXPECT_FALSE(fs::exists(dir / "bad.json"));
}

// A pair of photographs nobody measured the poses of (leuven, with its camera matrix from
// essential_mat_data.txt): `omma rig new` with sizes and the focal length, `omma calibrate
// --initial-pose` orients the cameras from the images and calibrates the rotation; the stitch's seam
// shows it. A free lens on one narrow overlap is refused with advice, not written.
TEST(CalibCli, InitialPoseFromImagesAlone) {
  const fs::path data = testing::opencv_samples_dir();
  if (data.empty()) GTEST_SKIP() << "opencv-doc not installed";
  const fs::path dir = temp_dir("calib-initial-pose");
  fs::copy_file(data / "leuvenA.jpg", dir / "cam_00.jpg");
  fs::copy_file(data / "leuvenB.jpg", dir / "cam_01.jpg");
  const std::string cam = " --camera size=751x563,focal=651.45,653.73,center=376.78,280.61";
  const RunResult n = run_omma("rig new" + cam + cam + " --out " + (dir / "rig.json").string());
  ASSERT_EQ(n.exit_code, 0) << n.err;
  const std::string calibrate = "calibrate --rig " + (dir / "rig.json").string() + " --frames " +
                                dir.string() + " --initial-pose --ransac-px 15 --json --out ";
  const RunResult c =
      run_omma(calibrate + (dir / "cal.json").string() + " --focal fixed --center fixed --distortion fixed");
  ASSERT_EQ(c.exit_code, 0) << c.err;
  const auto j = c.json();
  EXPECT_EQ(j["scene"], "far");               // the cameras share one centre: parallax cannot be modelled
  EXPECT_GT(j["inliers"].get<int>(), 40);     // measured 71
  EXPECT_LT(j["rms_px"].get<double>(), 2.0);  // measured 1.16 px
  EXPECT_GT(j["initial_rms_px"].get<double>(), 10.0);  // the rig new start: 17.3 px
  EXPECT_EQ(j["initial_pose"]["pairs"].size(), 1u);
  const Rig cal = load_rig(dir / "cal.json");
  // The camera turned left between the shots (leuvenB looks further left): about 20 deg apart.
  const double angle =
      rad2deg(std::acos(std::clamp(cal.cameras[0].frame.t.dot(cal.cameras[1].frame.t), -1.0, 1.0)));
  EXPECT_GT(angle, 10.0);
  EXPECT_LT(angle, 40.0);
  const RunResult s = run_omma("stitch --rig " + (dir / "cal.json").string() + " --frames " + dir.string() +
                               " --method linear --size 540x540 --json --out " + (dir / "pano.png").string());
  ASSERT_EQ(s.exit_code, 0) << s.err;
  EXPECT_GT(s.json()["inter_camera_psnr_db"].get<double>(), 25.0);  // measured 29.9 dB at 1080x1080

  // Distortion free on one narrow overlap runs away (k1 = -3.75): refused with advice, no file.
  const RunResult bad = run_omma(calibrate + (dir / "bad.json").string() + " --distortion per-camera");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_TRUE(has(bad.err, "not a lens") && has(bad.err, "--distortion fixed")) << bad.err;
  EXPECT_FALSE(fs::exists(dir / "bad.json"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace omma::test
