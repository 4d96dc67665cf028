// Panorama output grids: which direction each output pixel looks at. Conventions: conventions.h,
// equations (G1) (longitude-latitude grids) and (G2) (vr180). Every panorama, scene lookup and
// hardware angle register derives its pixel <-> direction mapping from here.
#pragma once

#include <optional>
#include <string>

#include "omma/core/geometry.h"

namespace omma {

enum class Projection {
  kEquirect,      // 360 x 90 deg: phi 360..0 left to right (G1), theta 0 (dome axis) top .. 90 deg bottom
  kVr180,         // 180 x 180 deg half-equirectangular, dome axis (+z) at the centre, right=-x, up=+y (G2)
  kEquirectFull,  // 360 x 180 deg: theta 0 top .. 180 deg bottom (full-sphere rigs)
  kEquirect100    // 360 x 100 deg: theta 0 top .. 100 deg bottom (Giga-Eye, thesis Table 7.4)
};

// "equirect", "vr180", "equirect-full", "equirect-100"
Projection parse_projection(const std::string& name);

// The angles (radians) the grid's width and height span: equirect 2 pi x pi/2, vr180 pi x pi,
// equirect-full 2 pi x pi, equirect-100 2 pi x 100 deg.
struct AngularSpan {
  double width = 0, height = 0;
};
AngularSpan angular_span(Projection p);
std::string to_string(Projection p);

// (G1) for one row of a longitude-latitude grid W pixels wide: the azimuth phi in [0, 2 pi) that
// continuous pixel coordinate x looks at (phi = -2 pi x / W mod 2 pi: turning right decreases phi),
// and its inverse, x in [0, W).
double equirect_phi(double x, int width);
double equirect_x(double phi, int width);

struct PanoGrid {
  Projection projection = Projection::kVr180;
  int width = 1080;
  int height = 1080;

  // Unit direction at continuous pixel coordinate (x, y); pixel centres are at integer + 0.5.
  Vec3 direction(double x, double y) const;
  Vec3 pixel_direction(int col, int row) const { return direction(col + 0.5, row + 0.5); }
  // Continuous pixel coordinate of direction w, or nullopt if the grid does not contain w.
  std::optional<Vec2> pixel(const Vec3& w) const;
  // Solid angle of pixel (col,row) in steradians (for area-weighted statistics).
  double pixel_solid_angle(int col, int row) const;
};

// Parses "WxH" (e.g. "1080x1080"); throws std::invalid_argument with a clear message. The size must
// lie within core/limits.h's image bounds, or with banded = true within the bounds of a panorama
// rendered band by band (check_banded_size).
struct Size2 {
  int width = 0, height = 0;
};
Size2 parse_size(const std::string& text, bool banded = false);

}  // namespace omma
