// The room scene (room.h): analytic primitives read from a JSON file, textured with fractal value
// noise, self-lit under a fixed light (room.h (R1)).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "omma/core/parse.h"
#include "omma/sim/room.h"
#include "omma/sim/room_default.h"  // generated at build time from data/scenes/room.json

namespace omma::sim {
namespace {

using json = nlohmann::json;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kEps = 1e-9;  // mm: hits closer than this to the ray origin are not hits
constexpr double kTintCellMm = 300;

// ---------------------------------------------------------------- value noise
inline uint32_t lattice_hash(int64_t x, int64_t y, int64_t z, uint64_t seed) {
  uint64_t h = static_cast<uint64_t>(x) * 0x9e3779b97f4a7c15ull + static_cast<uint64_t>(y);
  h = (h ^ (h >> 31)) * 0xbf58476d1ce4e5b9ull + static_cast<uint64_t>(z) + seed * 0x94d049bb133111ebull;
  h = (h ^ (h >> 29)) * 0x94d049bb133111ebull;
  return static_cast<uint32_t>(h ^ (h >> 32));
}
inline double lattice(int64_t x, int64_t y, int64_t z, uint64_t seed) {
  return (lattice_hash(x, y, z, seed) >> 8) * (1.0 / 16777215.0);
}
inline double smooth(double t) { return t * t * (3 - 2 * t); }

// Value noise in [0, 1] on unit cells, smoothstep-interpolated (2-D and 3-D).
double value_noise(double u, double v, uint64_t seed) {
  const double fu = std::floor(u), fv = std::floor(v);
  const int64_t iu = static_cast<int64_t>(fu), iv = static_cast<int64_t>(fv);
  const double su = smooth(u - fu), sv = smooth(v - fv);
  const double a = lattice(iu, iv, 0, seed), b = lattice(iu + 1, iv, 0, seed);
  const double c = lattice(iu, iv + 1, 0, seed), d = lattice(iu + 1, iv + 1, 0, seed);
  const double l0 = a + (b - a) * su, l1 = c + (d - c) * su;
  return l0 + (l1 - l0) * sv;
}
double value_noise(const Vec3& p, uint64_t seed) {
  const double fx = std::floor(p.x()), fy = std::floor(p.y()), fz = std::floor(p.z());
  const int64_t ix = static_cast<int64_t>(fx), iy = static_cast<int64_t>(fy), iz = static_cast<int64_t>(fz);
  const double sx = smooth(p.x() - fx), sy = smooth(p.y() - fy), sz = smooth(p.z() - fz);
  double layer[2];
  for (int k = 0; k < 2; ++k) {
    const double a = lattice(ix, iy, iz + k, seed), b = lattice(ix + 1, iy, iz + k, seed);
    const double c = lattice(ix, iy + 1, iz + k, seed), d = lattice(ix + 1, iy + 1, iz + k, seed);
    const double l0 = a + (b - a) * sx, l1 = c + (d - c) * sx;
    layer[k] = l0 + (l1 - l0) * sy;
  }
  return layer[0] + (layer[1] - layer[0]) * sz;
}
// Three value noises at once (one lattice hash, a byte per channel), in [0, 1]: the colour tint.
cv::Vec3d value_noise3ch(double u, double v, uint64_t seed) {
  const double fu = std::floor(u), fv = std::floor(v);
  const int64_t iu = static_cast<int64_t>(fu), iv = static_cast<int64_t>(fv);
  const double su = smooth(u - fu), sv = smooth(v - fv);
  const double w[4] = {(1 - su) * (1 - sv), su * (1 - sv), (1 - su) * sv, su * sv};
  const uint32_t h[4] = {lattice_hash(iu, iv, 0, seed), lattice_hash(iu + 1, iv, 0, seed),
                         lattice_hash(iu, iv + 1, 0, seed), lattice_hash(iu + 1, iv + 1, 0, seed)};
  cv::Vec3d out(0, 0, 0);
  for (int k = 0; k < 4; ++k)
    for (int c = 0; c < 3; ++c) out[c] += w[k] * ((h[k] >> (8 * c + 8)) & 0xff);
  return out / 255.0;
}
cv::Vec3d value_noise3ch(const Vec3& p, uint64_t seed) {
  const double fx = std::floor(p.x()), fy = std::floor(p.y()), fz = std::floor(p.z());
  const int64_t ix = static_cast<int64_t>(fx), iy = static_cast<int64_t>(fy), iz = static_cast<int64_t>(fz);
  const double s[3] = {smooth(p.x() - fx), smooth(p.y() - fy), smooth(p.z() - fz)};
  cv::Vec3d out(0, 0, 0);
  for (int k = 0; k < 8; ++k) {
    const int a = k & 1, b = (k >> 1) & 1, c = k >> 2;
    const double w = (a ? s[0] : 1 - s[0]) * (b ? s[1] : 1 - s[1]) * (c ? s[2] : 1 - s[2]);
    const uint32_t h = lattice_hash(ix + a, iy + b, iz + c, seed);
    for (int ch = 0; ch < 3; ++ch) out[ch] += w * ((h >> (8 * ch + 8)) & 0xff);
  }
  return out / 255.0;
}

// Standard deviation of value_noise (uniform lattice values, variance 1/12, times E[sum of the
// squared smoothstep weights] = (13/35)*2 = 0.7429 per dimension): 2-D 0.2145, 3-D 0.1849.
constexpr double kNoiseSd2 = 0.2145, kNoiseSd3 = 0.1849;

uint64_t mix_seed(uint64_t seed, uint64_t k) {
  uint64_t x = seed * 0x9e3779b97f4a7c15ull + k + 0x632be59bd9b4e019ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

struct Material {
  cv::Vec3f colour{0.5f, 0.5f, 0.5f};  // linear BGR
  double contrast = 0.5;
  uint64_t seed = 0;
  double largest = 500, smallest = 2, gain = 0.8;
  std::vector<double> inv_cell, amp;  // per octave: 1 / cell (1/mm), amplitude / (sd sqrt(sum amp^2))

  void prepare() {
    inv_cell.clear();
    amp.clear();
    double sum2 = 0, a = 1;
    for (double cell = largest;; cell *= 0.5, a *= gain) {  // down to the first cell <= smallest
      inv_cell.push_back(1 / cell);
      amp.push_back(a);
      sum2 += a * a;
      if (cell <= smallest * (1 + 1e-9)) break;
    }
    for (double& x : amp) x /= std::sqrt(sum2);
  }
  // (R1) without the shading: colour * (1 + contrast tanh(1.5 n)) * tint at face coordinates (u, v)
  // mm of a surface with seed `s`, or at point p (3-D) when `solid`.
  cv::Vec3f albedo(double u, double v, const Vec3& p, bool solid, uint64_t s) const {
    double n = 0;
    for (size_t k = 0; k < amp.size(); ++k) {
      const uint64_t sk = s + 7919 * k;
      n += amp[k] *
           ((solid ? value_noise(p * inv_cell[k], sk) : value_noise(u * inv_cell[k], v * inv_cell[k], sk)) -
            0.5);
    }
    n /= solid ? kNoiseSd3 : kNoiseSd2;
    const double f = 1 + contrast * std::tanh(1.5 * n);
    const uint64_t st = s + 1000003;
    const cv::Vec3d t =
        solid ? value_noise3ch(p / kTintCellMm, st) : value_noise3ch(u / kTintCellMm, v / kTintCellMm, st);
    cv::Vec3f out;
    for (int c = 0; c < 3; ++c) out[c] = static_cast<float>(colour[c] * f * (0.85 + 0.3 * t[c]));
    return out;
  }
};

enum class Kind { kBox, kSphere, kCylinder, kCard, kGrid };

struct Prim {
  Kind kind = Kind::kBox;
  bool room = false;
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();                               // box
  Vec3 centre = Vec3::Zero();                                              // sphere, cylinder, card, grid
  double radius = 0, half_length = 0;                                      // sphere, cylinder
  int axis = 2;                                                            // cylinder
  Vec3 normal = Vec3::UnitZ(), right = Vec3::UnitX(), up = Vec3::UnitY();  // card, grid
  double half_w = 0, half_h = 0;
  double bar = 0, pitch = 0;  // grid
  bool v_bars = true, h_bars = true;
  bool edge = false;              // card pattern
  double edge_c = 1, edge_s = 0;  // cos, sin of the edge's slant
  float dark = 0, light = 0;
  Vec3 bound_centre = Vec3::Zero();  // a sphere around the primitive (not the room): the fast reject
  double bound_radius = kInf;
  int material = 0, floor_material = 0, ceiling_material = 0;
  uint64_t seed = 0;  // mixed into the material's seed: every surface its own texture
};

// ---------------------------------------------------------------- intersections
// Slab test; the near hit, or the far one when the origin is inside.
inline double hit_box(const Vec3& o, const Vec3& inv, const Vec3& lo, const Vec3& hi) {
  double tn = -kInf, tf = kInf;
  for (int k = 0; k < 3; ++k) {
    const double t1 = (lo[k] - o[k]) * inv[k], t2 = (hi[k] - o[k]) * inv[k];
    tn = std::max(tn, std::min(t1, t2));
    tf = std::min(tf, std::max(t1, t2));
  }
  if (tn > tf) return kInf;
  if (tn > kEps) return tn;
  return tf > kEps ? tf : kInf;
}

inline double hit_sphere(const Vec3& o, const Vec3& d, const Vec3& c, double r) {
  const Vec3 oc = o - c;
  const double b = oc.dot(d), cc = oc.squaredNorm() - r * r;
  const double disc = b * b - cc;
  if (disc < 0) return kInf;
  const double sq = std::sqrt(disc);
  if (-b - sq > kEps) return -b - sq;
  return -b + sq > kEps ? -b + sq : kInf;
}

inline double hit_cylinder(const Vec3& o, const Vec3& d, const Prim& p) {
  const int k = p.axis, i = (k + 1) % 3, j = (k + 2) % 3;
  const double oi = o[i] - p.centre[i], oj = o[j] - p.centre[j], ok = o[k] - p.centre[k];
  const double r2 = p.radius * p.radius;
  double best = kInf;
  const double a = d[i] * d[i] + d[j] * d[j];
  if (a > 1e-24) {
    const double b = oi * d[i] + oj * d[j], c = oi * oi + oj * oj - r2;
    const double disc = b * b - a * c;
    if (disc >= 0) {
      const double sq = std::sqrt(disc);
      for (const double t : {(-b - sq) / a, (-b + sq) / a})
        if (t > kEps && std::abs(ok + t * d[k]) <= p.half_length) {
          best = t;
          break;
        }
    }
  }
  if (std::abs(d[k]) > 1e-24)
    for (const double cap : {-p.half_length, p.half_length}) {
      const double t = (cap - ok) / d[k];
      if (t > kEps && t < best) {
        const double x = oi + t * d[i], y = oj + t * d[j];
        if (x * x + y * y <= r2) best = t;
      }
    }
  return best;
}

inline bool in_bar(double a, double pitch, double half_bar) {
  return std::abs(a - pitch * std::round(a / pitch)) <= half_bar;
}

inline double hit_card(const Vec3& o, const Vec3& d, const Prim& p, double best) {
  const double den = d.dot(p.normal);
  if (std::abs(den) < 1e-15) return kInf;
  const double t = (p.centre - o).dot(p.normal) / den;
  if (!(t > kEps && t < best)) return kInf;
  const Vec3 q = o + t * d - p.centre;
  const double a = q.dot(p.right), b = q.dot(p.up);
  if (std::abs(a) > p.half_w || std::abs(b) > p.half_h) return kInf;
  if (p.kind == Kind::kGrid) {
    const bool bar =
        (p.v_bars && in_bar(a, p.pitch, p.bar / 2)) || (p.h_bars && in_bar(b, p.pitch, p.bar / 2));
    if (!bar) return kInf;
  }
  return t;
}

// ---------------------------------------------------------------- the scene
class RoomScene final : public Scene {
 public:
  RoomScene(std::vector<Prim> prims, std::vector<Material> materials, std::vector<RoomObject> objects,
            Vec3 light_dir, double ambient, std::optional<Travel> travel, std::string spec)
      : prims_(std::move(prims)),
        materials_(std::move(materials)),
        objects_(std::move(objects)),
        light_dir_(light_dir),
        ambient_(ambient),
        travel_(travel),
        spec_(std::move(spec)) {
    // The bounding spheres of the objects (prims_[1..]), structure of arrays for the vectorised
    // first pass of trace().
    const size_t n = prims_.size() - 1;
    for (auto* a : {&bx_, &by_, &bz_, &br_}) a->resize(n);
    for (size_t i = 0; i < n; ++i) {
      const Prim& p = prims_[i + 1];
      bx_[i] = p.bound_centre.x();
      by_[i] = p.bound_centre.y();
      bz_[i] = p.bound_centre.z();
      br_[i] = p.bound_radius;
    }
  }

  cv::Vec3f radiance(const Vec3& o, const Vec3& d, const Vec3&) const override {
    int idx = -1;
    const double t = trace(o, d, &idx);
    if (idx < 0) return {0, 0, 0};
    return shade(prims_[idx], o + t * d, d);
  }
  double distance(const Vec3& o, const Vec3& d) const override { return trace(o, d, nullptr); }
  std::string spec() const override { return spec_; }
  std::optional<Travel> travel() const override { return travel_; }
  const std::vector<RoomObject>& objects() const { return objects_; }

 private:
  double trace(const Vec3& o, const Vec3& d, int* idx) const {
    Vec3 inv;
    for (int k = 0; k < 3; ++k) inv[k] = 1 / (std::abs(d[k]) < 1e-300 ? 1e-300 : d[k]);
    // The room, always hit from inside: the first bound for the objects.
    double best = hit_box(o, inv, prims_[0].lo, prims_[0].hi);
    int bi = best < kInf ? 0 : -1;
    // First pass (vectorised): the objects whose bounding sphere the ray meets ahead of its origin,
    // as distance along the ray to the sphere's near side (+inf: missed).
    const size_t n = bx_.size();
    double stack[128];
    std::vector<double> heap;
    double* near = n <= 128 ? stack : (heap.resize(n), heap.data());
    const double ox = o.x(), oy = o.y(), oz = o.z(), dx = d.x(), dy = d.y(), dz = d.z();
    for (size_t i = 0; i < n; ++i) {
      const double cx = bx_[i] - ox, cy = by_[i] - oy, cz = bz_[i] - oz, r = br_[i];
      const double tc = cx * dx + cy * dy + cz * dz;
      const double off2 = cx * cx + cy * cy + cz * cz - tc * tc;
      near[i] = (off2 <= r * r && tc + r >= 0) ? tc - r : kInf;
    }
    // Second pass: the exact test for the candidates nearer than the best hit so far.
    for (size_t i = 0; i < n; ++i) {
      if (!(near[i] <= best)) continue;
      const Prim& p = prims_[i + 1];
      double t = kInf;
      switch (p.kind) {
        case Kind::kBox:
          t = hit_box(o, inv, p.lo, p.hi);
          break;
        case Kind::kSphere:
          t = hit_sphere(o, d, p.centre, p.radius);
          break;
        case Kind::kCylinder:
          t = hit_cylinder(o, d, p);
          break;
        case Kind::kCard:
        case Kind::kGrid:
          t = hit_card(o, d, p, best);
          break;
      }
      if (t < best) {
        best = t;
        bi = static_cast<int>(i + 1);
      }
    }
    if (idx) *idx = bi;
    return best;
  }

  cv::Vec3f shade(const Prim& p, const Vec3& x, const Vec3& d) const {
    Vec3 n = Vec3::UnitZ();
    double u = 0, v = 0;
    bool solid = false;
    uint64_t seed = p.seed;
    int mat = p.material;
    switch (p.kind) {
      case Kind::kBox: {
        // The face nearest to the hit point: -x, +x, -y, +y, -z, +z = 0..5.
        int face = 0;
        double dmin = kInf;
        for (int k = 0; k < 3; ++k) {
          const double a = std::abs(x[k] - p.lo[k]), b = std::abs(x[k] - p.hi[k]);
          if (a < dmin) dmin = a, face = 2 * k;
          if (b < dmin) dmin = b, face = 2 * k + 1;
        }
        const int k = face / 2;
        n = Vec3::Zero();
        n[k] = face % 2 ? 1 : -1;
        u = x[(k + 1) % 3];
        v = x[(k + 2) % 3];
        seed = mix_seed(seed, face);
        if (p.room && face == 4) mat = p.floor_material;
        if (p.room && face == 5) mat = p.ceiling_material;
        break;
      }
      case Kind::kSphere:
        n = (x - p.centre) / p.radius;
        solid = true;
        break;
      case Kind::kCylinder: {
        const int k = p.axis, i = (k + 1) % 3, j = (k + 2) % 3;
        const Vec3 q = x - p.centre;
        const double rho = std::hypot(q[i], q[j]);
        const double cap_gap = std::abs(std::abs(q[k]) - p.half_length);
        if (cap_gap < std::abs(rho - p.radius)) {  // a cap
          n = Vec3::Zero();
          n[k] = q[k] > 0 ? 1 : -1;
          u = q[i];
          v = q[j];
          seed = mix_seed(seed, q[k] > 0 ? 2 : 1);
        } else {  // the side: 3-D noise, no seam around it
          n = Vec3::Zero();
          n[i] = q[i] / rho;
          n[j] = q[j] / rho;
          solid = true;
        }
        break;
      }
      case Kind::kCard:
      case Kind::kGrid: {
        const Vec3 q = x - p.centre;
        u = q.dot(p.right);
        v = q.dot(p.up);
        n = p.normal;
        if (p.edge) {
          const float l = u * p.edge_c - v * p.edge_s < 0 ? p.dark : p.light;
          return {l, l, l};
        }
        break;
      }
    }
    if (n.dot(d) > 0) n = -n;  // the side facing the ray's origin
    const double lit = ambient_ + (1 - ambient_) * std::max(0.0, n.dot(light_dir_));
    const Material& m = materials_[mat];
    return m.albedo(u, v, Vec3(x - p.centre), solid, mix_seed(m.seed, seed)) * static_cast<float>(lit);
  }

  std::vector<Prim> prims_;                // the room first, then the objects in file order
  std::vector<double> bx_, by_, bz_, br_;  // bounding spheres of prims_[1..]: centre (mm), radius
  std::vector<Material> materials_;
  std::vector<RoomObject> objects_;
  Vec3 light_dir_;
  double ambient_;
  std::optional<Travel> travel_;
  std::string spec_;
};

// ---------------------------------------------------------------- parsing
std::string type_name(const json& v) { return v.type_name(); }

class Parser {
 public:
  explicit Parser(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(const std::string& where, const std::string& what) const {
    if (where.empty()) throw SceneError(fmt::format("room file {}: {}", source_, what));
    throw SceneError(fmt::format("room file {}: {}: {}", source_, where, what));
  }

  void check_object(const json& j, const std::string& where) const {
    if (!j.is_object()) fail(where, fmt::format("must be a JSON object, got {}", type_name(j)));
  }
  // Unknown keys (not starting with '_') are errors: a misspelt field would otherwise be ignored.
  void check_keys(const json& j, const std::string& where, std::initializer_list<const char*> allowed) const {
    for (const auto& item : j.items()) {
      const std::string& k = item.key();
      if (!k.empty() && k[0] == '_') continue;
      if (std::none_of(allowed.begin(), allowed.end(), [&](const char* a) { return k == a; })) {
        std::string list;
        for (const char* a : allowed) list += std::string(list.empty() ? "" : ", ") + "'" + a + "'";
        fail(where,
             fmt::format("unknown field '{}' (fields: {}; keys starting with '_' are comments)", k, list));
      }
    }
  }
  const json& require(const json& j, const std::string& where, const char* key) const {
    if (!j.contains(key)) fail(where, fmt::format("missing field '{}'", key));
    return j.at(key);
  }
  double number(const json& j, const std::string& where, const char* key, double lo, double hi,
                std::optional<double> fallback = std::nullopt, bool open_lo = false) const {
    if (!j.contains(key)) {
      if (fallback) return *fallback;
      fail(where, fmt::format("missing field '{}'", key));
    }
    const json& v = j.at(key);
    if (!v.is_number()) fail(where, fmt::format("'{}' must be a number, got {}", key, type_name(v)));
    const double x = v.get<double>();
    const bool ok = std::isfinite(x) && (open_lo ? x > lo : x >= lo) && x <= hi;
    if (!ok)
      fail(where, fmt::format("'{}' must be in {}{}, {}], got {}", key, open_lo ? "(" : "[", lo, hi, x));
    return x;
  }
  Vec3 vec3(const json& j, const std::string& where, const char* key, double bound,
            std::optional<Vec3> fallback = std::nullopt) const {
    if (!j.contains(key)) {
      if (fallback) return *fallback;
      fail(where, fmt::format("missing field '{}'", key));
    }
    const json& v = j.at(key);
    if (!v.is_array() || v.size() != 3)
      fail(where, fmt::format("'{}' must be an array of 3 numbers [x, y, z], got {}", key, v.dump()));
    Vec3 out;
    for (int k = 0; k < 3; ++k) {
      if (!v[k].is_number() || !std::isfinite(v[k].get<double>()) || std::abs(v[k].get<double>()) > bound)
        fail(where, fmt::format("'{}' must hold 3 numbers within +-{}, got {}", key, bound, v.dump()));
      out[k] = v[k].get<double>();
    }
    return out;
  }
  Vec3 direction(const json& j, const std::string& where, const char* key,
                 std::optional<Vec3> fallback) const {
    const Vec3 v = vec3(j, where, key, kMaxSceneMm, fallback);
    if (!(v.norm() > 1e-9)) fail(where, fmt::format("'{}' must be a non-zero vector, got [0, 0, 0]", key));
    return v.normalized();
  }
  std::string text(const json& j, const std::string& where, const char* key, std::string fallback) const {
    if (!j.contains(key)) return fallback;
    if (!j.at(key).is_string())
      fail(where, fmt::format("'{}' must be a string, got {}", key, type_name(j.at(key))));
    return j.at(key).get<std::string>();
  }

  Material material(const json& j, const std::string& where, uint64_t default_seed) const {
    check_object(j, where);
    check_keys(j, where, {"colour", "color", "contrast", "seed", "largest_mm", "smallest_mm", "gain"});
    Material m;
    if (j.contains("colour") && j.contains("color")) fail(where, "give 'colour' or 'color', not both");
    const char* ckey = j.contains("color") ? "color" : "colour";
    const Vec3 rgb = vec3(j, where, ckey, kMaxSceneLevel, Vec3(0.5, 0.5, 0.5));
    if (rgb.minCoeff() < 0) fail(where, fmt::format("'{}' must be linear RGB values >= 0", ckey));
    m.colour =
        cv::Vec3f(static_cast<float>(rgb.z()), static_cast<float>(rgb.y()), static_cast<float>(rgb.x()));
    m.contrast = number(j, where, "contrast", 0, 1, 0.5);
    m.seed = default_seed;
    if (j.contains("seed")) {
      const auto s = json_integer(j.at("seed"), 0, 0xffffffffll);
      if (!s)
        fail(where, fmt::format("'seed' must be an integer in [0, 4294967295], got {}", j.at("seed").dump()));
      m.seed = static_cast<uint64_t>(*s);
    }
    m.largest = number(j, where, "largest_mm", 0.01, 1e5, 500.0);
    m.smallest = number(j, where, "smallest_mm", 0.01, 1e5, 2.0);
    if (m.smallest > m.largest)
      fail(where, fmt::format("'smallest_mm' ({}) must not exceed 'largest_mm' ({})", m.smallest, m.largest));
    if (m.largest / m.smallest > std::ldexp(1.0, 23))
      fail(where, fmt::format("'largest_mm' / 'smallest_mm' = {} gives more than 24 octaves",
                              m.largest / m.smallest));
    m.gain = number(j, where, "gain", 0, 1, 0.8, true);
    m.prepare();
    return m;
  }

  // "min"/"max" or "centre"/"size" of a box.
  void box(const json& j, const std::string& where, Vec3* lo, Vec3* hi) const {
    const bool mm = j.contains("min") || j.contains("max"), cs = j.contains("centre") || j.contains("size");
    if (mm && cs) fail(where, "give either 'min' and 'max' or 'centre' and 'size', not both");
    if (cs) {
      const Vec3 c = vec3(j, where, "centre", kMaxSceneMm), s = vec3(j, where, "size", kMaxSceneMm);
      if (!(s.minCoeff() > 0))
        fail(where,
             fmt::format("'size' must be positive in every axis, got [{}, {}, {}]", s.x(), s.y(), s.z()));
      *lo = c - s / 2;
      *hi = c + s / 2;
      return;
    }
    *lo = vec3(j, where, "min", kMaxSceneMm);
    *hi = vec3(j, where, "max", kMaxSceneMm);
    for (int k = 0; k < 3; ++k)
      if (!((*hi)[k] > (*lo)[k]))
        fail(where, fmt::format("'max' must exceed 'min' in every axis (a positive size), got {} along {}",
                                (*hi)[k] - (*lo)[k], "xyz"[k]));
  }

 private:
  std::string source_;
};

std::string where_object(size_t i, const json& o) {
  std::string w = fmt::format("objects[{}]", i);
  if (o.is_object() && o.contains("name") && o.at("name").is_string())
    w += fmt::format(" (\"{}\")", o.at("name").get<std::string>());
  return w;
}

std::unique_ptr<Scene> parse_room(const std::string& text, const std::string& source,
                                  const std::string& spec) {
  const Parser P(source);
  json doc;
  try {
    doc = json::parse(text);
  } catch (const json::exception& e) {
    P.fail("", fmt::format("not valid JSON: {}", e.what()));
  }
  P.check_object(doc, "the top level");
  P.check_keys(doc, "the top level", {"format", "version", "light", "travel", "room", "objects"});
  if (doc.contains("format") && doc.at("format") != "omma-room")
    P.fail("", fmt::format("'format' must be \"omma-room\", got {}", doc.at("format").dump()));
  if (doc.contains("version") && doc.at("version") != 1)
    P.fail("", fmt::format("'version' must be 1, got {}", doc.at("version").dump()));

  Vec3 light_dir = Vec3(0.3, 0.2, 1).normalized();
  double ambient = 0.55;
  if (doc.contains("light")) {
    const json& l = doc.at("light");
    P.check_object(l, "light");
    P.check_keys(l, "light", {"direction", "ambient"});
    light_dir = P.direction(l, "light", "direction", light_dir);
    ambient = P.number(l, "light", "ambient", 0, 1, ambient);
  }
  std::optional<Scene::Travel> travel;
  if (doc.contains("travel")) {
    const json& t = doc.at("travel");
    P.check_object(t, "travel");
    P.check_keys(t, "travel", {"direction", "speed_mm_s"});
    travel = Scene::Travel{P.direction(t, "travel", "direction", std::nullopt),
                           P.number(t, "travel", "speed_mm_s", 0, 1e4, std::nullopt, true)};
  }

  std::vector<Prim> prims;
  std::vector<Material> materials;
  std::vector<RoomObject> objects;
  // The room.
  const json& r = P.require(doc, "", "room");
  P.check_object(r, "room");
  P.check_keys(r, "room", {"min", "max", "centre", "size", "material", "floor", "ceiling"});
  Prim room;
  room.room = true;
  P.box(r, "room", &room.lo, &room.hi);
  if (!((room.lo.array() < 0).all() && (room.hi.array() > 0).all()))
    P.fail("room", fmt::format("the rig centre (the origin) must lie inside the room, which spans [{}, {}] x "
                               "[{}, {}] x [{}, {}] mm",
                               room.lo.x(), room.hi.x(), room.lo.y(), room.hi.y(), room.lo.z(), room.hi.z()));
  materials.push_back(P.material(P.require(r, "room", "material"), "room.material", 1));
  room.material = 0;
  room.floor_material = room.ceiling_material = 0;
  if (r.contains("floor")) {
    materials.push_back(P.material(r.at("floor"), "room.floor", 2));
    room.floor_material = static_cast<int>(materials.size()) - 1;
  }
  if (r.contains("ceiling")) {
    materials.push_back(P.material(r.at("ceiling"), "room.ceiling", 3));
    room.ceiling_material = static_cast<int>(materials.size()) - 1;
  }
  room.seed = mix_seed(0, 0);
  prims.push_back(room);

  // The objects.
  const json objs = doc.contains("objects") ? doc.at("objects") : json::array();
  if (!objs.is_array()) P.fail("objects", fmt::format("must be an array, got {}", type_name(objs)));
  for (size_t i = 0; i < objs.size(); ++i) {
    const json& o = objs[i];
    const std::string w = where_object(i, o);
    P.check_object(o, w);
    const std::string type = P.text(o, w, "type", "");
    if (type.empty()) P.fail(w, "missing field 'type' (box, sphere, cylinder, card or grid)");
    Prim p;
    p.seed = mix_seed(i + 1, 0x726f6f6dull);
    RoomObject info;
    info.name = P.text(o, w, "name", "");
    info.type = type;
    const bool needs_material = !(type == "card" && o.contains("pattern"));
    if (type == "box") {
      P.check_keys(o, w, {"type", "name", "min", "max", "centre", "size", "material"});
      p.kind = Kind::kBox;
      P.box(o, w, &p.lo, &p.hi);
      info.centre = (p.lo + p.hi) / 2;
      info.size = p.hi - p.lo;
    } else if (type == "sphere") {
      P.check_keys(o, w, {"type", "name", "centre", "radius", "material"});
      p.kind = Kind::kSphere;
      p.centre = P.vec3(o, w, "centre", kMaxSceneMm);
      p.radius = P.number(o, w, "radius", 0, kMaxSceneMm, std::nullopt, true);
      info.centre = p.centre;
      info.size = Vec3::Constant(2 * p.radius);
    } else if (type == "cylinder") {
      P.check_keys(o, w, {"type", "name", "centre", "axis", "radius", "length", "material"});
      p.kind = Kind::kCylinder;
      p.centre = P.vec3(o, w, "centre", kMaxSceneMm);
      const std::string axis = P.text(o, w, "axis", "");
      if (axis != "x" && axis != "y" && axis != "z")
        P.fail(w, axis.empty() ? "missing field 'axis' (\"x\", \"y\" or \"z\")"
                               : fmt::format("'axis' must be \"x\", \"y\" or \"z\", got \"{}\"", axis));
      p.axis = axis[0] - 'x';
      p.radius = P.number(o, w, "radius", 0, kMaxSceneMm, std::nullopt, true);
      p.half_length = P.number(o, w, "length", 0, kMaxSceneMm, std::nullopt, true) / 2;
      info.centre = p.centre;
      info.size = Vec3::Constant(2 * p.radius);
      info.size[p.axis] = 2 * p.half_length;
    } else if (type == "card" || type == "grid") {
      if (type == "card")
        P.check_keys(o, w,
                     {"type", "name", "centre", "normal", "up", "size", "rotate_deg", "material", "pattern"});
      else
        P.check_keys(o, w,
                     {"type", "name", "centre", "normal", "up", "size", "rotate_deg", "material", "bar_mm",
                      "pitch_mm", "bars"});
      p.kind = type == "card" ? Kind::kCard : Kind::kGrid;
      p.centre = P.vec3(o, w, "centre", kMaxSceneMm);
      p.normal = P.direction(o, w, "normal", std::nullopt);
      const Vec3 up0 = P.direction(o, w, "up", std::abs(p.normal.z()) > 0.99 ? Vec3::UnitX() : Vec3::UnitZ());
      const Vec3 up = up0 - up0.dot(p.normal) * p.normal;
      if (up.norm() < 1e-6) P.fail(w, "'up' must not be parallel to 'normal'");
      p.up = up.normalized();
      p.right = p.up.cross(p.normal).normalized();  // the right of a viewer facing the card's front
      const double rot = deg2rad(P.number(o, w, "rotate_deg", -360, 360, 0.0));
      const Vec3 r0 = p.right, u0 = p.up;
      p.right = std::cos(rot) * r0 + std::sin(rot) * u0;
      p.up = -std::sin(rot) * r0 + std::cos(rot) * u0;
      const json& sz = P.require(o, w, "size");
      if (!sz.is_array() || sz.size() != 2 || !sz[0].is_number() || !sz[1].is_number())
        P.fail(w, fmt::format("'size' must be an array of 2 numbers [width, height], got {}", sz.dump()));
      const double sw = sz[0].get<double>(), sh = sz[1].get<double>();
      if (!(sw > 0 && sh > 0 && sw <= kMaxSceneMm && sh <= kMaxSceneMm))
        P.fail(w, fmt::format("'size' must be positive (up to {} mm), got [{}, {}]", kMaxSceneMm, sw, sh));
      p.half_w = sw / 2;
      p.half_h = sh / 2;
      info.centre = p.centre;
      info.size = Vec3(sw, sh, 0);
      info.normal = p.normal;
      info.right = p.right;
      info.up = p.up;
      if (type == "card") {
        info.pattern = "noise";
        if (o.contains("pattern") && o.contains("material"))
          P.fail(w, "give 'material' or 'pattern', not both");
        if (o.contains("pattern")) {
          const std::string pw = w + ".pattern";
          const json& pat = o.at("pattern");
          P.check_object(pat, pw);
          P.check_keys(pat, pw, {"type", "angle_deg", "dark", "light"});
          const std::string pt = P.text(pat, pw, "type", "");
          if (pt != "edge") P.fail(pw, fmt::format("'type' must be \"edge\", got \"{}\"", pt));
          const double a = P.number(pat, pw, "angle_deg", -45, 45, 0.0);
          p.edge = true;
          p.edge_c = std::cos(deg2rad(a));
          p.edge_s = std::sin(deg2rad(a));
          p.dark = static_cast<float>(P.number(pat, pw, "dark", 0, kMaxSceneLevel, 0.03));
          p.light = static_cast<float>(P.number(pat, pw, "light", 0, kMaxSceneLevel, 0.8));
          info.pattern = "edge";
          info.edge = (p.edge_c * p.up + p.edge_s * p.right).normalized();
          info.edge_angle_deg = a;
          info.dark = p.dark;
          info.light = p.light;
        }
      } else {
        p.bar = P.number(o, w, "bar_mm", 0, kMaxSceneMm, std::nullopt, true);
        p.pitch = P.number(o, w, "pitch_mm", 0, kMaxSceneMm, std::nullopt, true);
        if (!(p.pitch > p.bar))
          P.fail(w, fmt::format("'pitch_mm' ({}) must exceed 'bar_mm' ({}): else nothing shows through",
                                p.pitch, p.bar));
        const std::string bars = P.text(o, w, "bars", "both");
        if (bars != "both" && bars != "vertical" && bars != "horizontal")
          P.fail(w, fmt::format("'bars' must be \"both\", \"vertical\" or \"horizontal\", got \"{}\"", bars));
        p.v_bars = bars != "horizontal";
        p.h_bars = bars != "vertical";
        info.bar_mm = p.bar;
        info.pitch_mm = p.pitch;
      }
    } else {
      P.fail(w, fmt::format("unknown type \"{}\" (box, sphere, cylinder, card or grid)", type));
    }
    if (needs_material) {
      materials.push_back(P.material(P.require(o, w, "material"), w + ".material", 100 + i));
      p.material = static_cast<int>(materials.size()) - 1;
    }
    // The rig centre must lie outside every object (inside a solid it would see only the solid).
    const Vec3 z = Vec3::Zero();
    bool inside = false;
    switch (p.kind) {
      case Kind::kBox:
        inside = (p.lo.array() <= 0).all() && (p.hi.array() >= 0).all();
        break;
      case Kind::kSphere:
        inside = p.centre.norm() <= p.radius;
        break;
      case Kind::kCylinder: {
        const int k = p.axis, a = (k + 1) % 3, b = (k + 2) % 3;
        inside = std::abs(p.centre[k]) <= p.half_length && std::hypot(p.centre[a], p.centre[b]) <= p.radius;
        break;
      }
      case Kind::kCard:
      case Kind::kGrid: {
        const Vec3 q = z - p.centre;
        inside = std::abs(q.dot(p.normal)) < 1e-6 && std::abs(q.dot(p.right)) <= p.half_w &&
                 std::abs(q.dot(p.up)) <= p.half_h;
        break;
      }
    }
    if (inside)
      P.fail(w, "the rig centre (the origin) lies inside this object: it must lie outside every object");
    p.bound_centre = info.centre;
    switch (p.kind) {
      case Kind::kBox:
        p.bound_radius = (p.hi - p.lo).norm() / 2;
        break;
      case Kind::kSphere:
        p.bound_radius = p.radius;
        break;
      case Kind::kCylinder:
        p.bound_radius = std::hypot(p.radius, p.half_length);
        break;
      case Kind::kCard:
      case Kind::kGrid:
        p.bound_radius = std::hypot(p.half_w, p.half_h);
        break;
    }
    p.bound_radius = p.bound_radius * (1 + 1e-9) + 1e-6;  // rounding: never reject a true hit
    prims.push_back(p);
    objects.push_back(info);
  }
  return std::make_unique<RoomScene>(std::move(prims), std::move(materials), std::move(objects), light_dir,
                                     ambient, travel, spec);
}

}  // namespace

const std::string& default_room_json() {
  static const std::string text(kDefaultRoomJson);
  return text;
}

std::unique_ptr<Scene> make_room_scene_from_text(const std::string& json_text, const std::string& source,
                                                 const std::string& spec) {
  return parse_room(json_text, source, spec);
}

std::unique_ptr<Scene> make_room_scene(const std::string& path) {
  if (path.empty()) return parse_room(default_room_json(), "(built in, data/scenes/room.json)", "room");
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw SceneError(fmt::format("room file '{}' does not exist or is not a file", path));
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  if (!in) throw SceneError(fmt::format("room file '{}' cannot be read", path));
  return parse_room(ss.str(), "'" + path + "'", "room:" + path);
}

std::vector<RoomObject> room_objects(const Scene& scene) {
  if (const auto* room = dynamic_cast<const RoomScene*>(&scene)) return room->objects();
  return {};
}

}  // namespace omma::sim
