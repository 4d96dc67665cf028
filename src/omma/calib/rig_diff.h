// Comparing two rigs camera by camera (e.g. a calibrated rig against the simulator's true rig).
//   orientation error: angle of the relative rotation R_a R_b^T between the two cameras' frames
//                      (rows t, u, v, eq. 3.13), degrees;
//   focal error:       |f_a - f_b| / f_b per axis (fu and fv, the larger of the two), unitless;
//   centre error:      |(cu, cv)_a - (cu, cv)_b|, pixels;
//   ray error:         per camera, the RMS over a 9 x 9 grid of pixels inside b's angle of view of
//                      the angle between the rays a and b assign to the same pixel (unproject, with
//                      distortion), degrees. This is what a stitch sees: a principal-point error
//                      compensated by a small rotation (nearly the same ray bundle) has a large
//                      orientation error but a small ray error.
// Cameras are paired by id; both rigs must hold the same ids.
#pragma once

#include <vector>

#include "omma/core/rig.h"

namespace omma::calib {

struct Stat {
  double median = 0, max = 0, mean = 0;
};

struct RigDiff {
  Stat orientation_error_deg;
  Stat focal_error_rel;
  Stat center_error_px;
  Stat ray_error_deg;
  std::vector<double> per_camera_orientation_deg;  // in the order of rig a
  Mat3 alignment = Mat3::Identity();  // global rotation applied to rig a (identity unless aligned)
};

// With `align`, rig a is first rotated by the global rotation that best maps its frames onto b's
// (the far-field gauge: a distant scene cannot tell a rig from a rotated copy of it).
RigDiff diff_rigs(const Rig& a, const Rig& b, bool align = false);

// The rotation G (dome frame) minimising sum_i |R_b,i G - R_a,i|^2 (R = rows t,u,v): b's frames
// rotated by G^T match a's best. Chordal L2 mean via SVD.
Mat3 best_alignment(const Rig& a, const Rig& b);
// A copy of `rig` with every camera frame and position rotated by g (dome frame: w -> g w).
Rig rotate_rig(const Rig& rig, const Mat3& g);

Stat make_stat(std::vector<double> v);

// The ray error of one camera (see above): a and b are the same camera in two rigs.
double ray_error_deg(const RigCamera& a, const RigCamera& b);

}  // namespace omma::calib
