// Camera search and projection for one panorama direction (thesis eq. 2.3, 2.5, 5.19-5.26).
// Frames: dome frame, mm (conventions.h). Pixel coordinates: continuous, centres at integer + 0.5.
#pragma once

#include <vector>

#include "omma/core/rig.h"

namespace omma::pano {

struct Contributor {
  int camera = 0;  // index into rig.cameras (not the camera id)
  Vec2 px;         // continuous pixel coordinate of the direction in that camera (eq. 5.21-5.26)
  double r = 0;    // |r_i| (eq. 2.5): distance of the camera centre's projection onto the
                   // w-plane through the observer q, mm
};

struct SearchOptions {
  Vec3 q = Vec3::Zero();  // observer point (virtual viewpoint), mm; the dome centre by default
  double min_r_mm = 1e-6; // |r| is clamped below by this (cameras at the observer point)
};

// Every camera that sees w (eq. 2.3: w.t >= cos(aov/2)) and whose projection of w lands inside
// its image, in rig order.
std::vector<Contributor> find_contributors(const Rig& rig, const Vec3& w, const SearchOptions& opt = {});

// eq. 2.5 / 5.19: r = (q - c) - ((q - c).w) w, for camera centre c.
double orthographic_distance(const Vec3& q, const Vec3& camera_centre, const Vec3& w);

}  // namespace omma::pano
