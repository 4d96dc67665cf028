#include "omma/core/grid.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace omma {
namespace {
// Polar span of the equirectangular grids (radians).
double theta_span(Projection p) {
  switch (p) {
    case Projection::kEquirect: return kPi / 2;
    case Projection::kEquirectFull: return kPi;
    case Projection::kEquirect100: return deg2rad(100);
    case Projection::kVr180: break;
  }
  return 0;
}
}  // namespace

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
    case Projection::kEquirect: return "equirect";
    case Projection::kVr180: return "vr180";
    case Projection::kEquirectFull: return "equirect-full";
    case Projection::kEquirect100: return "equirect-100";
  }
  return "?";
}

Vec3 PanoGrid::direction(double x, double y) const {
  switch (projection) {
    case Projection::kEquirect:
    case Projection::kEquirectFull:
    case Projection::kEquirect100: {
      const double span = theta_span(projection);
      const double phi = x / width * 2 * kPi;
      const double theta = y / height * span;
      return direction_from_spherical(theta, phi);
    }
    case Projection::kVr180: {
      const double lon = x / width * kPi - kPi / 2;   // -90..90 deg, towards +x
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
      const double span = theta_span(projection);
      const Spherical s = spherical_from_direction(w);
      if (s.theta > span) return std::nullopt;
      return Vec2(s.phi / (2 * kPi) * width, s.theta / span * height);
    }
    case Projection::kVr180: {
      if (w.z() < 0) return std::nullopt;
      const double lat = std::asin(std::clamp(w.y(), -1.0, 1.0));
      const double lon = std::atan2(w.x(), w.z());
      return Vec2((lon + kPi / 2) / kPi * width, (kPi / 2 - lat) / kPi * height);
    }
  }
  return std::nullopt;
}

double PanoGrid::pixel_solid_angle(int col, int row) const {
  switch (projection) {
    case Projection::kEquirect:
    case Projection::kEquirectFull:
    case Projection::kEquirect100: {
      const double span = theta_span(projection);
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

Size2 parse_size(const std::string& text) {
  Size2 s;
  char x = 0;
  char extra = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &s.width, &x, &s.height, &extra) != 3 ||
      (x != 'x' && x != 'X') || s.width <= 0 || s.height <= 0 || s.width > 65536 || s.height > 65536)
    throw std::invalid_argument("size '" + text + "' must be WxH with positive integers, e.g. 1080x1080");
  return s;
}

}  // namespace omma
