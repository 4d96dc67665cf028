#include "omma/core/camera.h"

#include <cmath>

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

// The radial mapping of eq. 5.24, r (1 + k1 r^2), stops increasing where 1 + 3 k1 r^2 = 0.
TEST(Camera, RadialFoldOfBarrelDistortion) {
  EXPECT_NEAR(radial_fold({-0.3, 0, 0, 0, 0}), std::sqrt(1 / 0.9), 1e-9);
  EXPECT_TRUE(std::isinf(radial_fold({2.5, 0, 0, 0, 0})));
  EXPECT_TRUE(std::isinf(radial_fold({})));
  // k1 < 0 held back by k2 > 0: 1 - 0.9 s + 0.25 s^2 has no real root.
  EXPECT_TRUE(std::isinf(radial_fold({-0.3, 0.05, 0, 0, 0})));
}

// Strong lenses that the fixed-point inverse cannot follow: k1 >= 2 (its iteration diverges) and
// k1 = -0.3 near its fold. The inverse stays finite and exact wherever the mapping has one.
TEST(Camera, UndistortStrongLensesIsExactAndFinite) {
  for (const std::array<double, 5> k : {std::array<double, 5>{2.5, 0, 0, 0, 0},
                                        {-0.3, 0, 0, 0, 0},
                                        {10, 3, 0.01, -0.02, 1},
                                        {-0.3, 0, 0.02, 0.01, 0}}) {
    // Up to near the fold (nearer for tangential terms, which fold the image sooner on one side).
    const double reach = std::isinf(radial_fold(k)) ? 3.0 : (k[2] == 0 ? 0.98 : 0.8) * radial_fold(k);
    double worst = 0;
    for (double r = 0.01; r < reach; r += reach / 40)
      for (double t = 0; t < 6.28; t += 0.5) {
        const Vec2 xy(r * std::cos(t), r * std::sin(t));
        const Vec2 back = undistort(k, distort(k, xy));
        ASSERT_TRUE(std::isfinite(back.x()) && std::isfinite(back.y()));
        worst = std::max(worst, (back - xy).norm());
      }
    EXPECT_LT(worst, 1e-8) << "k = " << k[0] << " " << k[1] << " " << k[2] << " " << k[3] << " " << k[4];
  }
  // Beyond the fold (r_d > 0.703 for k1 = -0.3) there is no inverse: the fold, in the same direction.
  const std::array<double, 5> barrel{-0.3, 0, 0, 0, 0};
  const Vec2 far = undistort(barrel, Vec2(0.6, 0.6));
  EXPECT_NEAR(far.norm(), radial_fold(barrel), 1e-9);
  EXPECT_NEAR(far.x(), far.y(), 1e-12);
}

TEST(Camera, LensProblemChecksTheFieldIsOneToOne) {
  CameraModel c = test_camera({-0.3, 0, 0, 0, 0});
  c.in.aov = deg2rad(64);  // tan 32 deg = 0.62 < the fold at 1.05 (46.5 deg)
  EXPECT_EQ(c.in.lens_problem(), "");
  c.in.aov = deg2rad(120);  // tan 60 deg = 1.73: the cone reaches past the fold
  EXPECT_NE(c.in.lens_problem().find("folds back at 46.5 deg"), std::string::npos) << c.in.lens_problem();
  c.in.field = Intrinsics::Field::kImage;  // the corners (r_d 0.89) lie beyond r_d's maximum 0.70
  EXPECT_NE(c.in.lens_problem().find("before reaching the image corner"), std::string::npos);
  c.in.k = {-0.05, 0, 0, 0, 0};  // a real lens: monotonic far past the corners
  EXPECT_EQ(c.in.lens_problem(), "");
  c.in.k = {0, 0, 0.8, 0, 0};  // tangential terms that fold the image
  c.in.field = Intrinsics::Field::kCone;
  c.in.aov = deg2rad(64);
  EXPECT_NE(c.in.lens_problem().find("not one to one"), std::string::npos) << c.in.lens_problem();
  // Falls, then rises again into the image: k5 > 0 turns r_d back up past the fold.
  // r_d rises to 0.39 at the fold (34 deg), falls to 0.30 (45 deg), then rises again.
  c.in.k = {-1, 0, 0, 0, 0.3};
  c.in.field = Intrinsics::Field::kImage;
  c.in.fu = c.in.fv = 510;  // the corners at r_d 0.35: reached before the fold
  EXPECT_NE(c.in.lens_problem().find("back into the image"), std::string::npos) << c.in.lens_problem();
}

// project() sees nothing where the radial mapping falls: those directions would land back inside.
TEST(Camera, ProjectRefusesDirectionsPastTheFold) {
  const CameraModel c = test_camera({-0.3, 0, 0, 0, 0});
  EXPECT_TRUE(c.project(c.frame.t + 1.0 * c.frame.u).has_value());   // 45 deg, before the fold
  EXPECT_FALSE(c.project(c.frame.t + 1.5 * c.frame.u).has_value());  // 56 deg, past it
  // A corner pixel beyond the lens's reach unprojects to the fold direction, finite.
  const Vec3 w = c.unproject({0, 0});
  EXPECT_NEAR(rad2deg(std::acos(w.dot(c.frame.t))), rad2deg(std::atan(radial_fold(c.in.k))), 1e-6);
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
