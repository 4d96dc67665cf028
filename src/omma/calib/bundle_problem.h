// The bundle adjustment's Ceres problem (bundle.h), exposed for tests: the parameter blocks of one
// solve and the builder of one pass's problem. Not part of the calibration's interface.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <vector>

#include <ceres/ceres.h>

#include "omma/calib/calibrate.h"
#include "omma/core/geometry.h"

namespace omma::calib::detail {

// The parameters of one solve (model, gauge and priors: calibrate.h).
struct BundleBlocks {
  std::vector<Mat3> r_nom;                    // per camera: the start's dome -> camera rotation
  std::vector<std::array<double, 3>> delta;   // per camera: rotation correction (angle-axis, rad)
  std::vector<std::array<double, 4>> fcc;     // per camera: fu, fv, cu, cv (pixels)
  std::vector<std::array<double, 5>> kk;      // per camera: k1..k5
  std::vector<std::array<double, 4>> points;  // per track: near (P, h) normalised, far unit direction
  bool near = false;                          // the near-field model (homogeneous points)
  bool tube = false;                          // points on the calibration tube's wall
  double tube_r = 0;                          // the tube's radius, mm
  std::vector<char> on_tube;                  // per track: its point lies on the wall
  std::vector<std::array<double, 2>> uv;      // per track on the wall: (phi rad, z mm)
  std::array<double, 4> axis{};               // the tube's axis (ox, oy mm, tx, ty)
  bool share_intrinsics = false;              // one fcc block for all cameras (share_focal or share_center)
  bool share_distortion = false;              // one k block for all cameras
  std::vector<int> k_const, fcc_const;        // entries held (radial_terms, estimate_* options)
  std::vector<Vec3> c;                        // per camera: the start's centre, mm
  bool position = false;                      // near field, estimate_position: centres estimated
  int ref = 0;                                // the reference camera (position and rotation held)
  std::vector<double> len;                    // per camera: distance from the reference's centre, mm
                                              // (held; 0 = the camera does not move)
  std::vector<std::array<double, 3>> dir;     // per camera: unit direction from the reference's centre
  bool moves(int i) const;                    // camera i's centre is estimated
  Vec3 centre(int i) const;                   // camera i's current centre, mm
  double* fcc_block(int i);
  double* k_block(int i);
};

// The start of a solve: rotations and intrinsics of `start`, scene points triangulated (near) or
// the mean ray (far), the tracks on the tube's wall (tube_axis: a previous solve's axis, which also
// narrows the band to tube_tolerance_refined).
BundleBlocks init_bundle_blocks(const Rig& nominal, const Rig& start,
                                const std::vector<std::vector<TrackObservation>>& tracks, SceneModel scene,
                                const CalibrationOptions& opt,
                                const std::optional<std::array<double, 4>>& tube_axis);

// The manifolds a pass's problem refers to (the problem must not own them).
struct BundleManifolds {
  explicit BundleManifolds(const BundleBlocks& b);
  ceres::SphereManifold<3> sphere3;         // far-field points
  ceres::SphereManifold<4> sphere4;         // near-field homogeneous points
  std::unique_ptr<ceres::Manifold> k, fcc;  // the intrinsics' held entries (null: none or all held)
  ceres::SubsetManifold tube_offset_only;   // the tube's tilt held (CalibrationOptions::tube_tilt)
};

// Builds one pass's problem (Problem::Options::manifold_ownership = DO_NOT_TAKE_OWNERSHIP): one
// reprojection residual (robust loss) per kept observation of every track with at least two kept
// observations, the points' manifolds, the rotation prior (or rotations held), the mean-focal prior
// (near field without the tube, intrinsics_free) and the intrinsics held (all of them unless
// intrinsics_free, else those not estimated). Returns the number of observation residuals added.
int build_bundle_problem(ceres::Problem& problem, BundleManifolds& m, BundleBlocks& b,
                         const std::vector<std::vector<TrackObservation>>& tracks,
                         const std::vector<std::vector<char>>& keep, const Rig& nominal,
                         const CalibrationOptions& opt, bool intrinsics_free);

}  // namespace omma::calib::detail
