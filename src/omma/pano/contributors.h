// Camera search and projection for one panorama direction (thesis eq. 2.3, 2.5, 5.19-5.26), on a
// projection surface at distance D (surface.h).
// Frames: dome frame, mm (conventions.h). Pixel coordinates: continuous, centres at integer + 0.5.
//
// Projection surface. The thesis samples every camera along the panorama direction w itself
// (eq. 2.4: w projected onto each camera's t, u, v), i.e. it assumes the scene is at infinity. Here
// the panorama direction w from the observer q meets the scene at the distance D(w) (mm):
//     X = q + D w                                     (the scene point of direction w)
//     w_i = (X - c_i) / |X - c_i|                      (the ray of camera i, centre c_i, towards X)
// and camera i is searched (eq. 2.3 on w_i: w_i.t_i >= cos(aov/2)) and sampled (eq. 5.21-5.26 on
// w_i) along its own ray. With s = 1/D the unnormalised ray is w + s (q - c_i), linear in s, so
// D = +infinity (s = 0) gives w_i = w: exactly the thesis's model, bit for bit (the code takes w
// itself). In camera i's frame (t, u, v), with b = q - c_i:
//     x = (w.u + s b.u) / (w.t + s b.t),   y = (w.v + s b.v) / (w.t + s b.t)        (eq. 2.4, 5.21)
// which is what the engine's depth-adaptive renderer evaluates per tap (render/depth_render.h).
// The weights keep the thesis's orthographic distance |r_i| (eq. 2.5): the distance of camera i's
// centre from the observer's ray q + t w, which does not depend on D (how far camera i's viewpoint
// is from the observer's, i.e. how much parallax it adds where D is wrong).
#pragma once

#include <limits>
#include <string>
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
  Vec3 q = Vec3::Zero();   // observer point (virtual viewpoint), mm; the dome centre by default
  double min_r_mm = 1e-6;  // |r| is clamped below by this (cameras at the observer point)

  // False (with the reason in *why) when a value lies outside the range the code relies on.
  bool IsValid(std::string* why = nullptr) const;
};

// Every camera that sees w (eq. 2.3: w.t >= cos(aov/2)) and whose projection of w lands inside
// its image, in rig order (the scene at infinity).
std::vector<Contributor> find_contributors(const Rig& rig, const Vec3& w, const SearchOptions& opt = {});
// The same on the projection surface at distance depth_mm along w from opt.q (see the file
// comment): every camera that sees the point X = q + D w (eq. 2.3 on its own ray w_i) with X
// projecting inside its image; px is X's pixel. depth_mm = +infinity is the call above exactly.
std::vector<Contributor> find_contributors(const Rig& rig, const Vec3& w, double depth_mm,
                                           const SearchOptions& opt = {});

// Camera i's ray towards the surface point of w at distance depth_mm from q (unnormalised;
// w itself when depth_mm is +infinity).
inline Vec3 surface_ray(const Vec3& q, const Vec3& camera_centre, const Vec3& w, double depth_mm) {
  if (!(depth_mm < std::numeric_limits<double>::infinity())) return w;
  return w + (q - camera_centre) / depth_mm;  // (q + D w - c) / D
}

// eq. 2.5 / 5.19: r = (q - c) - ((q - c).w) w, for camera centre c.
double orthographic_distance(const Vec3& q, const Vec3& camera_centre, const Vec3& w);

}  // namespace omma::pano
