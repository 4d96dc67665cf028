// A rough rig from the images alone: each camera's orientation estimated from its overlaps with the
// other cameras, for cameras whose poses nobody measured (a photographer's handful of pictures, as a
// Hugin user gives them: images and maybe a focal length). calibrate_rig (calibrate.h) then takes
// over: its matching only looks at keypoints whose NOMINAL direction lies in the other camera's
// cone (features.h match_pair), so it needs a rig that is right to a few degrees, which this gives.
//
// Model: the far field (rotation only, calibrate.h): a distant scene is seen by two cameras along
// the same direction w, so the rays of a true match, in the two cameras' own frames, are related by
// one rotation: d_b = Q_ab d_a with d = R_cam w (R_cam: rows t, u, v, conventions.h). Per pair of
// images: SIFT (features.h detect_features), brute-force matching with Lowe's ratio test (no
// nominal prior: every keypoint against every keypoint), then RANSAC for Q_ab on 2-match samples
// (Kabsch, features.h fit_rotation), inliers within ransac_threshold_px (converted to an angle with
// the cameras' focal lengths), Q_ab refitted on the inliers. The rays come from each camera's
// intrinsics (Intrinsics: focal, principal point and distortion, eq. 5.21-5.26); a focal length off
// by a few per cent only widens the residuals, so the threshold is loose (calibrate_rig refines).
//
// Chaining: a maximum spanning tree of the pairs weighted by inlier count (Prim, from camera 0);
// camera 0 is fixed looking along +z with its image right along -x and its image down along -y,
// i.e. the centre of the vr180 grid (grid.h (G2)) shows camera 0's picture upright; every other
// camera's frame is R_b = Q_ab R_a along the tree. Positions: each camera sits at dome_radius_mm
// along its optical axis (irrelevant in the far field).
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/calib/features.h"
#include "omma/core/rig.h"

namespace omma::calib {

struct InitialPoseOptions {
  FeatureOptions features = default_features();
  double ratio = 0.75;                // Lowe's ratio test
  double ransac_threshold_px = 6;     // inlier threshold (pixels of the larger focal length)
  int ransac_iterations = 2000;       // 2-match samples per pair
  int min_inliers = 20;               // a pair with fewer does not link its cameras
  unsigned seed = 1;                  // RANSAC's random samples
  double dome_radius_mm = 5;          // where the cameras sit (far field: does not matter)
  std::string name = "initial-pose";  // the rig's name

  // SIFT on the image as it is (no upsampling: real photographs have enough pixels), up to 4000.
  static FeatureOptions default_features() {
    FeatureOptions f;
    f.max_features = 4000;
    f.upsample = 1;
    f.contrast_threshold = 0.02;
    return f;
  }
  // False (with the reason in *why) when a value lies outside the range the code relies on.
  bool IsValid(std::string* why = nullptr) const;
};

// Matches between two images (continuous pixel coordinates, centres at integer + 0.5).
struct PixelMatches {
  std::vector<Vec2> a, b;  // a[i] in image a matches b[i] in image b
};

// Ratio-test matches of every keypoint of `fa` against every keypoint of `fb` (cv::BFMatcher, L2,
// two nearest neighbours; a match must also be the mutual best). No geometry.
PixelMatches match_features(const CameraFeatures& fa, const CameraFeatures& fb, double ratio = 0.75);

struct PairPose {
  int cam_a = 0, cam_b = 0;          // indices into the inputs
  int matches = 0;                   // after the ratio test
  int inliers = 0;                   // consensus of the rotation
  double rms_px = 0;                 // residual of the inliers (pixels of camera b)
  Mat3 rotation = Mat3::Identity();  // d_b = rotation * d_a (rays in the cameras' own frames)
  bool in_tree = false;              // used to chain the orientations
};

struct InitialPoseSummary {
  Rig rig;                      // camera i: id i, intrinsics[i], the estimated frame
  std::vector<PairPose> pairs;  // every pair a < b
  std::vector<std::string> warnings;
};

// The rotation between two cameras' rays (d_b = Q d_a) from pixel matches, by RANSAC as above.
// Fills matches/inliers/rms_px/rotation; `inlier_mask` (optional) gets one flag per match.
PairPose estimate_pair_rotation(const Intrinsics& in_a, const Intrinsics& in_b, const PixelMatches& m,
                                const InitialPoseOptions& opt = {}, std::vector<bool>* inlier_mask = nullptr);

// Every camera's orientation from `images` (any size each, 8/16-bit, 1 or 3 channels; image i is
// intrinsics[i].width x height). Throws std::invalid_argument on bad input (counts, sizes, options:
// names the camera) and std::runtime_error naming the cameras that no chain of pairs with
// min_inliers links to camera 0.
InitialPoseSummary initial_pose(const std::vector<cv::Mat>& images, const std::vector<Intrinsics>& intrinsics,
                                const InitialPoseOptions& opt = {});

// The chaining alone, from pair rotations estimated elsewhere (e.g. estimate_pair_rotation on
// matches of the caller's choice): `pairs` with cam_a, cam_b, inliers and rotation set (any pairs,
// any order). Same rig and errors as initial_pose; pairs used get in_tree = true.
InitialPoseSummary initial_pose_from_pairs(const std::vector<Intrinsics>& intrinsics,
                                           std::vector<PairPose> pairs, const InitialPoseOptions& opt = {});

// Intrinsics of a W x H pinhole camera (centred principal point, no distortion) with the given
// DIAGONAL angle of view in degrees (what a photographer knows, or 2 atan(d / 2f) of EXIF's focal
// length f and sensor diagonal d); field kImage (the camera sees its whole image).
Intrinsics intrinsics_from_diagonal_fov(int width, int height, double diagonal_fov_deg);
// The same from a focal length in pixels.
Intrinsics intrinsics_from_focal(int width, int height, double focal_px);

}  // namespace omma::calib
