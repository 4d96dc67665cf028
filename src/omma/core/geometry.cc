#include "omma/core/geometry.h"

#include <algorithm>
#include <cmath>

namespace omma {

Vec3 direction_from_spherical(double theta, double phi) {
  const double s = std::sin(theta);
  return {s * std::cos(phi), s * std::sin(phi), std::cos(theta)};
}

Spherical spherical_from_direction(const Vec3& w) {
  Spherical s;
  const double rxy = std::hypot(w.x(), w.y());
  s.theta = std::atan2(rxy, w.z());
  s.phi = std::atan2(w.y(), w.x());
  if (s.phi < 0) s.phi += 2 * kPi;
  return s;
}

Mat3 Frame::dome_to_camera() const {
  Mat3 m;
  m.row(0) = t.transpose();
  m.row(1) = u.transpose();
  m.row(2) = v.transpose();
  return m;
}

Frame frame_from_ypr(const YawPitchRoll& a) {
  const Mat3 rx = Eigen::AngleAxisd(a.roll, Vec3::UnitX()).toRotationMatrix();
  const Mat3 ry = Eigen::AngleAxisd(a.pitch, Vec3::UnitY()).toRotationMatrix();
  const Mat3 rz = Eigen::AngleAxisd(a.yaw, Vec3::UnitZ()).toRotationMatrix();
  const Mat3 rt = rx * ry * rz;  // eq. 3.13d
  return Frame{rt.row(0).transpose(), rt.row(1).transpose(), rt.row(2).transpose()};
}

YawPitchRoll ypr_from_frame(const Frame& f) {
  // Rt = Rx(g) Ry(b) Rz(a) (eq. 3.13e): Rt(0,0)=cb ca, Rt(0,1)=-sa cb, Rt(0,2)=sb,
  // Rt(1,2)=-cb sg, Rt(2,2)=cb cg.
  const Mat3 rt = f.dome_to_camera();
  YawPitchRoll a;
  a.pitch = std::asin(std::clamp(rt(0, 2), -1.0, 1.0));
  const double cb = std::cos(a.pitch);
  if (cb > 1e-9) {
    a.yaw = std::atan2(-rt(0, 1), rt(0, 0));
    a.roll = std::atan2(-rt(1, 2), rt(2, 2));
  } else {
    // Gimbal lock: only yaw +/- roll is defined; put it all in yaw.
    a.roll = 0;
    a.yaw = std::atan2(rt(1, 0), rt(1, 1));
  }
  return a;
}

Frame frame_looking_at(const Vec3& t_in, const Vec3& down_hint) {
  Frame f;
  f.t = t_in.normalized();
  Vec3 v = down_hint - down_hint.dot(f.t) * f.t;
  if (v.norm() < 1e-9) {
    // Hint parallel to the axis: pick any perpendicular, stable choice.
    const Vec3 alt = std::abs(f.t.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
    v = alt - alt.dot(f.t) * f.t;
  }
  f.v = v.normalized();
  f.u = f.v.cross(f.t).normalized();  // v x t = u
  return f;
}

FrameError frame_error(const Frame& f) {
  FrameError e;
  e.max_norm_error = std::max({std::abs(f.t.norm() - 1), std::abs(f.u.norm() - 1), std::abs(f.v.norm() - 1)});
  e.max_dot = std::max({std::abs(f.t.dot(f.u)), std::abs(f.t.dot(f.v)), std::abs(f.u.dot(f.v))});
  e.handedness_error = (f.u.cross(f.v) - f.t).norm();
  return e;
}

double angle_between(const Vec3& a, const Vec3& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

}  // namespace omma
