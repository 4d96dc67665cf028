#include "omma/core/camera.h"

#include <gtest/gtest.h>

namespace omma {
namespace {

CameraModel test_camera(std::array<double, 5> k = {}) {
  CameraModel c;
  c.frame = frame_looking_at(Vec3(0.2, -0.3, 1.0), Vec3::UnitX());
  c.in.width = 250;
  c.in.height = 250;
  c.in.fu = 200;
  c.in.fv = 205;
  c.in.cu = 126.5;
  c.in.cv = 123.0;
  c.in.k = k;
  return c;
}

TEST(Camera, PinholeEq521) {
  const CameraModel c = test_camera();
  // The optical axis lands on the principal point.
  const Vec2 p = *c.project(c.frame.t);
  EXPECT_NEAR(p.x(), 126.5, 1e-9);
  EXPECT_NEAR(p.y(), 123.0, 1e-9);
  // A direction tilted towards u by atan(0.1) moves fu * 0.1 pixels along the columns.
  const Vec2 q = *c.project(c.frame.t + 0.1 * c.frame.u);
  EXPECT_NEAR(q.x(), 126.5 + 20.0, 1e-9);
  EXPECT_NEAR(q.y(), 123.0, 1e-9);
  EXPECT_FALSE(c.project(-c.frame.t).has_value());
}

TEST(Camera, ProjectUnprojectRoundTripWithDistortion) {
  const CameraModel c = test_camera({-0.12, 0.03, 0.001, -0.002, 0.004});
  for (double x = 5; x < 250; x += 30)
    for (double y = 5; y < 250; y += 30) {
      const Vec3 w = c.unproject({x, y});
      EXPECT_NEAR(w.norm(), 1, 1e-12);
      const Vec2 back = *c.project(w);
      EXPECT_NEAR(back.x(), x, 1e-6);
      EXPECT_NEAR(back.y(), y, 1e-6);
    }
}

TEST(Camera, DistortionEq524to526) {
  const std::array<double, 5> k = {0.1, 0.01, 0.002, 0.003, 0.001};
  const Vec2 xy(0.3, -0.2);
  const double r2 = 0.13, p = 1 + 0.1 * r2 + 0.01 * r2 * r2 + 0.001 * r2 * r2 * r2;
  const Vec2 d = distort(k, xy);
  EXPECT_NEAR(d.x(), p * 0.3 + 2 * 0.003 * 0.3 * -0.2 + 0.002 * (r2 + 2 * 0.09), 1e-15);
  EXPECT_NEAR(d.y(), p * -0.2 + 2 * 0.002 * 0.3 * -0.2 + 0.003 * (r2 + 2 * 0.04), 1e-15);
}

TEST(Camera, SeesEq23) {
  CameraModel c = test_camera();
  c.in.aov = deg2rad(64);
  const Vec3 axis = c.frame.t;
  const Vec3 in = (axis + std::tan(deg2rad(31.9)) * c.frame.u).normalized();
  const Vec3 out = (axis + std::tan(deg2rad(32.1)) * c.frame.u).normalized();
  EXPECT_TRUE(c.sees(in));
  EXPECT_FALSE(c.sees(out));
}

TEST(Camera, FocalForAov) {
  EXPECT_NEAR(Intrinsics::focal_for_aov(250, deg2rad(90)), 125.0, 1e-9);
}

}  // namespace
}  // namespace omma
