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

// A Giga-Eye-like camera: 2592 x 1944, 53 x 43 deg through the image centre (thesis ch. 7).
CameraModel rectangular_camera() {
  CameraModel c;
  c.frame = frame_looking_at(Vec3(0.3, 0.1, 0.2), Vec3::UnitZ());
  c.in.width = 2592;
  c.in.height = 1944;
  c.in.fu = 1296 / std::tan(deg2rad(26.5));
  c.in.fv = 972 / std::tan(deg2rad(21.5));
  c.in.cu = 1296;
  c.in.cv = 972;
  c.in.field = Intrinsics::Field::kImage;
  c.in.aov = c.in.bounding_aov();
  return c;
}

TEST(Camera, SeesImageFieldUsesTheImageBounds) {
  const CameraModel c = rectangular_camera();
  const Frame& f = c.frame;
  auto dir = [&](double along_u_deg, double along_v_deg) {
    return (f.t + std::tan(deg2rad(along_u_deg)) * f.u + std::tan(deg2rad(along_v_deg)) * f.v).normalized();
  };
  EXPECT_TRUE(c.sees(dir(26.4, 0)));
  EXPECT_FALSE(c.sees(dir(26.6, 0)));
  EXPECT_TRUE(c.sees(dir(0, -21.4)));
  EXPECT_FALSE(c.sees(dir(0, 21.6)));
  // Near the corner: inside the image, although 31.8 deg off the axis (a 53 deg cone misses it)...
  EXPECT_TRUE(c.sees(dir(26.0, 21.0)));
  EXPECT_GT(rad2deg(angle_between(dir(26.0, 21.0), f.t)), 31.5);
  // ...and the same camera as a cone of 53 deg misses it, but sees 26 deg along v, off the image.
  CameraModel cone = c;
  cone.in.field = Intrinsics::Field::kCone;
  cone.in.aov = deg2rad(53);
  EXPECT_FALSE(cone.sees(dir(26.0, 21.0)));
  EXPECT_TRUE(cone.sees(dir(0, 26.0)));
  EXPECT_FALSE(c.sees(dir(0, 26.0)));
  EXPECT_FALSE(c.sees(-f.t));
}

TEST(Camera, BoundingAovOfTheImage) {
  const CameraModel c = rectangular_camera();
  // No distortion: the corners are farthest, at atan(hypot(tan 26.5, tan 21.5)).
  const double corner = std::atan(std::hypot(std::tan(deg2rad(26.5)), std::tan(deg2rad(21.5))));
  EXPECT_NEAR(c.in.bounding_aov(), 2 * corner, 1e-12);
  EXPECT_NEAR(rad2deg(c.in.bounding_aov()), 64.86, 0.01);
  // Barrel distortion (k1 < 0) pulls the border inwards in the image: the border rays are wider.
  CameraModel d = c;
  d.in.k[0] = -0.05;
  EXPECT_GT(d.in.bounding_aov(), c.in.bounding_aov());
  EXPECT_EQ(parse_field("image"), Intrinsics::Field::kImage);
  EXPECT_EQ(to_string(Intrinsics::Field::kCone), "cone");
  EXPECT_THROW(parse_field("square"), std::invalid_argument);
}

TEST(Camera, FocalForAov) { EXPECT_NEAR(Intrinsics::focal_for_aov(250, deg2rad(90)), 125.0, 1e-9); }

}  // namespace
}  // namespace omma
