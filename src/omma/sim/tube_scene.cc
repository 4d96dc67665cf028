// The calibration tube and the flat-field target (declared in scene.h).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>

#include <fmt/format.h>

#include "omma/sim/scene.h"

namespace omma::sim {
namespace {

inline uint32_t hash2(int64_t a, int64_t b, uint32_t seed) {
  uint64_t h = static_cast<uint64_t>(a) * 0x9e3779b97f4a7c15ull ^
               static_cast<uint64_t>(b) * 0xc2b2ae3d27d4eb4full ^
               (uint64_t(seed) + 1) * 0x165667b19e3779f9ull;
  h ^= h >> 31;
  h *= 0xbf58476d1ce4e5b9ull;
  h ^= h >> 29;
  return static_cast<uint32_t>(h);
}

// Value noise in [0, 1] on a lattice of unit cells, smoothstep-interpolated; periodic in u with
// `period` cells when period > 0.
double value_noise(double u, double v, int64_t period, uint32_t seed) {
  const double fu = std::floor(u), fv = std::floor(v);
  const double a = u - fu, b = v - fv;
  const double su = a * a * (3 - 2 * a), sv = b * b * (3 - 2 * b);
  const int64_t iu = static_cast<int64_t>(fu), iv = static_cast<int64_t>(fv);
  auto lat = [&](int64_t x, int64_t y) {
    if (period > 0) x = ((x % period) + period) % period;
    return (hash2(x, y, seed) & 0xffffff) / double(0xffffff);
  };
  const double l0 = lat(iu, iv) + (lat(iu + 1, iv) - lat(iu, iv)) * su;
  const double l1 = lat(iu, iv + 1) + (lat(iu + 1, iv + 1) - lat(iu, iv + 1)) * su;
  return l0 + (l1 - l0) * sv;
}

class TubeScene final : public Scene {
 public:
  explicit TubeScene(const TubeParams& p) : p_(p) {
    if (!(p.diameter_mm > 2 * 5.5) || !std::isfinite(p.diameter_mm) || p.diameter_mm > 1000)
      throw SceneError(fmt::format(
          "tube scene: diameter must be 11..1000 mm (the dome has a 5 mm radius), got {}", p.diameter_mm));
    if (!(p.length_mm > 0 && p.length_mm <= kMaxSceneMm) || !(p.back_mm > 0 && p.back_mm <= kMaxSceneMm) ||
        !(p.brightness > 0 && p.brightness <= kMaxSceneLevel))
      throw SceneError(fmt::format("tube scene: length and back must be in (0, {}] mm, brightness in (0, {}]",
                                   kMaxSceneMm, kMaxSceneLevel));
    radius_ = p.diameter_mm / 2;
    circumference_ = 2 * kPi * radius_;
  }

  cv::Vec3f radiance(const Vec3& o, const Vec3& d, const Vec3&) const override {
    // Wall: |o_xy + s d_xy| = R, the far root (the ray starts inside).
    const double a = d.x() * d.x() + d.y() * d.y();
    const double b = o.x() * d.x() + o.y() * d.y();
    const double c = o.x() * o.x() + o.y() * o.y() - radius_ * radius_;
    if (c > 0) return {0, 0, 0};  // outside the tube
    double s = a > 1e-12 ? (-b + std::sqrt(std::max(0.0, b * b - a * c))) / a : 1e12;
    double z = o.z() + s * d.z();
    if (z > p_.length_mm || z < -p_.back_mm) {
      // An end cap (z = length ahead, z = -back behind): texture on (x, y), offset per cap.
      const double zc = z > p_.length_mm ? p_.length_mm : -p_.back_mm;
      s = (zc - o.z()) / d.z();
      const Vec3 q = o + s * d;
      return shade(q.x() + (zc > 0 ? 1000.0 : 3000.0), q.y(), 0);
    }
    const Vec3 q = o + s * d;
    double phi = std::atan2(q.y(), q.x());
    if (phi < 0) phi += 2 * kPi;
    return shade(phi * radius_, z, circumference_);
  }
  std::string spec() const override { return fmt::format("tube:{}", p_.diameter_mm); }

 private:
  // The print at surface coordinates (u, v) in mm (u periodic with `period` mm if > 0): octaves
  // of value noise from 12.8 mm down to 0.1 mm cells, every octave with the same amplitude (detail
  // at every scale), through a steep sigmoid (high contrast, a printed pattern), tinted by a
  // coarse colour noise so that every channel carries texture.
  cv::Vec3f shade(double u, double v, double period) const {
    double n = 0;
    double cell = 12.8;
    for (int k = 0; k < 8; ++k, cell *= 0.5) {
      const int64_t per = period > 0 ? std::max<int64_t>(1, std::llround(period / cell)) : 0;
      const double cu = period > 0 ? period / per : cell;  // a whole number of cells around
      n += value_noise(u / cu, v / cell, per, p_.seed + 17 * k) - 0.5;
    }
    const double albedo = 0.06 + 0.88 / (1 + std::exp(-7 * n));
    cv::Vec3f out;
    const double cell_c = 6.0;
    const int64_t per = period > 0 ? std::max<int64_t>(1, std::llround(period / cell_c)) : 0;
    const double cu = period > 0 ? period / per : cell_c;
    for (int ch = 0; ch < 3; ++ch) {
      const double tint = 0.65 + 0.35 * value_noise(u / cu, v / cell_c, per, p_.seed + 1000 + ch);
      out[ch] = static_cast<float>(p_.brightness * albedo * tint);
    }
    return out;
  }

  TubeParams p_;
  double radius_ = 0, circumference_ = 0;
};

class FlatScene final : public Scene {
 public:
  explicit FlatScene(double level) : level_(level) {
    if (!(level > 0 && level <= kMaxSceneLevel))
      throw SceneError(
          fmt::format("flat scene: level must be a radiance in (0, {}], got {}", kMaxSceneLevel, level));
  }
  cv::Vec3f radiance(const Vec3&, const Vec3&, const Vec3&) const override {
    const float l = static_cast<float>(level_);
    return {l, l, l};
  }
  std::string spec() const override { return fmt::format("flat:{}", level_); }

 private:
  double level_;
};

}  // namespace

std::unique_ptr<Scene> make_tube_scene(const TubeParams& params) {
  return std::make_unique<TubeScene>(params);
}
std::unique_ptr<Scene> make_flat_scene(double level) { return std::make_unique<FlatScene>(level); }

}  // namespace omma::sim
