#include "omma/core/photometric.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Dense>
#include <fmt/format.h>

namespace omma {

bool Photometric::is_identity() const {
  return vignetting == std::array<double, 3>{0, 0, 0} && center_px.isZero(0) &&
         gains == std::array<double, 3>{1, 1, 1};
}

bool Photometric::operator==(const Photometric& o) const {
  return vignetting == o.vignetting && center_px == o.center_px && gains == o.gains;
}

double vignetting_radius(const Photometric& p, int width, int height, double col, double row) {
  const double hw = 0.5 * width, hh = 0.5 * height;
  const double dx = col - (hw + p.center_px.x()), dy = row - (hh + p.center_px.y());
  return std::sqrt((dx * dx + dy * dy) / (hw * hw + hh * hh));
}

namespace {
// V as the cubic in s = r^2.
double falloff_s(const Photometric& p, double s) {
  return 1 + s * (p.vignetting[0] + s * (p.vignetting[1] + s * p.vignetting[2]));
}
}  // namespace

double vignetting_falloff(const Photometric& p, int width, int height, double col, double row) {
  const double r = vignetting_radius(p, width, height, col, row);
  return falloff_s(p, r * r);
}

double min_vignetting_falloff(const Photometric& p, int width, int height) {
  // The range of s = r^2 over the image rectangle [0, W] x [0, H]: the nearest point of the
  // rectangle to the centre and the farthest corner.
  const double hw = 0.5 * width, hh = 0.5 * height, n2 = hw * hw + hh * hh;
  const double cx = hw + p.center_px.x(), cy = hh + p.center_px.y();
  const double nx = std::clamp(cx, 0.0, double(width)) - cx, ny = std::clamp(cy, 0.0, double(height)) - cy;
  const double fx = std::max(cx, width - cx), fy = std::max(cy, height - cy);
  const double s0 = (nx * nx + ny * ny) / n2, s1 = (fx * fx + fy * fy) / n2;
  double lo = std::min(falloff_s(p, s0), falloff_s(p, s1));
  // Interior critical points: dV/ds = b + 2 c s + 3 d s^2 = 0.
  const double b = p.vignetting[0], c = p.vignetting[1], d = p.vignetting[2];
  auto consider = [&](double s) {
    if (s > s0 && s < s1) lo = std::min(lo, falloff_s(p, s));
  };
  if (std::abs(d) > 1e-15) {
    const double disc = 4 * c * c - 12 * d * b;
    if (disc >= 0) {
      consider((-2 * c + std::sqrt(disc)) / (6 * d));
      consider((-2 * c - std::sqrt(disc)) / (6 * d));
    }
  } else if (std::abs(c) > 1e-15) {
    consider(-b / (2 * c));
  }
  return lo;
}

std::array<double, 3> fit_vignetting(const std::vector<double>& s, const std::vector<double>& v,
                                     double* max_rel_error) {
  if (s.size() != v.size() || s.size() < 3)
    throw std::invalid_argument("fit_vignetting: need >= 3 samples (s, v)");
  const Eigen::Index n = static_cast<Eigen::Index>(s.size());
  // Relative residual (1 + b s + c s^2 + d s^3) / v - 1: linear in (b, c, d) with rows s^k / v.
  Eigen::MatrixXd a(n, 3);
  Eigen::VectorXd y(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double si = s[size_t(i)], vi = v[size_t(i)];
    if (!(vi > 0)) throw std::invalid_argument("fit_vignetting: falloff samples must be positive");
    a(i, 0) = si / vi, a(i, 1) = si * si / vi, a(i, 2) = si * si * si / vi;
    y(i) = 1 - 1 / vi;
  }
  Eigen::VectorXd w = Eigen::VectorXd::Constant(n, 1.0 / double(n)), x(3);
  double worst = 0;
  for (int it = 0; it < 60; ++it) {
    const Eigen::VectorXd sw = w.cwiseSqrt();
    x = (sw.asDiagonal() * a).colPivHouseholderQr().solve(sw.asDiagonal() * y);
    const Eigen::VectorXd e = (a * x - y).cwiseAbs();
    worst = e.maxCoeff();
    // Lawson's update: weights grow where the error is large.
    w = w.cwiseProduct(e.cwiseMax(1e-15));
    const double total = w.sum();
    if (!(total > 0)) break;
    w /= total;
  }
  if (max_rel_error) *max_rel_error = worst;
  return {x[0], x[1], x[2]};
}

void validate_photometric(const Photometric& p, int width, int height, const std::string& where) {
  for (double v : p.vignetting)
    if (!std::isfinite(v))
      throw std::invalid_argument(where + ": photometric vignetting coefficient is not finite");
  if (!p.center_px.allFinite())
    throw std::invalid_argument(where + ": photometric vignetting centre is not finite");
  for (double g : p.gains)
    if (!std::isfinite(g) || g <= 0)
      throw std::invalid_argument(fmt::format("{}: photometric gain {} must be a positive number", where, g));
  if (width <= 0 || height <= 0)
    throw std::invalid_argument(where + ": photometric model needs a positive image size");
  if (std::abs(p.center_px.x()) > width || std::abs(p.center_px.y()) > height)
    throw std::invalid_argument(
        fmt::format("{}: photometric vignetting centre offset ({}, {}) px lies beyond the image", where,
                    p.center_px.x(), p.center_px.y()));
  const double lo = min_vignetting_falloff(p, width, height);
  if (!(lo > 0.02))
    throw std::invalid_argument(
        fmt::format("{}: photometric vignetting polynomial (b={}, c={}, d={}) falls to {:.3g} inside the "
                    "image (must stay above "
                    "0.02: a falloff that reaches zero cannot be corrected)",
                    where, p.vignetting[0], p.vignetting[1], p.vignetting[2], lo));
  // The largest V: the polynomial must not blow up either (a correction gain below 1/50).
  Photometric neg = p;
  for (double& v : neg.vignetting) v = -v;
  const double hi = 2 - min_vignetting_falloff(neg, width, height);  // max V = 2 - min(2 - V)
  if (hi > 50)
    throw std::invalid_argument(
        fmt::format("{}: photometric vignetting polynomial reaches {:.3g} inside the image "
                    "(at most 50)",
                    where, hi));
}

}  // namespace omma
