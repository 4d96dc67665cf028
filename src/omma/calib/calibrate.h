// Rig calibration from one set of camera frames (thesis §3.6): SIFT features in every camera,
// matching between cameras whose nominal cones of view intersect, RANSAC outlier rejection, then
// a Ceres bundle adjustment of per-camera rotation, focal lengths, principal point and radial
// distortion, with a robust loss. Measured accuracies and the tuning behind the defaults:
// docs/results/tuning-calibration.md.
//
// Model (conventions.h, eq. 3.13, eq. 5.21-5.26). Camera i maps a dome-frame direction w to
//   p = Exp(delta_i) * R_nom_i * w          (R_nom_i = rows t, u, v of the NOMINAL camera i;
//                                             delta_i = angle-axis correction in the camera frame)
//   x = p_u / p_t,  y = p_v / p_t,  (x', y') = distort(k_i, x, y),  pixel = (cu + fu x', cv + fv y').
// The calibrated frame is (t, u, v) = rows of Exp(delta_i) R_nom_i; ypr follow from eq. 3.13.
//
// Scene points (one per feature track, built by union-find over the pairwise matches):
//   * far field: a unit direction s on S^2 (Ceres SphereManifold<3>), w = s. The cameras sit on a
//     5 mm dome, so a distant scene is seen along parallel rays: rotation-only.
//   * near field (parallax, e.g. the 35 mm colon tube): a homogeneous point X = (P, h) on S^3 and
//     the camera centres c_i FIXED at their nominal positions: w = P - h c_i (mm).
//   * near field with camera positions estimated (CalibrationOptions::estimate_position, a rig with a
//     real baseline, e.g. a stereo pair at 0.5-3 m): c_i = c_ref + |c_i - c_ref| * dir_i, dir_i on
//     S^2 (SphereManifold<3>). Gauge: the reference camera (the first with observations) keeps its
//     nominal position AND rotation; every other camera keeps its nominal DISTANCE from the
//     reference (the scale: the baseline length the user measured), only its direction moves; the
//     rotation prior is not used. Not with the calibration tube.
//   The scene model is chosen per run (auto: near when the essential-matrix consensus, summed over
//   all camera pairs, exceeds the rotation-only one by near_ratio).
//
// Gauge: in the far field the whole rig can rotate freely without changing any image, so a weak
// prior |delta_i| / sigma (sigma = prior_rotation_deg) pulls the rotations towards the nominal
// ones; it only fixes the free global rotation (the rig's mean orientation stays nominal). With
// parallax the fixed camera positions fix the gauge and the prior is negligible.
//
// Near-field focal ambiguity: the baseline (cameras on a 5 mm dome) is small against the scene
// depth (the colon wall at ~20 mm), so scaling every focal length by s and pushing the scene away
// (points radially out from the dome centre) changes the images only in second order. A prior
// (sigma = prior_mean_focal) holds the MEAN of fu/fu_nominal over the cameras at 1 in the near
// field: it fixes that one direction (the lens batch's mean focal length is taken as designed), the
// cameras' focal lengths relative to each other stay free. The near field also uses a Cauchy loss
// (loss = "auto"): wrong matches that lie along epipolar lines would drag the rotations away under
// Huber. Principal point and a small rotation about u or v are nearly the same thing for a 64 deg
// lens (a shift of c px ~ c / f rad), which the near-field overlaps (narrow bands) hardly separate.
//
// Residuals are in pixels; the robust loss (Huber or Cauchy, scale loss_scale_px) tames remaining
// outliers, then observations above outlier_px are dropped and the problem is solved again. Three
// passes: rotations and points with nominal intrinsics (a warm start), everything free, then
// rejection and the final solve. Nothing is rejected after the warm start: with nominal
// intrinsics the edge observations that determine them look like outliers.
//
// Several shots (calibrate_shots). kAverage: a static rig AND a static scene; the frame sets are
// averaged (average_frame_sets) and calibrated as one. kPool: a static rig, a scene that may change
// between shots (a chessboard moved in front of a stereo pair): features, matches and feature tracks
// per shot (a scene point belongs to one shot), and one bundle adjustment over all tracks of all
// shots; the scene model (auto) from the consensus summed over all shots and pairs. kAuto: pool
// when the shots' frames differ (shots_differ), else average.
//
// Subpixel refinement (refine_rounds, subpixel.h). SIFT keypoints of one scene point in two cameras
// disagree by a few tenths of a pixel (SIFT is not affine invariant). After the first solve every
// track is re-measured: its observation nearest a principal point is the reference, and every other
// observation becomes the ECC alignment of the reference's patch (SubpixelOptions::patch_px), by a
// homography started from the current model's map of the local scene plane (near field: plane
// through the track's point, normal from its neighbouring points; far field: the plane at
// infinity); then all is solved again from the first solution with outlier_px = refine_outlier_px.
// Near field: dense, flat-fielded, weighted refinement instead (dense_refine, refine.h
// dense_tracks); the study of the near-field limits behind these choices is in
// docs/near_field_calibration.md.
//
// Stages and files: features and matching (features.h, with the feature tracks), bundle
// adjustment (bundle.h), subpixel refinement (refine.h, subpixel.h), photometric calibration
// (photometric.h); calibrate.cc runs them in order.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/calib/features.h"
#include "omma/calib/subpixel.h"
#include "omma/core/rig.h"

