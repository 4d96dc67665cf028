// The camera model: pinhole with radial and tangential distortion (thesis eq. 2.3, 5.21-5.26).
// Units: focal lengths and principal point in pixels, pixel centres at integer + 0.5
// (conventions.h); angle of view in radians inside the library, degrees in files.
#pragma once

#include <array>
#include <optional>
#include <string>

#include "omma/core/geometry.h"

namespace omma {

struct Intrinsics {
  int width = 250;            // pixels
  int height = 250;           // pixels
  double fu = 200;            // focal length along u (image x), pixels
  double fv = 200;            // focal length along v (image y), pixels
  double cu = 125;            // principal point, image x, pixels (pixel-centre convention)
  double cv = 125;            // principal point, image y, pixels
  std::array<double, 5> k{};  // k1, k2 radial; k3, k4 tangential; k5 radial (eq. 5.24-5.26)
  double aov = deg2rad(64);   // full angle of view of the camera cone, radians (eq. 2.3)
  // Which directions the camera sees. kCone (the thesis's model, eq. 2.3, and the default of rig
  // files that do not say): the cone of full angle `aov` (clipped by the image bounds wherever the
  // cone pokes out of them). kImage: every direction that projects inside the image [0,W)x[0,H),
  // e.g. the 53 x 43 deg rectangle of a Giga-Eye camera (thesis ch. 7); `aov` is then only the
  // bounding cone (bounding_aov()), which culling code may use as a cheap superset.
  enum class Field { kCone, kImage };
  Field field = Field::kCone;

  bool has_distortion() const;
  // Focal length (pixels) that makes a centred W x H sensor's half-width see aov/2.
  static double focal_for_aov(int width, double aov);
  // Why the lens model cannot describe this camera, or "" if it can: the distortion (eq. 5.23-5.26)
  // must map the camera's field one to one, i.e. the radial mapping increases (radial_fold) and the
  // Jacobian of distort stays positive over the field's undistorted radius: tan(aov / 2) for kCone,
  // for kImage the radius at which the radial mapping reaches the image's farthest corner. For
  // kImage, directions past that radius must not map back inside it.
  std::string lens_problem() const;
  // Full angle of the smallest cone around the optical axis holding the whole image: twice the
  // largest angle between the axis and the ray through any point of the image border (sampled
  // every pixel along the border, so distortion is included).
  double bounding_aov() const;
};

Intrinsics::Field parse_field(const std::string& name);  // "cone" | "image"
std::string to_string(Intrinsics::Field f);

// Normalised (undistorted) image-plane coordinates -> distorted normalised coordinates
// (eq. 5.23-5.26).
Vec2 distort(const std::array<double, 5>& k, const Vec2& xy);
// Inverse of distort: fixed-point iteration (converges for the mild distortion of real lenses),
// else Newton's method on the monotonic part of the radial mapping. Always finite and bounded: a
// point beyond the lens model's reach (past the radius where the radial mapping folds back,
// radial_fold) comes back at the fold radius in its own direction.
Vec2 undistort(const std::array<double, 5>& k, const Vec2& xy_distorted, int iterations = 20);
// The radial mapping of eq. 5.24 (tangential terms aside): r_d(r) = r (1 + k1 r^2 + k2 r^4 + k5 r^6)
// for the undistorted normalised radius r = tan(angle from the axis).
double radial_distort(const std::array<double, 5>& k, double r);
// The smallest undistorted radius r > 0 where r_d(r) stops increasing (dr_d/dr <= 0): beyond it the
// model folds back and is not a lens. +infinity if r_d increases up to kMaxLensRadius.
double radial_fold(const std::array<double, 5>& k);
// tan(89.9 deg): the widest undistorted radius any lens check or inverse considers.
inline constexpr double kMaxLensRadius = 572.96;

struct CameraModel {
  Frame frame;
  Intrinsics in;

  // Does the camera see the unit direction w? kCone: w lies inside the cone of view (eq. 2.3).
  // kImage: w projects inside the image bounds (w need not be unit).
  bool sees(const Vec3& w) const;
  // eq. 5.21-5.26: continuous pixel coordinates (col, row) of direction w (need not be unit).
  // nullopt if w is behind the camera (w.t <= 0) or where the distortion folds back (the radial
  // mapping decreases or changes sign there: not a lens). Does NOT check the image bounds or the aov.
  std::optional<Vec2> project(const Vec3& w) const;
  // Is the continuous coordinate inside the image [0, W) x [0, H)?
  bool inside(const Vec2& px) const {
    return px.x() >= 0 && px.y() >= 0 && px.x() < in.width && px.y() < in.height;
  }
  // Unit direction (dome frame) of the ray through continuous pixel coordinate px.
  Vec3 unproject(const Vec2& px) const;
};

}  // namespace omma
