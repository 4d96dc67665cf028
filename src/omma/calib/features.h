// Feature detection, matching and outlier rejection between overlapping cameras of a rig
// (thesis §3.6: SIFT features, then a geometric model rejects the false matches).
//
// Pixel coordinates are continuous with pixel centres at integer + 0.5 (conventions.h); OpenCV
// keypoints (centres at integers) are shifted by +0.5 when they enter this module.
//
// Geometric models used by RANSAC (directions in the dome frame, computed with the NOMINAL rig):
//   * far field (rotation only): the cameras sit on a 5 mm dome, so for a distant scene two
//     cameras see the same point along parallel rays, and the nominal directions of a true match
//     are related by one small rotation: d_j = R d_i. Minimal sample: 2 matches (Kabsch).
//   * near field (parallax, e.g. the colon tube): the essential matrix between the two cameras'
//     normalised coordinates (cv::findEssentialMat, 5-point RANSAC).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/core/rig.h"

namespace omma::calib {

struct CameraFeatures {
  std::vector<Vec2> px;  // continuous pixel coordinates (centres at integer + 0.5)
  cv::Mat descriptors;   // CV_32F, one row per keypoint (SIFT, 128 columns)
};

struct FeatureOptions {
  int max_features = 2000;           // per camera (SIFT nfeatures)
  double contrast_threshold = 0.01;  // SIFT contrast threshold (lower: more features on small images)
  int border_px = 2;                 // drop keypoints this close to the image border
  int upsample = 2;                  // run SIFT on the image upsampled this much (more, finer
                                     // keypoints on 250x250 frames; 1 = off)
  double blur_sigma = 0;             // Gaussian pre-smoothing (pixels, 0: off) against sensor noise
  double clahe_clip = 3.0;           // contrast-limited histogram equalisation (0: off), applied only
  int clahe_below = 200;             // when plain SIFT finds fewer keypoints than this: brings out
                                     // texture in dark, low-contrast views (night sky)

  // False (with the reason in *why) when a value lies outside the range the code relies on.
  bool IsValid(std::string* why = nullptr) const;
};

// SIFT on one camera image (8U or 16U, 1 or 3 channels).
CameraFeatures detect_features(const cv::Mat& image, const FeatureOptions& opt = {});

// Pairs (a, b) of rig indices (a < b) whose nominal cones of view intersect: angle(t_a, t_b) <
// (aov_a + aov_b)/2 - margin. Only these pairs are matched.
std::vector<std::pair<int, int>> overlapping_pairs(const Rig& rig, double margin_rad = 0);

enum class SceneModel { kFar, kNear, kAuto };
SceneModel parse_scene_model(const std::string& name);  // "far", "near", "auto"
std::string to_string(SceneModel m);

struct MatchOptions {
  double ratio = 0.8;              // Lowe's ratio test on the two nearest descriptors
  double self_ratio = 0;           // repetitive texture (a chessboard's squares): a match is dropped
                                   // when either keypoint has a twin in its OWN image whose descriptor
                                   // distance is below match distance / self_ratio (an ambiguous
                                   // keypoint); 0 = off
  double overlap_margin_deg = 8;   // only keypoints whose nominal direction lies inside the other
                                   // camera's cone widened by this are matched (tolerates the
                                   // assembly errors of the nominal rig)
  double ransac_threshold_px = 5;  // inlier threshold, pixels (converted to angle with the focal)
  int ransac_iterations = 500;
  int min_inliers = 8;  // fewer: the pair is dropped
  unsigned seed = 1;

  // False (with the reason in *why) when a value lies outside the range the code relies on.
  bool IsValid(std::string* why = nullptr) const;
};

struct Match {
  int a = 0, b = 0;  // keypoint indices in camera a and camera b
};

struct PairMatches {
  int cam_a = 0, cam_b = 0;         // rig indices
  int putative = 0;                 // after the ratio test (mutual nearest neighbours)
  std::vector<Match> putative_set;  // those matches
  std::vector<Match> inliers;       // after RANSAC, with the model asked for (auto: see match_pair)
  std::vector<Match> rotation_set, essential_set;  // consensus sets of both models
  int rotation_inliers = 0;                        // consensus of the rotation-only model
  int essential_inliers = 0;         // consensus of the essential-matrix model (near field), 0 if not run
  Mat3 rotation = Mat3::Identity();  // far-field model: d_b = rotation * d_a (dome frame, nominal)
  // True when the essential-matrix consensus is clearly larger (the pair shows parallax).
  bool prefers_near() const { return essential_inliers > 1.3 * rotation_inliers + 5; }
  // Sets `inliers` to the consensus set of `model` (kAuto: the preferred one), or empties it if
  // it has fewer than min_inliers matches.
  void choose(SceneModel model, int min_inliers);
};

// Ratio-test matching then RANSAC with the given scene model (kAuto runs both and keeps the
// essential-matrix consensus only when it is clearly larger, i.e. the pair shows parallax).
PairMatches match_pair(const Rig& nominal, int cam_a, int cam_b, const CameraFeatures& fa,
                       const CameraFeatures& fb, SceneModel model, const MatchOptions& opt = {});

// Least-squares rotation R minimising sum |R a_i - b_i|^2 over unit vectors (Kabsch).
Mat3 fit_rotation(const std::vector<Vec3>& a, const std::vector<Vec3>& b);

// One observation of a feature track: camera (rig index) and continuous pixel (centres at
// integer + 0.5, conventions.h).
struct TrackObservation {
  int cam = 0;
  Vec2 px;
  // Whitening of the residual (a square root of the observation's information matrix, scaled so
  // that an average observation has ~identity): the residual is weight * (projection - px). The
  // subpixel refinement sets it from the alignment's covariance; identity = plain pixels.
  Eigen::Matrix2d weight = Eigen::Matrix2d::Identity();
};

// Feature tracks from the pairwise matches (union-find over every camera's keypoints): one track per
// connected set of matched keypoints; a set that holds two keypoints of one camera is dropped
// (an inconsistent match), as are sets of one. Observations are the keypoints' continuous pixels.
std::vector<std::vector<TrackObservation>> build_tracks(const std::vector<CameraFeatures>& feats,
                                                        const std::vector<PairMatches>& pairs);

}  // namespace omma::calib