namespace omma::calib {

// The near field's alignment options (chosen on the simulated colon,
// docs/results/tuning-calibration.md): 31 px patches (larger ones cross the wall's folds), no coarse
// Gaussian stage (the start is within a few tenths of a pixel), correlation >= 0.5 (the
// flat-fielded patches correlate less; the covariance weights the weak ones down), flat field of
// sigma 5 px (to_alignment_image).
inline SubpixelOptions dense_subpixel_defaults() {
  SubpixelOptions so;
  so.patch_px = 31;
  so.gauss_px = 0;
  so.min_correlation = 0.5;
  so.flatfield_sigma_px = 5;
  return so;
}

struct CalibrationOptions {
  FeatureOptions features;
  MatchOptions match;
  SceneModel scene = SceneModel::kAuto;
  double near_ratio = 1.15;       // auto: near when the essential-matrix consensus over all pairs
                                  // exceeds the rotation-only one by this factor
  double overlap_margin_deg = 0;  // pairs need nominal cones intersecting by more than this

  bool estimate_rotation = true;
  bool estimate_position = false;    // near field: camera centres move on spheres about the reference
                                     // camera's (see "near field with camera positions estimated");
                                     // set prior_mean_focal = 0 to let the focal lengths move too
  bool estimate_focal = true;        // fu, fv
  bool estimate_center = true;       // cu, cv
  int radial_terms = 1;              // how many radial coefficients to estimate: 0..3 = k1, k2, k5
  bool estimate_tangential = false;  // k3, k4
  bool share_focal = false;          // one fu, fv for all cameras
  bool share_center = false;         // one cu, cv for all cameras
  bool share_distortion = false;     // one k1..k5 for all cameras

