// The ray error of rig-diff: what a stitch sees of two camera models.
#include "omma/calib/rig_diff.h"

#include <gtest/gtest.h>

#include "omma/testing/test_scenes.h"

namespace omma::calib {
namespace {

RigCamera rotated(RigCamera c, const Vec3& axis_camera, double angle_rad) {
  // Rotation about an axis given in the camera's own frame (t, u, v coordinates).
  const Mat3 r_dc = c.frame.dome_to_camera();
  const Vec3 axis_dome = r_dc.transpose() * axis_camera;
  const Mat3 m = r_dc * Eigen::AngleAxisd(angle_rad, axis_dome).toRotationMatrix().transpose();
  c.frame = {m.row(0).transpose(), m.row(1).transpose(), m.row(2).transpose()};
  return c;
}

TEST(RigDiff, RayErrorIsWhatTheStitchSees) {
  const Rig rig = testing::test_rig_24();
  const RigCamera& c = rig.cameras[4];
  EXPECT_NEAR(ray_error_deg(c, c), 0, 1e-9);
  // A rotation of 1.5 deg about the image's u axis turns every ray by at most 1.5 deg (exactly for
  // rays perpendicular to the axis): RMS just below 1.5.
  const RigCamera r = rotated(c, Vec3(0, 1, 0), deg2rad(1.5));
  EXPECT_LE(ray_error_deg(r, c), 1.5 + 1e-9);
  EXPECT_GT(ray_error_deg(r, c), 1.3);
  // A principal-point shift of 5 px moves the rays by 5 / f rad on the axis, 5 cos^2(a) / f at
  // field angle a ...
  RigCamera shifted = c;
  shifted.in.cu += 5;
  const double pp_only = ray_error_deg(shifted, c);
  EXPECT_LT(pp_only, rad2deg(5 / c.in.fu));
  EXPECT_GT(pp_only, 0.8 * rad2deg(5 / c.in.fu));
  // ... and a rotation about v by ~5 / f rad nearly undoes it (the principal-point / rotation
  // ambiguity of calibration): a large orientation error, a small ray error.
  double best = 1e9;
  for (double sign : {-1.0, 1.0})
    best = std::min(best, ray_error_deg(rotated(shifted, Vec3(0, 0, 1), sign * 5 / c.in.fu), c));
  EXPECT_LT(best, 0.15 * pp_only);
  Rig a = rig, b = rig;
  b.cameras[4] = shifted;
  const RigDiff d = diff_rigs(b, a);
  EXPECT_NEAR(d.ray_error_deg.max, pp_only, 1e-12);
  EXPECT_NEAR(d.ray_error_deg.median, 0, 1e-9);
}

}  // namespace
}  // namespace omma::calib
