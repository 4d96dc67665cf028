#include "omma/core/grid.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "omma/core/limits.h"

namespace omma {

AngularSpan angular_span(Projection p) {
  switch (p) {
    case Projection::kEquirect:
      return {2 * kPi, kPi / 2};
    case Projection::kVr180:
      return {kPi, kPi};
    case Projection::kEquirectFull:
      return {2 * kPi, kPi};
    case Projection::kEquirect100:
      return {2 * kPi, deg2rad(100)};
  }
  return {2 * kPi, kPi};
}

Projection parse_projection(const std::string& name) {
  if (name == "equirect") return Projection::kEquirect;
  if (name == "vr180") return Projection::kVr180;
  if (name == "equirect-full") return Projection::kEquirectFull;
  if (name == "equirect-100") return Projection::kEquirect100;
  throw std::invalid_argument("unknown projection '" + name +
                              "' (use equirect, vr180, equirect-full or equirect-100)");
}

std::string to_string(Projection p) {
  switch (p) {
    case Projection::kEquirect:
      return "equirect";
    case Projection::kVr180:
      return "vr180";
    case Projection::kEquirectFull:
      return "equirect-full";
    case Projection::kEquirect100:
      return "equirect-100";
  }
  return "?";
}

double equirect_phi(double x, int width) {
  // (G1): phi = -2 pi x / W, wrapped into [0, 2 pi).
  double phi = -x / width * 2 * kPi;
  phi -= 2 * kPi * std::floor(phi / (2 * kPi));
  return phi >= 2 * kPi ? 0.0 : phi;
}

double equirect_x(double phi, int width) {
  // Inverse of (G1), wrapped into [0, W).
  double x = -phi / (2 * kPi) * width;
  x -= width * std::floor(x / width);
  return x >= width ? 0.0 : x;
}

Vec3 PanoGrid::direction(double x, double y) const {
  switch (projection) {
    case Projection::kEquirect:
    case Projection::kEquirectFull:
    case Projection::kEquirect100: {
      const double theta = y / height * angular_span(projection).height;  // (G1)
      return direction_from_spherical(theta, equirect_phi(x, width));
    }
    case Projection::kVr180: {
      const double lon = kPi / 2 - x / width * kPi;   // (G2): +90 deg (+x) at the left .. -90 (-x)
      const double lat = kPi / 2 - y / height * kPi;  // +90 (top, +y) .. -90 deg
      const double c = std::cos(lat);
      return {c * std::sin(lon), std::sin(lat), c * std::cos(lon)};
    }
  }
  return Vec3::UnitZ();
}

std::optional<Vec2> PanoGrid::pixel(const Vec3& w_in) const {
  const Vec3 w = w_in.normalized();
  switch (projection) {
    case Projection::kEquirect:
    case Projection::kEquirectFull:
    case Projection::kEquirect100: {
      const double span = angular_span(projection).height;
      const Spherical s = spherical_from_direction(w);
      if (s.theta > span) return std::nullopt;
      return Vec2(equirect_x(s.phi, width), s.theta / span * height);
    }
    case Projection::kVr180: {
      if (w.z() < 0) return std::nullopt;
      const double lat = std::asin(std::clamp(w.y(), -1.0, 1.0));
      const double lon = std::atan2(w.x(), w.z());
      return Vec2((kPi / 2 - lon) / kPi * width, (kPi / 2 - lat) / kPi * height);
    }
  }
  return std::nullopt;
}

double PanoGrid::pixel_solid_angle(int col, int row) const {
  switch (projection) {
    case Projection::kEquirect:
    case Projection::kEquirectFull:
    case Projection::kEquirect100: {
      const double span = angular_span(projection).height;
      const double t0 = row * span / height, t1 = (row + 1) * span / height;
      return (2 * kPi / width) * (std::cos(t0) - std::cos(t1));
    }
    case Projection::kVr180: {
      const double l0 = kPi / 2 - row * kPi / height, l1 = kPi / 2 - (row + 1) * kPi / height;
      return (kPi / width) * (std::sin(l0) - std::sin(l1));
    }
  }
  return 0;
}

Size2 parse_size(const std::string& text, bool banded) {
  // W 'x' H, decimal digits only; the values are range-checked as 64-bit integers before narrowing.
  auto bad = [&] {
    return std::invalid_argument("size '" + text + "' must be WxH with positive integers, e.g. 1080x1080");
  };
  const size_t x = text.find_first_of("xX");
  if (x == std::string::npos) throw bad();
  auto number = [&](size_t from, size_t to) {
    if (from == to || to - from > 9) throw bad();
    int64_t v = 0;
    for (size_t i = from; i < to; ++i) {
      if (text[i] < '0' || text[i] > '9') throw bad();
      v = v * 10 + (text[i] - '0');
    }
    return v;
  };
  const int64_t w = number(0, x), h = number(x + 1, text.size());
  if (banded)
    check_banded_size(w, h, "size");
  else
    check_image_size(w, h, "size");
  return Size2{int(w), int(h)};
}

}  // namespace omma
