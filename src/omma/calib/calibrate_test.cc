// Calibration accuracy on simulated frames (thesis §3.6): the 24-camera prototype dome perturbed
// by the simulator (--perturb orient=2,focal=0.03,center=5,k1=0.05), frames rendered with the TRUE
// rig, calibrated from the NOMINAL rig, compared with the truth.
#include "omma/calib/calibrate.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "omma/calib/photometric.h"
#include "omma/calib/rig_diff.h"
#include "omma/design/prototype.h"
#include "omma/pano/quality.h"
#include "omma/pano/stitch.h"
#include "omma/sim/perturb.h"
#include "omma/sim/simulate.h"
#include "omma/testing/expect.h"
#include "omma/testing/test_scenes.h"

namespace omma::calib {
namespace {

const PanoGrid kGrid{Projection::kEquirect, 720, 180};
const char* kPerturb = "orient=2,focal=0.03,center=5,k1=0.05";  // the assumed manufacturing errors

struct Outcome {
  CalibrationSummary result;
  RigDiff before, after;
  double psnr_true = 0, psnr_calibrated = 0, psnr_nominal = 0;
};

double stitch_psnr(const Rig& rig, const std::vector<cv::Mat>& frames, const cv::Mat& truth,
                   const cv::Mat& mask) {
  pano::StitchOptions so;
  so.method = pano::Method::kNearest;
  so.grid = kGrid;
  so.progress = false;
  return pano::psnr_db(pano::stitch(rig, frames, so), truth, mask);
}

// The simulator (omma_sim) renders the thesis prototype (design) with that perturbation;
// calibrate from the nominal rig; compare with the true rig; nn panoramas against the truth.
Outcome run_simulated(const std::string& scene_spec) {
  const Rig nominal = design::thesis_prototype_rig();
  const auto scene = sim::make_scene(scene_spec);
  sim::SimulateOptions so;
  so.perturb = sim::parse_perturb(kPerturb);
  so.truth_grid = kGrid;
  so.effects.supersample = 2;
  so.progress = false;
  const sim::SimulateSummary sr = sim::simulate(nominal, *scene, so);
  std::vector<cv::Mat> frames;
  for (const auto& f : sr.frames) frames.push_back(f.image);
  Outcome o;
  CalibrationOptions opt;
  opt.threads = 1;  // deterministic: the near-field solution moves by tenths of a degree with the
                    // summation order of a multi-threaded Ceres solve
  o.result = calibrate_rig(nominal, frames, opt);
  o.before = diff_rigs(nominal, sr.true_rig, /*align=*/true);
  // Far field: the global rotation is not observable (gauge, calibrate.h); compare without it.
  o.after = diff_rigs(o.result.rig, sr.true_rig, /*align=*/true);
  const Rig aligned = rotate_rig(o.result.rig, o.after.alignment);
  pano::StitchOptions st;
  st.method = pano::Method::kNearest;
  st.grid = kGrid;
  st.progress = false;
  const cv::Mat pano_true = pano::stitch(sr.true_rig, frames, st);
  cv::Mat gray, mask;
  cv::cvtColor(pano_true, gray, cv::COLOR_BGR2GRAY);
  mask = gray > 0;  // covered region
  o.psnr_true = pano::psnr_db(pano_true, sr.truth, mask);
  o.psnr_calibrated = stitch_psnr(aligned, frames, sr.truth, mask);
  o.psnr_nominal = stitch_psnr(nominal, frames, sr.truth, mask);
  std::printf(
      "%s: matches %d inliers %d tracks %d obs %d rejected %d rms %.3f px (nominal %.3f), uncalibrated %zu\n"
      "  orientation err median %.4f max %.4f deg (nominal %.3f), focal err median %.5f max %.5f "
      "(nominal %.4f), centre err median %.3f max %.3f px (nominal %.3f), ray err median %.4f max %.4f deg "
      "(nominal %.4f)\n"
      "  nn PSNR vs truth: true rig %.2f dB, calibrated %.2f dB, nominal %.2f dB\n",
      scene_spec.c_str(), o.result.matches, o.result.inliers, o.result.tracks, o.result.observations,
      o.result.rejected, o.result.rms_px, o.result.initial_rms_px, o.result.uncalibrated_ids.size(),
      o.after.orientation_error_deg.median, o.after.orientation_error_deg.max,
      o.before.orientation_error_deg.median, o.after.focal_error_rel.median, o.after.focal_error_rel.max,
      o.before.focal_error_rel.median, o.after.center_error_px.median, o.after.center_error_px.max,
      o.before.center_error_px.median, o.after.ray_error_deg.median, o.after.ray_error_deg.max,
      o.before.ray_error_deg.median, o.psnr_true, o.psnr_calibrated, o.psnr_nominal);
  return o;
}

std::string photo(const char* name) { return std::string("photo:") + OMMA_DATA_DIR + "/" + name; }

TEST(Calibrate, FarFieldPhotoMeetsAccuracyTargets) {
  const Outcome o = run_simulated(photo("lake.jpg"));
  EXPECT_EQ(o.result.scene, SceneModel::kFar);
  EXPECT_TRUE(o.result.uncalibrated_ids.empty());
  // The accuracy targets: median orientation < 0.1 deg, focal < 0.5 %, RMS < 0.5 px, PSNR within
  // 0.5 dB of the true rig's. With the subpixel refinement (subpixel.h) measured: 0.016 deg (max
  // 0.13), 0.04 %, centre 0.08 px, RMS 0.036 px; the thresholds keep a margin of ~3x.
  EXPECT_LT(o.after.orientation_error_deg.median, 0.05);
  EXPECT_LT(o.after.focal_error_rel.median, 0.0015);
  EXPECT_LT(o.after.center_error_px.median, 0.25);
  EXPECT_LT(o.result.rms_px, 0.1);
  EXPECT_GT(o.psnr_calibrated, o.psnr_true - 0.5);
  EXPECT_GT(o.psnr_true, o.psnr_nominal + 1.0);  // the perturbation matters
}

// The Louvre at night: the pole cameras see a dark, featureless sky. They keep their nominal values
// and are named in a warning; the others are calibrated.
TEST(Calibrate, FeaturelessSkyCamerasKeepNominalValuesWithWarning) {
  const Outcome o = run_simulated(photo("louvre.jpg"));
  EXPECT_FALSE(o.result.uncalibrated_ids.empty());
  EXPECT_LE(o.result.uncalibrated_ids.size(), 6u);
  ASSERT_FALSE(o.result.warnings.empty());
  for (int id : o.result.uncalibrated_ids)
    EXPECT_NE(o.result.warnings[0].find(std::to_string(id)), std::string::npos) << o.result.warnings[0];
  EXPECT_LT(o.result.rms_px, 0.5);
  EXPECT_LT(o.after.orientation_error_deg.median, 0.5 * o.before.orientation_error_deg.median);
  EXPECT_GT(o.psnr_calibrated, o.psnr_nominal + 1.0);
}

// The colon (near field, parallax). The panorama target is met (PSNR after calibration within 0.5 dB
// of the true rig's) and the reprojection RMS too, but not the parameter targets (orientation 0.1 deg,
// focal 0.5 %):
// with a 5 mm baseline against a ~20 mm deep scene, focal length trades against depth (the mean
// focal is held by a prior, calibrate.h) and the principal point against rotation, and the
// observations of the dark, folded wall are not precise enough even after the dense, flat-fielded
// refinement (calibrate.h, "Near field"). Measured with one Ceres thread (deterministic): 0.525 deg
// (max 0.87), 1.09 %, centre 2.26 px, ray 0.34 deg, RMS 0.115 px, 7971 tracks (before the dense
// refinement: 0.63 deg, max 1.35, 1.23 %, 2.69 px, ray 0.41 deg, RMS 0.14 px; two more simulation
// seeds: 0.54 / 0.58 deg, 1.10 / 0.67 %, ray 0.40 / 0.23 deg; nominal rig: 2.03 deg, 3.1 %, 5 px,
// ray 1.85 deg). The thresholds below are what this solver truly meets, with a margin.
TEST(Calibrate, ColonNearFieldCalibration) {
  const Outcome o = run_simulated("colon");
  EXPECT_EQ(o.result.scene, SceneModel::kNear);
  EXPECT_TRUE(o.result.uncalibrated_ids.empty());
  EXPECT_GT(o.result.tracks, 4000);                 // the dense refinement's tracks
  EXPECT_LT(o.result.rms_px, 0.2);                  // target 0.5 px
  EXPECT_GT(o.psnr_calibrated, o.psnr_true - 0.5);  // the panorama target
  EXPECT_GT(o.psnr_calibrated, o.psnr_nominal + 0.5);
  EXPECT_LT(o.after.orientation_error_deg.median, 0.75);  // target 0.1 deg: not met
  EXPECT_LT(o.after.orientation_error_deg.max, 1.3);
  EXPECT_LT(o.after.focal_error_rel.median, 0.016);  // target 0.5 %: not met
  EXPECT_LT(o.after.center_error_px.median, 0.7 * o.before.center_error_px.median);
  // What the stitch sees: the rays of the calibrated cameras (rig_diff.h), a quarter of the nominal
  // rig's ray error or better.
  EXPECT_LT(o.after.ray_error_deg.median, 0.25 * o.before.ray_error_deg.median);
}

// The thesis's calibration (§3.6): several shots of the static, well-lit 35 mm calibration tube,
// averaged, flat-fielded with shots of a white target, wall points constrained to the tube
// (CalibrationOptions::tube_diameter_mm). The full figures (8 shots, three seeds: every accuracy
// target met) come from docs/results/tube_calibration.sh (docs/results/tube_calibration.md); this test keeps
// CI shorter
// (~30 s of CPU) with 2 shots, one dense round and SIFT without upsampling. Measured (seed 1):
// orientation median 0.19 deg (max 0.30), focal 0.33 % (max 0.61), centre 0.59 px, RMS 0.058 px
// (with SIFT upsampled: 0.16 / 0.33 deg at 42 s; 8 shots, full settings: 0.089 / 0.165 deg).
TEST(Calibrate, CalibrationTubeFewShots) {
  const Rig nominal = design::thesis_prototype_rig();
  sim::SimulateOptions so;
  so.perturb = sim::parse_perturb(kPerturb);
  so.truth = false;
  so.progress = false;
  so.shots = 2;
  so.effects.supersample = 2;
  auto images = [](const std::vector<sim::CameraFrame>& fs) {
    std::vector<cv::Mat> out;
    for (const auto& f : fs) out.push_back(f.image);
    return out;
  };
  const sim::SimulateSummary tube = sim::simulate(nominal, *sim::make_tube_scene(), so);
  const sim::SimulateSummary flat = sim::simulate(nominal, *sim::make_flat_scene(), so);
  const auto frames = flat_field_frames(average_frame_sets({images(tube.frames), images(tube.more_shots[0])}),
                                        {images(flat.frames), images(flat.more_shots[0])});
  CalibrationOptions opt;
  opt.scene = SceneModel::kNear;
  opt.tube_diameter_mm = 35;
  opt.dense_rounds = 1;
  opt.features.upsample = 1;  // SIFT on the frames as they are: a quarter of the work
  const CalibrationSummary r = calibrate_rig(nominal, frames, opt);
  const RigDiff d = diff_rigs(r.rig, tube.true_rig);
  std::printf(
      "tube, 2 shots: orientation median %.3f max %.3f deg, focal median %.4f max %.4f, centre median %.3f "
      "px, "
      "RMS %.3f px, %d tracks\n",
      d.orientation_error_deg.median, d.orientation_error_deg.max, d.focal_error_rel.median,
      d.focal_error_rel.max, d.center_error_px.median, r.rms_px, r.tracks);
  EXPECT_TRUE(r.uncalibrated_ids.empty());
  // Measured 0.158 deg (max 0.260), 0.32 %, 0.55 px (0.19 / 0.30 deg with the tube's tilt estimated).
  EXPECT_LT(d.orientation_error_deg.median,
            0.25);  // target 0.1 with 8 shots (met there: docs/results/tube_calibration.md)
  EXPECT_LT(d.orientation_error_deg.max, 0.45);  // target 0.3 with 8 shots
  EXPECT_LT(d.focal_error_rel.median, 0.005);
  EXPECT_LT(d.center_error_px.median, 1.0);
  EXPECT_LT(r.rms_px, 0.3);
}

// Model check without images: points on a 21 mm tube (the colon's mean radius) projected through
// the perturbed true rig by core's CameraModel::project are perfect near-field tracks. The bundle
// adjustment (CameraModel-identical residual, eq. 5.21-5.26) started from the nominal rig must give
// the true rig back exactly when no prior biases it; with 0.2 px noise (SIFT's level) the same
// geometry only determines the rig to ~0.5 deg / ~1 % / ~2 px: the colon's limit is conditioning
// (5 mm baseline against ~20 mm depth), not a model mismatch.
std::vector<std::vector<TrackObservation>> tube_tracks(const Rig& rig, int points, double noise_px,
                                                       unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uz(-40, 40), uphi(0, 2 * kPi);
  std::normal_distribution<double> g(0, 1);
  std::vector<std::vector<TrackObservation>> tracks;
  for (int k = 0; k < points; ++k) {
    const double phi = uphi(rng);
    const Vec3 p(21 * std::cos(phi), 21 * std::sin(phi), uz(rng));
    std::vector<TrackObservation> t;
    for (int i = 0; i < static_cast<int>(rig.cameras.size()); ++i) {
      const RigCamera& c = rig.cameras[i];
      const auto px = c.model().project(p - c.position_mm);
      if (!px || px->x() < 0 || px->y() < 0 || px->x() > c.in.width || px->y() > c.in.height) continue;
      t.push_back({i, *px + noise_px * Vec2(g(rng), g(rng))});
    }
    if (t.size() >= 2) tracks.push_back(std::move(t));
  }
  return tracks;
}

TEST(Calibrate, NearFieldModelRecoversTrueRigFromPerfectTracks) {
  const Rig nominal = design::thesis_prototype_rig();
  const Rig truth = sim::perturb_rig(nominal, sim::parse_perturb(kPerturb), 1);
  CalibrationOptions opt;
  opt.prior_rotation_deg = 0;  // near field: the fixed camera positions fix the gauge
  opt.prior_mean_focal = 0;
  const CalibrationSummary r =
      calibrate_from_tracks(nominal, tube_tracks(truth, 3000, 0, 3), SceneModel::kNear, opt);
  const RigDiff d = diff_rigs(r.rig, truth);
  EXPECT_LT(r.rms_px, 1e-3);
  EXPECT_LT(d.orientation_error_deg.max, 1e-3);
  EXPECT_LT(d.focal_error_rel.max, 1e-5);
  EXPECT_LT(d.center_error_px.max, 1e-2);
  // The same with SIFT-like noise: the conditioning limit (numbers in the comment above).
  const CalibrationSummary rn =
      calibrate_from_tracks(nominal, tube_tracks(truth, 3000, 0.2, 3), SceneModel::kNear, opt);
  const RigDiff dn = diff_rigs(rn.rig, truth, /*align=*/true);  // as the accuracy tests
  std::printf(
      "perfect tracks: orientation %.5f deg, focal %.6f, centre %.4f px; 0.2 px noise: %.3f deg, %.4f, %.3f "
      "px\n",
      d.orientation_error_deg.median, d.focal_error_rel.median, d.center_error_px.median,
      dn.orientation_error_deg.median, dn.focal_error_rel.median, dn.center_error_px.median);
  EXPECT_LT(dn.orientation_error_deg.median, 1.0);
  EXPECT_GT(dn.orientation_error_deg.median, 0.1);  // documents that 0.2 px noise is too much for 0.1 deg
}

TEST(Calibrate, TexturelessFramesThrow) {
  const Rig nominal = testing::test_rig_24();
  std::vector<cv::Mat> frames(nominal.cameras.size(), cv::Mat(250, 250, CV_8UC3, cv::Scalar(90, 90, 90)));
  EXPECT_THROW(calibrate_rig(nominal, frames), std::runtime_error);
}

TEST(Calibrate, FramesMustMatchTheRig) {
  const Rig nominal = testing::test_rig_24();
  std::vector<cv::Mat> frames(3, cv::Mat(250, 250, CV_8UC3, cv::Scalar(0)));
  EXPECT_THROW(calibrate_rig(nominal, frames), std::invalid_argument);
}

TEST(RigDiff, IdenticalRigsAndKnownRotation) {
  const Rig a = testing::test_rig_24();
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

using testing::refusal;

TEST(Options, FeatureOptionsRefuseBadValues) {
  FeatureOptions o;
  EXPECT_TRUE(o.IsValid());
  o.upsample = 0;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("upsample"), std::string::npos);
  EXPECT_NE(refusal([&] { detect_features(cv::Mat(64, 64, CV_8UC1, cv::Scalar(128)), o); }).find("upsample"),
            std::string::npos);
}

TEST(Options, MatchOptionsRefuseBadValues) {
  MatchOptions o;
  EXPECT_TRUE(o.IsValid());
  o.ratio = 1.5;
  EXPECT_FALSE(o.IsValid());
  const Rig rig = design::thesis_prototype_rig();
  EXPECT_NE(refusal([&] { match_pair(rig, 0, 1, {}, {}, SceneModel::kFar, o); }).find("ratio"),
            std::string::npos);
}

TEST(Options, CalibrationOptionsRefuseBadValues) {
  EXPECT_TRUE(CalibrationOptions{}.IsValid());
  const Rig rig = design::thesis_prototype_rig();
  CalibrationOptions o;
  o.radial_terms = 4;
  EXPECT_NE(refusal([&] { calibrate_rig(rig, {}, o); }).find("radial_terms"), std::string::npos);
  o = {};
  o.loss = "l2";
  EXPECT_FALSE(o.IsValid());
  o = {};
  o.dense_subpixel.max_iterations = 0;  // nested options are checked too
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("dense_subpixel"), std::string::npos);
  EXPECT_NE(refusal([&] { calibrate_from_tracks(rig, {}, SceneModel::kFar, o); }).find("dense_subpixel"),
            std::string::npos);
}

}  // namespace
}  // namespace omma::calib
