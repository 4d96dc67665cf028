// Calibration accuracy on synthetic frames (thesis §3.6): a perturbed 24-camera dome, frames
// rendered with the TRUE rig, calibrated from the NOMINAL rig, compared with the truth.
#include "omma/calib/calibrate.h"

#include <gtest/gtest.h>

#include "omma/calib/rig_diff.h"
#include "omma/calib/test_support.h"

namespace omma::calib {
namespace {

const PanoGrid kGrid{Projection::kEquirect, 720, 180};

struct Outcome {
  CalibrationResult result;
  RigDiff before, after;
  double psnr_true = 0, psnr_calibrated = 0, psnr_nominal = 0;
};

Outcome run_far_field(const std::string& photo) {
  const cv::Mat scene = testing::load_scene(std::string(OMMA_DATA_DIR) + "/" + photo);
  EXPECT_FALSE(scene.empty());
  const Rig nominal = testing::test_dome();
  const Rig truth = testing::perturb(nominal, {});
  const auto frames = testing::render_frames(truth, scene);
  Outcome o;
  o.result = calibrate_rig(nominal, frames);
  o.before = diff_rigs(nominal, truth, /*align=*/true);
  // Far field: the global rotation is not observable (gauge); compare after removing it.
  o.after = diff_rigs(o.result.rig, truth, /*align=*/true);
  const Rig aligned = rotate_rig(o.result.rig, o.after.alignment);
  const cv::Mat truth_pano = testing::render_truth(scene, kGrid);
  cv::Mat mask;
  const cv::Mat pano_true = testing::render_panorama(truth, frames, kGrid, &mask);
  o.psnr_true = testing::psnr(pano_true, truth_pano, mask);
  o.psnr_calibrated = testing::psnr(testing::render_panorama(aligned, frames, kGrid), truth_pano, mask);
  o.psnr_nominal = testing::psnr(testing::render_panorama(nominal, frames, kGrid), truth_pano, mask);
  std::printf(
      "%s: matches %d inliers %d tracks %d obs %d rejected %d rms %.3f px (nominal %.3f)\n"
      "  orientation err median %.4f max %.4f deg (nominal %.3f), focal err median %.5f max %.5f "
      "(nominal %.4f), centre err median %.3f max %.3f px (nominal %.3f)\n"
      "  PSNR true rig %.2f dB, calibrated %.2f dB, nominal %.2f dB\n",
      photo.c_str(), o.result.matches, o.result.inliers, o.result.tracks, o.result.observations,
      o.result.rejected, o.result.rms_px, o.result.initial_rms_px, o.after.orientation_error_deg.median,
      o.after.orientation_error_deg.max, o.before.orientation_error_deg.median, o.after.focal_error_rel.median,
      o.after.focal_error_rel.max, o.before.focal_error_rel.median, o.after.center_error_px.median,
      o.after.center_error_px.max, o.before.center_error_px.median, o.psnr_true, o.psnr_calibrated,
      o.psnr_nominal);
  return o;
}

TEST(Calibrate, FarFieldLouvreMeetsAccuracyTargets) {
  const Outcome o = run_far_field("louvre.jpg");
  EXPECT_EQ(o.result.scene, SceneModel::kFar);
  EXPECT_TRUE(o.result.uncalibrated_ids.empty());
  EXPECT_LT(o.after.orientation_error_deg.median, 0.1);
  EXPECT_LT(o.after.focal_error_rel.median, 0.005);
  EXPECT_LT(o.result.rms_px, 0.5);
  EXPECT_GT(o.psnr_calibrated, o.psnr_true - 0.5);
  EXPECT_GT(o.psnr_true, o.psnr_nominal + 1.0);  // the perturbation matters
}

TEST(Calibrate, TexturelessFramesThrow) {
  const Rig nominal = testing::test_dome();
  std::vector<cv::Mat> frames(nominal.cameras.size(), cv::Mat(250, 250, CV_8UC3, cv::Scalar(90, 90, 90)));
  EXPECT_THROW(calibrate_rig(nominal, frames), std::runtime_error);
}

TEST(Calibrate, FramesMustMatchTheRig) {
  const Rig nominal = testing::test_dome();
  std::vector<cv::Mat> frames(3, cv::Mat(250, 250, CV_8UC3, cv::Scalar(0)));
  EXPECT_THROW(calibrate_rig(nominal, frames), std::invalid_argument);
}

TEST(RigDiff, IdenticalRigsAndKnownRotation) {
  const Rig a = testing::test_dome();
  const RigDiff same = diff_rigs(a, a);
  EXPECT_NEAR(same.orientation_error_deg.max, 0, 1e-6);
  Rig b = a;
  b.cameras[3].in.fu *= 1.02;
  b.cameras[3].in.cu += 3;
  b.cameras[3].in.cv += 4;
  const Mat3 r = Eigen::AngleAxisd(deg2rad(1.5), Vec3(0, 0, 1)).toRotationMatrix();
  const Mat3 m = r * b.cameras[5].frame.dome_to_camera();
  b.cameras[5].frame = {m.row(0).transpose(), m.row(1).transpose(), m.row(2).transpose()};
  const RigDiff d = diff_rigs(b, a);
  EXPECT_NEAR(d.orientation_error_deg.max, 1.5, 1e-6);
  EXPECT_NEAR(d.focal_error_rel.max, 0.02, 1e-9);
  EXPECT_NEAR(d.center_error_px.max, 5, 1e-9);
  // A globally rotated rig differs by the rotation angle, and by ~0 after alignment.
  const Rig g = rotate_rig(a, Eigen::AngleAxisd(deg2rad(2), Vec3(1, 1, 0).normalized()).toRotationMatrix());
  EXPECT_NEAR(diff_rigs(g, a).orientation_error_deg.median, 2, 1e-6);
  EXPECT_LT(diff_rigs(g, a, true).orientation_error_deg.max, 1e-6);
}

}  // namespace
}  // namespace omma::calib
namespace omma::calib {
TEST(CalibrateDebug, DumpFrames) {
  const char* photo = getenv("PHOTO") ? getenv("PHOTO") : "louvre.jpg";
  const cv::Mat scene = testing::load_scene(std::string(OMMA_DATA_DIR) + "/" + photo);
  const Rig nominal = testing::test_dome();
  const Rig truth = testing::perturb(nominal, {});
  const auto frames = testing::render_frames(truth, scene);
  for (size_t i = 0; i < frames.size(); ++i) cv::imwrite("/tmp/calib_dbg/cam_" + std::to_string(i) + ".png", frames[i]);
  CalibrationOptions copt;
  if (getenv("UP")) copt.features.upsample = atoi(getenv("UP"));
  if (getenv("CLAHE")) copt.features.clahe_clip = atof(getenv("CLAHE"));
  if (getenv("NF")) copt.features.max_features = atoi(getenv("NF"));
  if (getenv("IT")) copt.max_iterations = atoi(getenv("IT"));
  const auto res = calibrate_rig(nominal, frames, copt);
  const RigDiff d = diff_rigs(res.rig, truth, true);
  std::printf("orient median %.4f focal median %.5f center median %.3f\n", d.orientation_error_deg.median, d.focal_error_rel.median, d.center_error_px.median);
  for (size_t i = 0; i < frames.size(); ++i) {
    const auto& a = res.rig.cameras[i]; const auto& b = truth.cameras[i];
    std::printf("cam %zu obs %d rms %.3f orient %.3f f %.2f/%.2f c %.2f %.2f / %.2f %.2f k1 %.4f/%.4f\n", i, res.per_camera[i].matches, res.per_camera[i].rms_px,
      d.per_camera_orientation_deg[i], a.in.fu, b.in.fu, a.in.cu, a.in.cv, b.in.cu, b.in.cv, a.in.k[0], b.in.k[0]);
  }
  Rig aligned = rotate_rig(res.rig, d.alignment);
  const cv::Mat truth_pano = testing::render_truth(scene, kGrid);
  cv::Mat mask;
  const cv::Mat pano_true = testing::render_panorama(truth, frames, kGrid, &mask);
  std::printf("psnr true %.2f calibrated %.2f\n", testing::psnr(pano_true, truth_pano, mask), testing::psnr(testing::render_panorama(aligned, frames, kGrid), truth_pano, mask));
  for (int c : res.uncalibrated_ids) aligned.cameras[c] = truth.cameras[c];
  std::printf("psnr with uncalibrated replaced by truth %.2f\n", testing::psnr(testing::render_panorama(aligned, frames, kGrid), truth_pano, mask));
  cv::imwrite("/tmp/calib_dbg/pano_true.png", pano_true);
  cv::imwrite("/tmp/calib_dbg/pano_cal.png", testing::render_panorama(aligned, frames, kGrid));
  cv::imwrite("/tmp/calib_dbg/pano_truth.png", truth_pano);
}
}
