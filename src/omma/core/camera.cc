#include "omma/core/camera.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>
#include <fmt/ranges.h>

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

namespace {

// The radial scale of eq. 5.24 as a function of s = r^2: 1 + k1 s + k2 s^2 + k5 s^3.
double radial_scale(const std::array<double, 5>& k, double s) {
  return 1 + s * (k[0] + s * (k[1] + s * k[4]));
}

// d r_d / d r of the radial mapping, as a function of s = r^2: 1 + 3 k1 s + 5 k2 s^2 + 7 k5 s^3.
double radial_slope(const std::array<double, 5>& k, double s) {
  return 1 + s * (3 * k[0] + s * (5 * k[1] + s * 7 * k[4]));
}

// Jacobian of distort (eq. 5.24-5.26) at xy: [dxd/dx dxd/dy; dyd/dx dyd/dy].
Eigen::Matrix2d distort_jacobian(const std::array<double, 5>& k, const Vec2& xy) {
  const double x = xy.x(), y = xy.y(), r2 = x * x + y * y;
  const double p = radial_scale(k, r2);
  const double q = 2 * k[0] + r2 * (4 * k[1] + r2 * 6 * k[4]);  // dp/dx = q x, dp/dy = q y
  Eigen::Matrix2d j;
  j << p + q * x * x + 2 * k[3] * y + 6 * k[2] * x, q * x * y + 2 * k[3] * x + 2 * k[2] * y,
      q * x * y + 2 * k[2] * y + 2 * k[3] * x, p + q * y * y + 2 * k[2] * x + 6 * k[3] * y;
  return j;
}

bool converged(const Vec2& err) { return err.squaredNorm() < 1e-20; }

// The undistorted radius r in [0, lim] with radial_distort(k, r) = rd, by bisection, for a radial
// mapping that increases on [0, lim] and exceeds rd at lim.
double radial_inverse(const std::array<double, 5>& k, double rd, double lim) {
  double lo = 0, hi = lim;
  for (int i = 0; i < 100 && hi - lo > 1e-15 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (radial_distort(k, mid) < rd ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// Newton's method on distort from `xy`, within radius `lim`, accepted only while it improves.
Vec2 newton(const std::array<double, 5>& k, const Vec2& xd, Vec2 xy, double lim) {
  double best = (distort(k, xy) - xd).norm();
  for (int i = 0; i < 30 && best > 1e-12; ++i) {
    const Eigen::Matrix2d j = distort_jacobian(k, xy);
    if (!(std::abs(j.determinant()) > 1e-12)) break;
    const Vec2 next = xy - j.inverse() * (distort(k, xy) - xd);
    const double e = (distort(k, next) - xd).norm();
    if (!(e < best) || !(next.norm() <= lim)) break;
    xy = next, best = e;
  }
  return xy;
}

// The robust inverse: Newton's method from `guess` (the fixed-point iteration's last iterate) if it
// gets there; else the radial mapping inverted by bisection on [0, fold] (where it increases), then
// Newton's method with the tangential terms from there.
Vec2 undistort_robust(const std::array<double, 5>& k, const Vec2& xd, const Vec2& guess) {
  const double rd = xd.norm();
  if (!(rd > 0)) return Vec2(0, 0);
  // The fold of the previous call's lens, kept per thread: consecutive calls are for one camera.
  thread_local std::array<double, 5> last_k{};
  thread_local double last_fold = std::numeric_limits<double>::infinity();
  if (k != last_k) last_k = k, last_fold = radial_fold(k);
  const double lim = std::min(last_fold, kMaxLensRadius);
  if (std::isfinite(guess.x()) && std::isfinite(guess.y()) && guess.norm() <= lim) {
    const Vec2 xy = newton(k, xd, guess, lim);
    if (converged(distort(k, xy) - xd)) return xy;
  }
  // Beyond the model's reach: the fold, in the point's own direction.
  const double r = radial_distort(k, lim) > rd ? radial_inverse(k, rd, lim) : lim;
  const Vec2 xy = xd * (r / rd);
  return k[2] == 0 && k[3] == 0 ? xy : newton(k, xd, xy, lim);
}

}  // namespace

double radial_distort(const std::array<double, 5>& k, double r) { return r * radial_scale(k, r * r); }

double radial_fold(const std::array<double, 5>& k) {
  if (k[0] >= 0 && k[1] >= 0 && k[4] >= 0) return std::numeric_limits<double>::infinity();
  // The slope is a cubic in s = r^2 with slope(0) = 1: march s geometrically up to the widest
  // radius (steps of 1 %), then bisect the first sign change.
  const double s_max = kMaxLensRadius * kMaxLensRadius;
  double prev = 0;
  for (double s = 1e-8; prev < s_max; prev = s, s = std::min(s * 1.01, s_max)) {
    if (radial_slope(k, s) > 0) {
      if (s >= s_max) break;
      continue;
    }
    double lo = prev, hi = s;
    for (int i = 0; i < 80; ++i) {
      const double mid = 0.5 * (lo + hi);
      (radial_slope(k, mid) > 0 ? lo : hi) = mid;
    }
    return std::sqrt(lo);
  }
  return std::numeric_limits<double>::infinity();
}

Vec2 undistort(const std::array<double, 5>& k, const Vec2& xd, int iterations) {
  // Fixed-point iteration x <- x - (distort(x) - xd): converges where the Jacobian of distort is
  // within (0, 2) of the identity, i.e. for the mild distortion of real lenses.
  Vec2 xy = xd;
  Vec2 err(1, 1);
  for (int i = 0; i < iterations; ++i) {
    err = distort(k, xy) - xd;
    xy -= err;
    if (converged(err)) break;
  }
  if (std::isfinite(xy.x()) && std::isfinite(xy.y()) && converged(err)) return xy;
  return undistort_robust(k, xd, xy);
}

std::string Intrinsics::lens_problem() const {
  if (!has_distortion()) return "";
  // The farthest image corner, in distorted normalised coordinates.
  double corner = 0;
  for (const double col : {0.0, double(width)})
    for (const double row : {0.0, double(height)})
      corner = std::max(corner, std::hypot((col - cu) / fu, (row - cv) / fv));
  const double fold = radial_fold(k);
  double reach;  // the undistorted radius the camera's field needs
  if (field == Field::kCone) {
    reach = std::tan(std::min(aov / 2, deg2rad(89.9)));
  } else {
    const double lim = std::min(fold, kMaxLensRadius);
    if (!(radial_distort(k, lim) > corner))
      return fmt::format(
          "the distortion k = [{}] folds back at {:.1f} deg from the axis, before reaching the image "
          "corner (the radial mapping r (1 + k1 r^2 + k2 r^4 + k5 r^6) must increase over the field)",
          fmt::join(k, ", "), rad2deg(std::atan(lim)));
    reach = radial_inverse(k, corner, lim);
  }
  if (fold <= reach)
    return fmt::format(
        "the distortion k = [{}] folds back at {:.1f} deg from the axis, inside the camera's field "
        "({:.1f} deg): the radial mapping r (1 + k1 r^2 + k2 r^4 + k5 r^6) must increase over the field",
        fmt::join(k, ", "), rad2deg(std::atan(fold)), rad2deg(std::atan(reach)));
  // The whole mapping, tangential terms included, one to one over the field: a positive Jacobian
  // (and a positive radial scale) on a polar grid of 48 radii x 96 angles.
  for (int i = 1; i <= 48; ++i)
    for (int a = 0; a < 96; ++a) {
      const double r = reach * i / 48, t = 2 * kPi * a / 96;
      const Vec2 xy(r * std::cos(t), r * std::sin(t));
      const Vec2 d = distort(k, xy);
      if (!(distort_jacobian(k, xy).determinant() > 0) || !(d.dot(xy) > 0))
        return fmt::format(
            "the distortion k = [{}] is not one to one at {:.1f} deg from the axis, inside the camera's "
            "field ({:.1f} deg): the tangential terms k3, k4 fold the image there",
            fmt::join(k, ", "), rad2deg(std::atan(r)), rad2deg(std::atan(reach)));
    }
  // kImage: directions past the field (where project() still accepts them: rising slope, positive
  // scale) must land outside the image, not fold back into it.
  if (field == Field::kImage)
    for (double r = reach; r < kMaxLensRadius; r *= 1.01) {
      const double s = r * r;
      if (radial_slope(k, s) > 0 && radial_scale(k, s) > 0 && radial_distort(k, r) < corner * (1 - 1e-9))
        return fmt::format(
            "the distortion k = [{}] maps directions at {:.1f} deg from the axis back into the image "
            "(the radial mapping falls and rises again past the image corner)",
            fmt::join(k, ", "), rad2deg(std::atan(r)));
    }
  return "";
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
  if (in.has_distortion()) {
    // Past the fold of the radial mapping (falling slope) or where it turns negative, the model
    // maps directions back into the image: not a lens, nothing seen there.
    const double s = xy.squaredNorm();
    if (!(radial_slope(in.k, s) > 0) || !(radial_scale(in.k, s) > 0)) return std::nullopt;
    xy = distort(in.k, xy);
  }
  return Vec2(in.cu + in.fu * xy.x(), in.cv + in.fv * xy.y());
}

Vec3 CameraModel::unproject(const Vec2& px) const {
  Vec2 xy((px.x() - in.cu) / in.fu, (px.y() - in.cv) / in.fv);
  if (in.has_distortion()) xy = undistort(in.k, xy);
  return (frame.t + xy.x() * frame.u + xy.y() * frame.v).normalized();
}

}  // namespace omma
