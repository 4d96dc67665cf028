// The real stereo rig of OpenCV's samples (real_data.h: left01..14.jpg / right01..14.jpg, 640 x 480
// gray, left10 / right10 missing; a 9 x 6 inner-corner chessboard of 25 mm squares moves between
// the shots, the rig is static) as a test fixture: the pairs, their chessboard calibration (the
// truth), the perturbed start a user would give, and the errors of a rig against the truth. Used by
// `omma real stereo-calib` (bench/real_stereo.cc), calib/stereo_real_test.cc and the CLI test
// CalibCli.RealStereoPooledShots.
//
// Conventions.
//   * OpenCV: cv::stereoCalibrate's R, T map left-camera coordinates to right-camera coordinates,
//     x_r = R x_l + T (OpenCV camera axes: x right, y down, z forward; T in mm). The right camera's
//     centre in the left camera's frame is -R^T T. OpenCV's pixel centres are at integers, omma's at
//     +0.5 (core/conventions.h): omma's cu = OpenCV's cx + 0.5, cv = cy + 0.5.
//   * The rig's dome frame is the left camera's OpenCV frame: camera 0 (left) sits at the origin with
//     u = +x, v = +y, t = +z; camera 1 (right) has rows (u, v, t) = the rows of its rotation
//     (R for the truth) and its centre at position_mm (-R^T T for the truth).
//   * Distortion: OpenCV's (k1 k2 p1 p2 k3) is omma's k = (k1, k2, p2, p1, k3) (k3 = p2, k4 = p1,
//     core/camera.h eq. 5.24-5.26).
//   * Units: mm, degrees in the names ending _deg, percent in _pct, pixels in _px.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/core/rig.h"

namespace omma::testing {

// The stereo pairs found in a folder, in shot order (ids ascending, 1..14).
struct StereoPairs {
  std::filesystem::path dir;
  std::vector<int> ids;              // shot numbers of the files (leftNN.jpg / rightNN.jpg)
  std::vector<cv::Mat> left, right;  // 8-bit gray (CV_8UC1), one per id
};

// Reads leftNN.jpg and rightNN.jpg for NN = 01..14 from `dir` (shots whose left or right file is
// absent are left out). Throws std::runtime_error naming the file if one exists but cannot be read.
// An empty result where `dir` holds none (e.g. opencv_samples_dir() empty: opencv-doc not installed).
StereoPairs load_stereo_pairs(const std::filesystem::path& dir);

// The chessboard calibration of the pairs: cv::findChessboardCorners (9 x 6, ADAPTIVE_THRESH |
// NORMALIZE_IMAGE) and cv::cornerSubPix (11 x 11 window, 30 iterations / 0.01) in both images,
// cv::calibrateCamera per camera over the shots whose board was found in both, then
// cv::stereoCalibrate with CALIB_FIX_INTRINSIC. OpenCV conventions (pixel centres at integers).
// Reproducible to about 1e-11 relative, not bit for bit: with the same corners (bit for bit),
// OpenCV 4.6's cv::calibrateCamera returns one of two results (fx of the right camera
// 542.34012484306641 or 542.34012483883146) depending on the process's heap layout.
struct StereoTruth {
  cv::Mat k[2], d[2];           // camera matrices (CV_64F 3x3), distortion (CV_64F 1x5: k1 k2 p1 p2 k3)
  Mat3 r;                       // x_r = R x_l + T
  Vec3 t;                       // mm
  double rms_mono[2] = {0, 0};  // cv::calibrateCamera's RMS reprojection error per camera, px
  double rms_stereo = 0;        // cv::stereoCalibrate's, px
  int views = 0;                // shots whose board was found in both images
  // Per shot (indices of StereoPairs): the refined corners (54, row-major from the board's first
  // corner, OpenCV pixels), empty where the board was not found in both images.
  std::vector<std::vector<cv::Point2f>> corners[2];

  // The right camera's centre in the left camera's frame (= the dome frame), mm: -R^T T.
  Vec3 right_centre_mm() const { return -r.transpose() * t; }
};

// Throws std::runtime_error naming pairs.dir if the board is found in both images of fewer than 3
// shots.
StereoTruth stereo_chessboard_truth(const StereoPairs& pairs);

// The start a user would give: focal lengths focal_rel times the truth's (fu = focal_rel * fx,
// fv = focal_rel * fy), principal point at the image centre (320, 240), no distortion, aov 80 deg;
// the left camera exact (at the origin, the dome frame's axes); the right camera's rotation
// pose_deg off (R_start = Rot(axis.normalized(), pose_deg) * R) and its centre rotated pose_deg
// about n = (b x a).normalized(), b = right_centre_mm(), a = baseline_axis or, where that is zero,
// axis (as given: not normalised before the cross product); n = b.unitOrthogonal() where b x a
// vanishes. The baseline length is the truth's (the scale gauge). The rig is validated.
struct StereoStartOptions {
  Vec3 axis = Vec3(1, 1, 0);          // rotation axis of the right camera's error, any nonzero vector
  Vec3 baseline_axis = Vec3::Zero();  // see above (only its direction matters, up to rounding)
  double focal_rel = 1.03;
  double pose_deg = 5;
  std::string name;                              // Rig::name
  double dome_radius_mm = DomeInfo{}.radius_mm;  // Rig::dome.radius_mm
};
Rig stereo_start_rig(const StereoTruth& truth, const StereoStartOptions& opt = {});

// `rig` with both cameras' intrinsics replaced by the truth's: fu, fv = fx, fy; cu, cv = cx + 0.5,
// cy + 0.5; k from OpenCV's distortion (see Conventions). Poses, size and aov unchanged.
Rig with_truth_intrinsics(Rig rig, const StereoTruth& truth);

// The right camera's rotation relative to the left's, as OpenCV's R: M1 M0^T with Mi the matrix of
// rows (u, v, t) of camera i.
Mat3 stereo_relative_rotation(const Rig& rig);

// Errors of a two-camera rig (camera 0 left, camera 1 right) against the truth.
struct StereoErrors {
  double relative_rotation_deg = 0;       // angle of stereo_relative_rotation(rig) * R^T
  double baseline_direction_deg = 0;      // angle between M0 (c1 - c0) and right_centre_mm()
  double focal_pct[2] = {0, 0};           // 100 * (|fu / fx - 1| + |fv / fy - 1|) / 2, left, right
  double principal_point_px[2] = {0, 0};  // |(cu, cv) - (cx + 0.5, cy + 0.5)|, left, right
};
StereoErrors stereo_errors(const Rig& rig, const StereoTruth& truth);

// The pairs as calib::calibrate_shots's shots: {left, right} converted to BGR (CV_8UC3), for the
// shots whose id is in `ids` (in the pairs' order), or every shot where `ids` is empty.
std::vector<std::vector<cv::Mat>> stereo_shot_sets(const StereoPairs& pairs,
                                                   const std::vector<int>& ids = {});

}  // namespace omma::testing
