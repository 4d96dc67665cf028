#include "omma/core/grid.h"

#include <cmath>

#include <gtest/gtest.h>

namespace omma {
namespace {

TEST(Grid, Vr180CentreIsDomeAxis) {
  PanoGrid g{Projection::kVr180, 1080, 1080};
  EXPECT_NEAR((g.direction(540, 540) - Vec3::UnitZ()).norm(), 0, 1e-12);
  EXPECT_NEAR((g.direction(1080, 540) + Vec3::UnitX()).norm(), 0, 1e-12);  // right edge = -x (G2)
  EXPECT_NEAR((g.direction(0, 540) - Vec3::UnitX()).norm(), 0, 1e-12);     // left edge = +x
  EXPECT_NEAR((g.direction(540, 0) - Vec3::UnitY()).norm(), 0, 1e-12);     // top edge = +y
}

TEST(Grid, EquirectTopRowIsDomeAxis) {
  PanoGrid g{Projection::kEquirect, 1920, 512};
  EXPECT_NEAR(g.direction(100, 0).z(), 1.0, 1e-12);
  EXPECT_NEAR(g.direction(0, 512).z(), 0.0, 1e-12);
  EXPECT_NEAR((g.direction(0, 512) - Vec3::UnitX()).norm(), 0, 1e-12);    // left edge = +x (G1)
  EXPECT_NEAR((g.direction(960, 512) + Vec3::UnitX()).norm(), 0, 1e-12);  // centre = -x
  EXPECT_NEAR((g.direction(480, 512) + Vec3::UnitY()).norm(), 0, 1e-12);  // a quarter turn right = -y
}

// conventions.h: a panorama is the world as seen by a person at the rig's centre. Wherever that
// person looks (f, with "up" h the image's up there), the image's right is their right, f x h, and
// never their left: the grids are not mirrored.
TEST(Grid, ImageRightIsTheViewersRightInEveryProjection) {
  for (Projection p :
       {Projection::kVr180, Projection::kEquirect, Projection::kEquirectFull, Projection::kEquirect100}) {
    const PanoGrid g{p, 720, 360};
    int checked = 0;
    for (int r = 10; r < 350; r += 20)
      for (int c = 5; c < 715; c += 30) {
        const double x = c + 0.5, y = r + 0.5, e = 1e-3;
        const Vec3 f = g.direction(x, y);
        const Vec3 up = (g.direction(x, y - e) - g.direction(x, y + e)).normalized();
        const Vec3 right = (g.direction(x + e, y) - g.direction(x - e, y)).normalized();
        EXPECT_GT(right.dot(f.cross(up)), 0.999) << to_string(p) << " at " << c << "," << r;
        ++checked;
      }
    EXPECT_GT(checked, 300);
  }
}

TEST(Grid, EquirectLongitudeFunctionsAreInverse) {
  for (int w : {1, 360, 1920})
    for (double x : {0.0, 0.25, 0.5, 17.3, w - 0.5, w - 1e-9}) {
      if (x >= w) continue;
      const double phi = equirect_phi(x, w);
      EXPECT_GE(phi, 0);
      EXPECT_LT(phi, 2 * kPi);
      const double back = equirect_x(phi, w);
      EXPECT_GE(back, 0);
      EXPECT_LT(back, w);
      EXPECT_NEAR(std::remainder(back - x, double(w)), 0, 1e-6) << w << " " << x;
    }
  EXPECT_NEAR(equirect_phi(0.25 * 360, 360), 1.5 * kPi, 1e-12);  // a quarter of the way: phi = 270 deg
}

TEST(Grid, RoundTripAllProjections) {
  for (Projection p :
       {Projection::kVr180, Projection::kEquirect, Projection::kEquirectFull, Projection::kEquirect100}) {
    PanoGrid g{p, 640, 320};
    for (int r = 3; r < 320; r += 37)
      for (int c = 2; c < 640; c += 41) {
        const Vec3 w = g.pixel_direction(c, r);
        const auto px = g.pixel(w);
        ASSERT_TRUE(px.has_value()) << to_string(p);
        EXPECT_NEAR(px->x(), c + 0.5, 1e-9) << to_string(p);
        EXPECT_NEAR(px->y(), r + 0.5, 1e-9) << to_string(p);
      }
  }
}

TEST(Grid, SolidAnglesSumToTheField) {
  PanoGrid half{Projection::kEquirect, 360, 90};
  PanoGrid vr{Projection::kVr180, 200, 200};
  double a = 0, b = 0;
  for (int r = 0; r < 90; ++r)
    for (int c = 0; c < 360; ++c) a += half.pixel_solid_angle(c, r);
  for (int r = 0; r < 200; ++r)
    for (int c = 0; c < 200; ++c) b += vr.pixel_solid_angle(c, r);
  EXPECT_NEAR(a, 2 * kPi, 1e-9);  // hemisphere
  EXPECT_NEAR(b, 2 * kPi, 1e-9);
}

TEST(Grid, Equirect100SpansPolar0To100Degrees) {
  // Table 7.4: 360 x 100 deg; 9000 x 2400 keeps 25 x 24 px per degree.
  const PanoGrid g{parse_projection("equirect-100"), 9000, 2400};
  EXPECT_EQ(to_string(g.projection), "equirect-100");
  EXPECT_NEAR(rad2deg(spherical_from_direction(g.direction(0, 2400)).theta), 100, 1e-9);
  EXPECT_NEAR(rad2deg(spherical_from_direction(g.direction(4500, 1200)).theta), 50, 1e-9);
  EXPECT_FALSE(g.pixel(direction_from_spherical(deg2rad(100.5), 1.0)).has_value());
  double a = 0;
  const PanoGrid small{Projection::kEquirect100, 90, 50};
  for (int r = 0; r < 50; ++r)
    for (int c = 0; c < 90; ++c) a += small.pixel_solid_angle(c, r);
  EXPECT_NEAR(a, 2 * kPi * (1 - std::cos(deg2rad(100))), 1e-9);
}

TEST(Grid, ParseSize) {
  EXPECT_EQ(parse_size("1920x512").width, 1920);
  EXPECT_EQ(parse_size("1920x512").height, 512);
  EXPECT_THROW(parse_size("1920"), std::invalid_argument);
  EXPECT_THROW(parse_size("-3x4"), std::invalid_argument);
  EXPECT_THROW(parse_size("3x4junk"), std::invalid_argument);
  // Bounded (core/limits.h): 16384 a side and 2^28 pixels; no wrap-around of huge numbers.
  EXPECT_EQ(parse_size("16384x16384").width, 16384);
  EXPECT_THROW(parse_size("65536x65536"), std::invalid_argument);
  EXPECT_THROW(parse_size("16385x2"), std::invalid_argument);
  EXPECT_THROW(parse_size("4294967546x250"), std::invalid_argument);
  EXPECT_THROW(parse_size("0x250"), std::invalid_argument);
  EXPECT_THROW(parse_size("x250"), std::invalid_argument);
  EXPECT_THROW(parse_size("+3x4"), std::invalid_argument);
  EXPECT_THROW(parse_projection("fisheye"), std::invalid_argument);
}

}  // namespace
}  // namespace omma