  std::string loss = "auto";  // "huber", "cauchy", "none" or "auto": Huber in the far field,
                              // Cauchy in the near field (see "Near-field focal ambiguity" above)
  double loss_scale_px = 1.0;
  double outlier_px = 3.0;          // after the first solve, drop observations with a larger error
  double prior_rotation_deg = 5;    // gauge prior (see above)
  double prior_mean_focal = 0.002;  // near field only: sigma (relative) of a prior pulling the MEAN
                                    // of fu/fu_nominal (and fv) over the calibrated cameras to 1;
                                    // 0 = off (see "Near-field focal ambiguity" above)
  int refine_rounds = 1;            // subpixel refinement rounds after the first solve (0 = off):
                                    // ECC patch alignment of every observation, then solve again
  SubpixelOptions subpixel;
  double refine_min_fraction = 0.5;  // fewer observations aligned: keep the unrefined solution
                                     // (warning)
  double refine_outlier_px = 1.0;    // outlier_px of the solves on refined observations
  bool dense_refine = true;          // near field: dense guided correspondences from every keypoint
                                     // (see dense_tracks in refine.h) instead of the matched tracks
  int dense_rounds = 2;              // near field with dense_refine: refinement rounds (instead of
                                     // refine_rounds); the second aligns ~50 % more, from a better rig
  SubpixelOptions dense_subpixel = dense_subpixel_defaults();  // alignment options of dense_refine
  int dense_neighbours = 8;           // scene points whose median depth places a candidate keypoint
  double dense_max_gap_px = 40;       // candidates farther from any observed scene point are skipped
  bool dense_weighting = true;        // whiten by the alignment covariance (AlignInfo)
  double dense_weight_floor = 0.5;    // sigma floor, relative to the median sigma
  double dense_reference_weight = 1;  // weight of the reference observation (the patch centre)
  // The calibration tube (thesis §3.6, Fig. 3.12a; the simulator's tube scene): its known diameter.
  // Near field only: scene points within tube_tolerance (relative) of its wall, a cylinder about an
  // axis near the dome's z axis whose offset (and with tube_tilt its tilt) is estimated with the rig, are
  // constrained to it (two surface coordinates instead of a free 3D point), which fixes the depth scale (no
  // mean-focal prior is then needed or used) and removes the near field's flat directions (see
  // "Near-field focal ambiguity" and docs/near_field_calibration.md). 0 = off (free points).
  double tube_diameter_mm = 0;
  // The tube's axis defines the rig's z axis, as the thesis's fixture does (false: only its offset is
  // estimated) or is estimated, tilt too (true: for a mount that is not trusted; the rig's tilt and the
  // tube's then trade against each other, told apart only by the 5 mm parallax of the camera positions,
  // and the rig compares with the truth up to a global rotation, rig-diff --align).
  bool tube_tilt = false;
  double tube_tolerance = 0.15;          // first solve (from the nominal rig)
  double tube_tolerance_refined = 0.03;  // solves after the first
  int max_iterations = 50;               // Ceres iterations per solve
  int min_observations = 30;             // a camera with fewer keeps its nominal values (warning)
  int threads = 2;                       // Ceres threads; near-field results vary with the summation order
                                         // of a multi-threaded solve, 1 = reproducible

