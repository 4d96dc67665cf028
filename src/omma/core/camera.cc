#include "omma/core/camera.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace omma {

bool Intrinsics::has_distortion() const {
  for (double x : k)
    if (x != 0) return true;
  return false;
}

double Intrinsics::focal_for_aov(int width, double aov) { return 0.5 * width / std::tan(aov / 2); }

double Intrinsics::bounding_aov() const {
  // Largest angle from the optical axis over the ray through every point of the border.
  double worst = 0;
  auto visit = [&](double col, double row) {
    Vec2 xy((col - cu) / fu, (row - cv) / fv);
    if (has_distortion()) xy = undistort(k, xy);
    worst = std::max(worst, std::atan(xy.norm()));
  };
  if (!has_distortion()) {  // a pinhole's farthest border points are its corners
    visit(0, 0), visit(width, 0), visit(0, height), visit(width, height);
    return 2 * worst;
  }
  for (int c = 0; c <= width; ++c) {
    visit(c, 0);
    visit(c, height);
  }
  for (int r = 0; r <= height; ++r) {
    visit(0, r);
    visit(width, r);
  }
  return 2 * worst;
}

Intrinsics::Field parse_field(const std::string& name) {
  if (name == "cone") return Intrinsics::Field::kCone;
  if (name == "image") return Intrinsics::Field::kImage;
  throw std::invalid_argument("unknown field of view '" + name + "' (use cone or image)");
}

std::string to_string(Intrinsics::Field f) { return f == Intrinsics::Field::kCone ? "cone" : "image"; }

Vec2 distort(const std::array<double, 5>& k, const Vec2& xy) {
  const double x = xy.x(), y = xy.y();
  const double r2 = x * x + y * y;                                        // eq. 5.23
  const double p = 1 + k[0] * r2 + k[1] * r2 * r2 + k[4] * r2 * r2 * r2;  // eq. 5.24
  return {p * x + 2 * k[3] * x * y + k[2] * (r2 + 2 * x * x),             // eq. 5.25
          p * y + 2 * k[2] * x * y + k[3] * (r2 + 2 * y * y)};            // eq. 5.26
}

Vec2 undistort(const std::array<double, 5>& k, const Vec2& xd, int iterations) {
  Vec2 xy = xd;
  for (int i = 0; i < iterations; ++i) {
    const Vec2 err = distort(k, xy) - xd;
    xy -= err;
    if (err.squaredNorm() < 1e-24) break;
  }
  return xy;
}

bool CameraModel::sees(const Vec3& w) const {
  if (in.field == Intrinsics::Field::kCone) return w.dot(frame.t) >= std::cos(in.aov / 2);  // eq. 2.3
  const auto px = project(w);
  return px && inside(*px);
}

std::optional<Vec2> CameraModel::project(const Vec3& w) const {
  const double wt = w.dot(frame.t);
  if (wt <= 1e-12) return std::nullopt;
  Vec2 xy(w.dot(frame.u) / wt, w.dot(frame.v) / wt);  // eq. 5.21-5.22 (normalised)
  if (in.has_distortion()) xy = distort(in.k, xy);
  return Vec2(in.cu + in.fu * xy.x(), in.cv + in.fv * xy.y());
}

Vec3 CameraModel::unproject(const Vec2& px) const {
  Vec2 xy((px.x() - in.cu) / in.fu, (px.y() - in.cv) / in.fv);
  if (in.has_distortion()) xy = undistort(in.k, xy);
  return (frame.t + xy.x() * frame.u + xy.y() * frame.v).normalized();
}

}  // namespace omma
