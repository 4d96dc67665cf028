#include "omma/core/geometry.h"

#include <gtest/gtest.h>

namespace omma {
namespace {

TEST(Geometry, SphericalRoundTripEq515) {
  for (double th = 0.05; th < kPi; th += 0.3)
    for (double ph = 0; ph < 2 * kPi; ph += 0.4) {
      const Vec3 w = direction_from_spherical(th, ph);
      EXPECT_NEAR(w.norm(), 1.0, 1e-12);
      const Spherical s = spherical_from_direction(w);
      EXPECT_NEAR(s.theta, th, 1e-12);
      EXPECT_NEAR(s.phi, ph, 1e-12);
    }
  // Pole is +z, phi = 0 is +x, phi = 90 deg is +y.
  EXPECT_NEAR((direction_from_spherical(0, 1.0) - Vec3::UnitZ()).norm(), 0, 1e-12);
  EXPECT_NEAR((direction_from_spherical(kPi / 2, 0) - Vec3::UnitX()).norm(), 0, 1e-12);
  EXPECT_NEAR((direction_from_spherical(kPi / 2, kPi / 2) - Vec3::UnitY()).norm(), 0, 1e-12);
}

TEST(Geometry, YawPitchRollEq313) {
  // All zero: t = x, u = y, v = z.
  const Frame f0 = frame_from_ypr({0, 0, 0});
  EXPECT_NEAR((f0.t - Vec3::UnitX()).norm(), 0, 1e-12);
  EXPECT_NEAR((f0.u - Vec3::UnitY()).norm(), 0, 1e-12);
  EXPECT_NEAR((f0.v - Vec3::UnitZ()).norm(), 0, 1e-12);
  // First row of eq. 3.13e: t = (cb ca, -sa cb, sb).
  const double a = 0.3, b = -0.4, g = 1.1;
  const Frame f = frame_from_ypr({a, b, g});
  EXPECT_NEAR(f.t.x(), std::cos(b) * std::cos(a), 1e-12);
  EXPECT_NEAR(f.t.y(), -std::sin(a) * std::cos(b), 1e-12);
  EXPECT_NEAR(f.t.z(), std::sin(b), 1e-12);
  // Third row: v = (sa sg - ca cg sb, cg sa sb + sg ca, cb cg).
  EXPECT_NEAR(f.v.x(), std::sin(a) * std::sin(g) - std::cos(a) * std::cos(g) * std::sin(b), 1e-12);
  EXPECT_NEAR(f.v.z(), std::cos(b) * std::cos(g), 1e-12);
  const FrameError e = frame_error(f);
  EXPECT_LT(e.max_dot, 1e-12);
  EXPECT_LT(e.handedness_error, 1e-12);
  const YawPitchRoll back = ypr_from_frame(f);
  EXPECT_NEAR(back.yaw, a, 1e-12);
  EXPECT_NEAR(back.pitch, b, 1e-12);
  EXPECT_NEAR(back.roll, g, 1e-12);
}

TEST(Geometry, FrameLookingAt) {
  const Frame f = frame_looking_at(Vec3(1, 1, 1), Vec3::UnitZ());
  const FrameError e = frame_error(f);
  EXPECT_LT(e.max_norm_error, 1e-12);
  EXPECT_LT(e.max_dot, 1e-12);
  EXPECT_LT(e.handedness_error, 1e-12);
  EXPECT_GT(f.v.z(), 0);  // "down" follows the hint
  // Degenerate hint still gives a valid frame.
  const FrameError e2 = frame_error(frame_looking_at(Vec3::UnitZ(), Vec3::UnitZ()));
  EXPECT_LT(e2.handedness_error, 1e-12);
}

}  // namespace
}  // namespace omma