  // False (with the reason in *why) when a value lies outside the range the code relies on.
  bool IsValid(std::string* why = nullptr) const;
};

// Options for a rig with a real baseline seen at 0.5-3 m (a stereo pair calibrated from pooled
// shots of a changing scene): near field, camera positions estimated (the baseline direction),
// k1 and k2 per camera (strong barrel distortion), focal lengths and principal points HELD at the
// nominal ones, RANSAC threshold 8 px (the start knows no distortion: ~50 px at the corners of a
// k1 = -0.27 lens, mostly common to both views), 200 iterations, no subpixel refinement.
// Why the intrinsics are held: a static two-camera rig gives, however many shots are pooled, one
// epipolar geometry (the fundamental matrix, 7 numbers) plus the distortion; with nearly parallel
// optical axes the focal lengths are not determined by it (Bougnoux's degeneracy: on OpenCV's stereo
// samples, free focal lengths run 16-45 % away, even from the true principal points and distortion)
// and a principal point offset dc trades against the relative rotation by dc / f rad (free principal
// points run 45-130 px away). Measured there (13 shots, start 5 deg / 5 deg / focal 3 % / principal
// points at the image centre, 23 and 12 px off): relative rotation 1.33 deg, baseline direction
// 0.68 deg, k1 -0.26 / -0.31 (chessboard -0.27 / -0.28), RMS 0.33 px; the rotation's floor is the
// start's relative principal point error (~11 px / 536 px = 1.2 deg). From the chessboard's
// intrinsics instead: 0.076 deg, 0.63 deg. Everything free: focal 50 % off, rotation 14 deg.
// self_ratio 0.7: the chessboard's squares match each other (ratio test 0.8: 220 of 332 matches on
// the board wrong, 101 of 200 RANSAC inliers, mostly along the epipolar lines); 0.7 leaves 48 of
// 92 and 27 of 69 (stereo_real_test.cc, `omma real stereo-calib`).
inline CalibrationOptions stereo_calibration_options() {
  CalibrationOptions o;
  o.scene = SceneModel::kNear;
  o.estimate_position = true;
  o.prior_mean_focal = 0;
  o.estimate_focal = false;
  o.estimate_center = false;
  o.radial_terms = 2;
  o.match.ransac_threshold_px = 8;
  o.match.self_ratio = 0.7;
  o.max_iterations = 200;
  o.refine_rounds = 0;
  o.dense_refine = false;
  return o;
}

struct CameraReport {
  int id = 0;
  double rms_px = 0;  // reprojection RMS over this camera's observations
  int matches = 0;    // observations (feature track members) of this camera used in the fit
  bool calibrated = true;
};

struct PairReport {
  int cam_a = 0, cam_b = 0;  // camera ids
  int matches = 0;           // after the ratio test, summed over shots
  int inliers = 0;           // after RANSAC with the chosen scene model, summed over shots
};

struct CalibrationSummary {
  Rig rig;                              // the calibrated rig (uncalibrated cameras keep nominal values)
  SceneModel scene = SceneModel::kFar;  // the model used
  int matches = 0;                      // pairwise matches after the ratio test, all pairs
  int inliers = 0;                      // pairwise matches after RANSAC
  int pairs = 0;                        // camera pairs matched (nominal cones intersect)
  int tracks = 0;                       // scene points in the bundle adjustment
  int observations = 0;                 // residual blocks in the final solve
  int rejected = 0;                     // observations dropped as outliers after the first solve
  double rms_px = 0;                    // final reprojection RMS, pixels
  double initial_rms_px = 0;            // RMS with the nominal rig (same observations), pixels
  std::vector<CameraReport> per_camera;
  std::vector<PairReport> per_pair;   // every matched pair (overlapping nominal cones)
  int shots = 1;                      // shots whose tracks went into the adjustment
  std::vector<int> uncalibrated_ids;  // cameras with too few matches (kept nominal)
  std::vector<std::string> warnings;
};

// Throws std::runtime_error if nothing can be calibrated (e.g. textureless frames: no camera has
// enough matches). `frames` are in rig order (see omma/core/frames.h load_frames).
CalibrationSummary calibrate_rig(const Rig& nominal, const std::vector<cv::Mat>& frames,
                                 const CalibrationOptions& opt = {});

enum class ShotMode { kAverage, kPool, kAuto };
ShotMode parse_shot_mode(const std::string& name);  // "average", "pool", "auto"
std::string to_string(ShotMode m);

// PSNR (dB, 8-bit scale on the gray images) between shot 0's frame and every other shot's frame of
// the same camera: the lowest over all cameras and shots (+infinity for one shot). Sizes must agree.
double min_shot_psnr_db(const std::vector<std::vector<cv::Mat>>& sets);
// kAuto's test: the shots differ (a changing scene) when min_shot_psnr_db < kShotsDifferPsnrDb.
// Measured: simulated shots of a static scene (sensor noise only): 37.2 dB (lake, 3 shots), 40.7 dB
// (tube, 2 shots); OpenCV's real stereo shots 1-3 (a chessboard moved between them): 8.9 dB. Very
// noisy static shots (sigma ~10 of 255) would fall below 28 dB: pass --shots average for those.
constexpr double kShotsDifferPsnrDb = 28;
bool shots_differ(const std::vector<std::vector<cv::Mat>>& sets);

// calibrate_rig on several shots (`sets`: one frame set per shot, rig order) in the given mode
// (see "Several shots" above). Pooled: the subpixel refinement is not run (refine_rounds and
// dense_refine are ignored, a warning says so). Throws as calibrate_rig and average_frame_sets.
CalibrationSummary calibrate_shots(const Rig& nominal, const std::vector<std::vector<cv::Mat>>& sets,
                                   ShotMode mode, const CalibrationOptions& opt = {});

// Several shots of a static scene: the frame sets averaged in linear light (sRGB decoded,
// averaged, encoded again as 16-bit sRGB, CV_16UC3), which divides the sensor noise by sqrt(shots)
// and keeps one observation per feature. Throws std::invalid_argument if the sets differ in count
// or in a frame's size or are not 8/16-bit colour images (names the set and camera index).
std::vector<cv::Mat> average_frame_sets(const std::vector<std::vector<cv::Mat>>& sets);

// The bundle adjustment of calibrate_rig alone, on given feature tracks (one scene point per track,
// scene kFar or kNear; tracks with fewer than 2 observations of calibrated cameras are ignored).
// Used to check the model: tracks made by projecting known points through a rig must give that
// rig back. Throws std::invalid_argument on a bad camera index or kAuto, std::runtime_error if
// fewer than 2 cameras have min_observations.
CalibrationSummary calibrate_from_tracks(const Rig& nominal,
                                         std::vector<std::vector<TrackObservation>> tracks, SceneModel scene,
                                         const CalibrationOptions& opt = {});

}  // namespace omma::calib
