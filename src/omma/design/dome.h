// Building blocks shared by the dome designers: radial cameras on the dome surface and the
// geometric relation between a camera's angle of view, the dome radius and the overlap distance
// (thesis eq. 3.1-3.2). Units: mm, radians (conventions.h).
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "omma/core/rig.h"

namespace omma::design {

// Intrinsics of an ideal square camera (default 250 x 250 px, Table 3.1) whose focal length makes
// the centred sensor's half-width see aov/2 (Intrinsics::focal_for_aov); principal point centred.
Intrinsics ideal_intrinsics(double aov_rad, int width = 250, int height = 250);

// A camera looking radially outwards along the unit direction t, its pinhole on the dome surface
// at r_phys_mm * t. The image "down" (+v) points away from the pole (the projection of -z), so the
// pictures are upright for a dome standing on its rim; at the poles v falls back to a fixed axis.
RigCamera radial_camera(int id, const Vec3& t, double r_phys_mm, const Intrinsics& in);

// A rig of radial cameras with consecutive ids 0..n-1 (validated).
Rig radial_rig(const std::vector<Vec3>& axes, double r_phys_mm, const Intrinsics& in, bool sphere,
               const std::string& method, const std::string& name);

// eq. 3.2: half-angle beta (radians) between a camera's axis and the direction (from the dome
// centre) at which its cone of half-angle aov/2, apex on the dome at r_phys, meets the sphere of
// radius r_vir: beta = aov/2 - asin(r_phys / r_vir * sin(aov/2)). Seen from the dome centre a
// radial camera covers exactly the spherical cap of radius beta at distance r_vir.
// Returns a negative value when r_vir is too close (r_vir < r_phys * sin(aov/2) is clamped).
double reach_angle(double aov_rad, double r_phys_mm, double r_vir_mm);

// Inverse of reach_angle (eq. 3.1): the distance at which the reach is `beta`:
// r_vir = r_phys * sin(aov/2) / sin(aov/2 - beta); +infinity when beta >= aov/2.
double distance_for_reach(double aov_rad, double r_phys_mm, double beta_rad);

inline constexpr double kInfinity = std::numeric_limits<double>::infinity();

}  // namespace omma::design
