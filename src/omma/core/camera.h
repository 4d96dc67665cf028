// The camera model: pinhole with radial and tangential distortion (thesis eq. 2.3, 5.21-5.26).
// Units: focal lengths and principal point in pixels, pixel centres at integer + 0.5
// (conventions.h); angle of view in radians inside the library, degrees in files.
#pragma once

#include <array>
#include <optional>

#include "omma/core/geometry.h"

namespace omma {

struct Intrinsics {
  int width = 250;         // pixels
  int height = 250;        // pixels
  double fu = 200;         // focal length along u (image x), pixels
  double fv = 200;         // focal length along v (image y), pixels
  double cu = 125;         // principal point, image x, pixels (pixel-centre convention)
  double cv = 125;         // principal point, image y, pixels
  std::array<double, 5> k{};  // k1, k2 radial; k3, k4 tangential; k5 radial (eq. 5.24-5.26)
  double aov = deg2rad(64);   // full angle of view of the camera cone, radians (eq. 2.3)

  bool has_distortion() const;
  // Focal length (pixels) that makes a centred W x H sensor's half-width see aov/2.
  static double focal_for_aov(int width, double aov);
};

// Normalised (undistorted) image-plane coordinates -> distorted normalised coordinates
// (eq. 5.23-5.26).
Vec2 distort(const std::array<double, 5>& k, const Vec2& xy);
// Inverse of distort by fixed-point iteration (converges for the mild distortion of real lenses).
Vec2 undistort(const std::array<double, 5>& k, const Vec2& xy_distorted, int iterations = 20);

struct CameraModel {
  Frame frame;
  Intrinsics in;

  // eq. 2.3: the direction lies inside the camera's cone of view.
  bool sees(const Vec3& w) const { return w.dot(frame.t) >= std::cos(in.aov / 2); }
  // eq. 5.21-5.26: continuous pixel coordinates (col, row) of direction w (need not be unit).
  // nullopt if w is behind the camera (w.t <= 0). Does NOT check the image bounds or the aov.
  std::optional<Vec2> project(const Vec3& w) const;
  // Is the continuous coordinate inside the image [0, W) x [0, H)?
  bool inside(const Vec2& px) const {
    return px.x() >= 0 && px.y() >= 0 && px.x() < in.width && px.y() < in.height;
  }
  // Unit direction (dome frame) of the ray through continuous pixel coordinate px.
  Vec3 unproject(const Vec2& px) const;
};

}  // namespace omma
