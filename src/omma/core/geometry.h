// Directions, spherical angles and rotations. Conventions: see conventions.h.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "omma/core/conventions.h"

namespace omma {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

// eq. 5.15: unit direction from polar angle theta (from +z) and azimuth phi (from +x), radians.
Vec3 direction_from_spherical(double theta, double phi);

struct Spherical {
  double theta = 0;  // polar angle from +z, radians, [0, pi]
  double phi = 0;    // azimuth from +x towards +y, radians, [0, 2 pi)
};
// Inverse of direction_from_spherical; w need not be normalised (must be non-zero).
Spherical spherical_from_direction(const Vec3& w);

// Camera orientation frame (t, u, v), see conventions.h.
struct Frame {
  Vec3 t = Vec3::UnitX();  // optical axis
  Vec3 u = Vec3::UnitY();  // image +x (columns)
  Vec3 v = Vec3::UnitZ();  // image +y (rows)
  // Rows t, u, v: maps dome coordinates to camera coordinates (t-, u-, v-components).
  Mat3 dome_to_camera() const;
};

struct YawPitchRoll {
  double yaw = 0, pitch = 0, roll = 0;  // alpha, beta, gamma of eq. 3.13, radians
};

// eq. 3.13: Rt = Rx(roll) Ry(pitch) Rz(yaw); t, u, v are the rows of Rt.
Frame frame_from_ypr(const YawPitchRoll& ypr);
// Inverse of frame_from_ypr (pitch in [-pi/2, pi/2]; at gimbal lock roll is set to 0).
YawPitchRoll ypr_from_frame(const Frame& f);

// A camera frame looking along t with image +y ("down") as close as possible to `down_hint`
// (projected onto the plane normal to t). If the hint is parallel to t a fallback is used.
Frame frame_looking_at(const Vec3& t, const Vec3& down_hint);

// Orthonormality errors: max |dot| between distinct axes, max ||axis| - 1|, and | (u x v) - t |.
struct FrameError {
  double max_norm_error = 0;
  double max_dot = 0;
  double handedness_error = 0;
};
FrameError frame_error(const Frame& f);

// Angle between two (not necessarily unit) vectors, radians, numerically stable.
double angle_between(const Vec3& a, const Vec3& b);

}  // namespace omma
