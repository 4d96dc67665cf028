// The procedural colon scene (declared in scene.h).
//
// Surface: radius R(z, phi) around the scene z axis (a height field over the tube), tabulated on a
// periodic grid of 0.15 mm cells together with the albedo. A ray origin + s dir hits the wall at the
// first s where g(s) = R(z(s), phi(s)) - rho(s) changes sign (rho = distance from the axis).
// g is Lipschitz with constant Lg = 1 + max|dR/dz| + max|dR/dphi| / R_min in the shell
// R_min <= rho, so steps of g / Lg cannot jump over the wall; a bisection then refines the hit.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <vector>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "omma/sim/scene.h"

namespace omma::sim {
namespace {

constexpr double kPeriod = 240.0;  // mm, the tube repeats along z
constexpr double kGeoCell = 0.3;   // mm, radius table cell along z (and about along the circumference)
constexpr double kTexCell = 0.15;  // mm, albedo table cell
constexpr double kMaxDistance = 400.0;
constexpr double kNoHit = std::numeric_limits<double>::infinity();
constexpr double kBlock = 4.0;  // mm, z blocks of the slope bounds
constexpr int kSkipBlocks = 4;  // the free-space skip looks this many blocks either way
constexpr double kTwoPi = 2 * kPi;

// Fast atan2 (max error about 1e-5 rad), result in [0, 2 pi).
inline double fast_phi(double y, double x) {
  const double ax = std::abs(x), ay = std::abs(y);
  const double mx = std::max(ax, ay), mn = std::min(ax, ay);
  if (mx == 0) return 0;
  const double a = mn / mx, s = a * a;
  double r =
      ((((-0.0117212 * s + 0.05265332) * s - 0.11643287) * s + 0.19354346) * s - 0.33262347) * s + 0.99997726;
  r *= a;
  if (ay > ax) r = kPi / 2 - r;
  if (x < 0) r = kPi - r;
  if (y < 0) r = kTwoPi - r;
  return r >= kTwoPi ? r - kTwoPi : r;
}

inline uint32_t hash3(int32_t a, int32_t b, uint32_t seed) {
  uint32_t h =
      static_cast<uint32_t>(a) * 0x8da6b343u ^ static_cast<uint32_t>(b) * 0xd8163841u ^ seed * 0xcb1ab31fu;
  h ^= h >> 13;
  h *= 0x5bd1e995u;
  h ^= h >> 15;
  return h;
}

// Value noise on a lattice periodic in both axes (nu x nv cells), coordinates in cells; in [0, 1].
double value_noise(double u, double v, int nu, int nv, uint32_t seed) {
  const double fu = std::floor(u), fv = std::floor(v);
  const int iu = static_cast<int>(fu), iv = static_cast<int>(fv);
  auto lat = [&](int a, int b) {
    a = ((a % nu) + nu) % nu;
    b = ((b % nv) + nv) % nv;
    return (hash3(a, b, seed) & 0xffffff) / double(0xffffff);
  };
  auto smooth = [](double t) { return t * t * (3 - 2 * t); };
  const double tu = smooth(u - fu), tv = smooth(v - fv);
  const double a = lat(iu, iv) * (1 - tu) + lat(iu + 1, iv) * tu;
  const double b = lat(iu, iv + 1) * (1 - tu) + lat(iu + 1, iv + 1) * tu;
  return a * (1 - tv) + b * tv;
}

// Periodic fractal noise over the tube surface: z in mm, phi in radians, feature size `cell` mm.
double tube_noise(double z, double phi, double cell, double radius, int octaves, uint32_t seed) {
  double sum = 0, amp = 1, norm = 0;
  for (int o = 0; o < octaves; ++o) {
    const int nu = std::max(1, static_cast<int>(std::lround(kPeriod / cell)));
    const int nv = std::max(1, static_cast<int>(std::lround(kTwoPi * radius / cell)));
    sum += amp * value_noise(z / kPeriod * nu, phi / kTwoPi * nv, nu, nv, seed + 101 * o);
    norm += amp;
    amp *= 0.5;
    cell *= 0.5;
  }
  return sum / norm;
}

inline double smoothstep(double e0, double e1, double x) {
  const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

inline double wrap_period(double dz) { return dz - kPeriod * std::round(dz / kPeriod); }
inline double wrap_angle(double a) { return a - kTwoPi * std::round(a / kTwoPi); }

struct Polyp {
  double z, phi, radius, height;
};

// Bilinear interpolation cell of a periodic (z, phi) table.
struct Cell {
  size_t i00, i01, i10, i11;
  float a, b;  // weights along z and phi
};

template <typename T>
T at(const std::vector<T>& t, const Cell& c) {
  return (t[c.i00] * (1 - c.b) + t[c.i01] * c.b) * (1 - c.a) + (t[c.i10] * (1 - c.b) + t[c.i11] * c.b) * c.a;
}

// A table over the tube surface: nz rows along z (period kPeriod), nphi columns around.
struct TableGrid {
  int nz = 0, nphi = 0;
  double dz = 0, dphi = 0, inv_dz = 0, inv_dphi = 0, inv_nz = 0;
  TableGrid() = default;
  TableGrid(double cell_mm, double radius_mm)
      : nz(static_cast<int>(std::lround(kPeriod / cell_mm))),
        nphi(static_cast<int>(std::lround(kTwoPi * radius_mm / cell_mm))),
        dz(kPeriod / nz),
        dphi(kTwoPi / nphi),
        inv_dz(1 / dz),
        inv_dphi(1 / dphi),
        inv_nz(1.0 / nz) {}
  size_t size() const { return static_cast<size_t>(nz) * nphi; }
  size_t idx(int iz, int ip) const {
    iz %= nz;
    if (iz < 0) iz += nz;
    ip %= nphi;
    if (ip < 0) ip += nphi;
    return static_cast<size_t>(iz) * nphi + ip;
  }
  Cell cell(double z, double phi) const {
    double u = z * inv_dz;
    u -= nz * std::floor(u * inv_nz);
    const double v = phi * inv_dphi;
    const double fu = std::floor(u), fv = std::floor(v);
    int iu = static_cast<int>(fu), iv = static_cast<int>(fv);
    if (iu >= nz) iu -= nz;
    if (iv >= nphi) iv -= nphi;
    if (iv < 0) iv += nphi;
    const int iu1 = iu + 1 == nz ? 0 : iu + 1;
    const int iv1 = iv + 1 == nphi ? 0 : iv + 1;
    const size_t r0 = static_cast<size_t>(iu) * nphi, r1 = static_cast<size_t>(iu1) * nphi;
    return {r0 + iv, r0 + iv1, r1 + iv, r1 + iv1, static_cast<float>(u - fu), static_cast<float>(v - fv)};
  }
};

class ColonScene final : public Scene {
 public:
  explicit ColonScene(const ColonParams& p) : p_(p) {
    if (!(p.radius_mm >= 10 && p.radius_mm <= 40))
      throw SceneError(fmt::format("colon scene: radius must be 10..40 mm, got {}", p.radius_mm));
    geo_ = TableGrid(kGeoCell, p.radius_mm);
    tex_ = TableGrid(kTexCell, p.radius_mm);
    build_tables();
  }

  cv::Vec3f radiance(const Vec3& o, const Vec3& d, const Vec3& light) const override {
    const double s = distance(o, d);
    if (!(s < kNoHit)) return {0, 0, 0};
    return shade(o + s * d, light);
  }

  // The first wall hit along o + s d, or kNoHit (outside the tube, along the axis, beyond
  // kMaxDistance).
  double distance(const Vec3& o, const Vec3& d) const override {
    const double rho0 = std::hypot(o.x(), o.y());
    if (rho0 >= radius_at(o.z(), fast_phi(o.y(), o.x()))) return kNoHit;  // outside the tube
    // Enter the shell rho >= r_min_ (analytic), then march.
    const double a = d.x() * d.x() + d.y() * d.y();
    double s = 0;
    if (rho0 < r_min_) {
      if (a < 1e-12) return kNoHit;  // along the axis: the lumen vanishes into the dark
      const double b = o.x() * d.x() + o.y() * d.y(), c = rho0 * rho0 - r_min_ * r_min_;
      s = (-b + std::sqrt(b * b - a * c)) / a;
    }
    // Lipschitz-safe march: |dg/ds| <= |d_xy| (1 + Lphi / rho_lo) + Lz |d_z| with the slopes of
    // R (per radian, per mm) bounded over the z-window of +-1 block around the current point; a
    // step never travels more than one block along z, so the bound holds over the whole step.
    const double dxy = std::sqrt(a), adz = std::abs(d.z());
    // Smallest rho on the marched part of the ray: r_min_ if we start inside the shell (a line leaves
    // a circle only once), else the closest approach to the axis if it lies ahead, else rho0.
    double rho_lo = r_min_;
    if (rho0 >= r_min_) {
      const double s_c = a > 1e-12 ? -(o.x() * d.x() + o.y() * d.y()) / a : 0;
      rho_lo = s_c > 0 ? std::abs(o.x() * d.y() - o.y() * d.x()) / dxy : rho0;
    }
    rho_lo = std::max(rho_lo, 0.5);
    const double max_h = kBlock / std::max(adz, 1e-9);
    const double max_skip = kSkipBlocks * kBlock / std::max(adz, 1e-9);
    double g = gap(o, d, s), s_prev = s, g_prev = g;
    while (true) {
      if (s > kMaxDistance) return kNoHit;
      if (g <= 0) break;
      const double z = o.z() + s * d.z();
      const int k = block_of(z);
      const double L = 1.02 * (dxy * (1 + lphi_win_[k] / rho_lo) + lz_win_[k] * adz) + 1e-6;
      double h = std::min(std::max(g / L, 0.08 + 0.002 * s), max_h);
      // Skip: while rho stays below the smallest radius of the blocks within kSkipBlocks, no hit.
      const double px = o.x() + s * d.x(), py = o.y() + s * d.y();
      const double rho2 = px * px + py * py, rw = rmin_skip_[k];
      if (rho2 < rw * rw && a > 1e-12) {
        const double b = px * d.x() + py * d.y();
        const double t = (-b + std::sqrt(b * b - a * (rho2 - rw * rw))) / a;
        h = std::max(h, std::min(t, max_skip));
      } else if (rho2 < rw * rw) {
        h = std::max(h, max_skip);
      }
      // Secant acceleration for grazing rays (g shrinking slowly): aim just past the predicted
      // crossing, but never more than about a millimetre, so no fold or polyp can be jumped over.
      if (s > s_prev && g < g_prev) {
        const double rate = (g_prev - g) / (s - s_prev);
        h = std::max(h, std::min(1.2 * g / rate, 2.0 + 0.02 * s));
      }
      s_prev = s;
      g_prev = g;
      s += h;
      g = gap(o, d, s);
    }
    // Regula falsi (Illinois) between s_prev (g > 0, inside) and s (g <= 0, beyond the wall).
    double lo = s_prev, hi = s, glo = g_prev, ghi = g;
    int side = 0;
    for (int i = 0; i < 8 && hi - lo > 0.02; ++i) {
      const double m = (lo * ghi - hi * glo) / (ghi - glo);
      const double gm = gap(o, d, m);
      if (std::abs(gm) < 0.005) {  // within 5 um of the wall (radially)
        hi = m;
        break;
      }
      if (gm > 0) {
        lo = m;
        glo = gm;
        if (side == 1) ghi *= 0.5;
        side = 1;
      } else {
        hi = m;
        ghi = gm;
        if (side == -1) glo *= 0.5;
        side = -1;
      }
    }
    return hi;
  }

  std::string spec() const override { return "colon"; }

 private:
  // Analytic surface (used once, to fill the tables). Returns R and, via out-params, material.
  double analytic_radius(double z, double phi, double* polyp_weight) const {
    const double R0 = p_.radius_mm;
    double r =
        R0 + 2.5 * std::sin(kTwoPi * 2 * z / kPeriod + 0.7) + 1.0 * std::sin(2 * phi + kTwoPi * z / kPeriod);
    // Haustral folds: ten per period, semilunar (three crescents between the taeniae), wavy.
    const double spacing = kPeriod / 10;
    const int k0 = static_cast<int>(std::floor(z / spacing));
    for (int k = k0 - 1; k <= k0 + 1; ++k) {
      const int kk = ((k % 10) + 10) % 10;
      const double zk = k * spacing + 0.5 * spacing + 2.5 * std::sin(phi + 1.3 * kk);
      const double dz = z - zk;
      const double amp = 4.5 * (0.2 + 0.8 * std::abs(std::sin(1.5 * (phi - 0.4 * kk))));
      r -= amp * std::exp(-(dz * dz) / (2.0 * 2.0));
    }
    double pw = 0;
    for (const Polyp& q : polyps_) {
      const double dz = wrap_period(z - q.z), da = wrap_angle(phi - q.phi) * R0;
      const double t = (dz * dz + da * da) / (q.radius * q.radius);
      if (t < 1) {
        const double prof = (1 - t) * (1 + 0.8 * t);  // dome: flat top, sharp base (sessile polyp)
        r -= q.height * prof;
        pw = std::max(pw, std::sqrt(1 - t));
      }
    }
    if (polyp_weight) *polyp_weight = pw;
    return r;
  }

  void build_tables() {
    // {z mm, phi, base radius mm, height mm}: within sight of a dome at z = 0, spread around.
    polyps_ = {{12, deg2rad(40), 6.0, 5.0},
               {24, deg2rad(165), 5.0, 4.5},
               {33, deg2rad(275), 7.0, 6.0},
               {58, deg2rad(105), 5.5, 4.5}};
    radius_.assign(geo_.size(), 0);
    tbb::parallel_for(0, geo_.nz, [&](int iz) {
      for (int ip = 0; ip < geo_.nphi; ++ip)
        radius_[geo_.idx(iz, ip)] =
            static_cast<float>(analytic_radius(iz * geo_.dz, ip * geo_.dphi, nullptr));
    });
    albedo_.assign(tex_.size(), cv::Vec3f());
    const uint32_t seed = p_.seed;
    const double R0 = p_.radius_mm;
    tbb::parallel_for(0, tex_.nz, [&](int iz) {
      const double z = iz * tex_.dz;
      for (int ip = 0; ip < tex_.nphi; ++ip) {
        const double phi = ip * tex_.dphi;
        double pw = 0;
        analytic_radius(z, phi, &pw);
        // Mucosa: pink-red with slow variation (linear BGR).
        const double slow = tube_noise(z, phi, 12.0, R0, 2, seed);
        cv::Vec3f c(0.16f, 0.20f, 0.62f);
        c *= static_cast<float>(0.8 + 0.4 * slow);
        // Vessels: thin lines along the level set 0.5 of fractal noise, two scales.
        const double n1 = tube_noise(z, phi, 6.0, R0, 3, seed + 17);
        const double n2 = tube_noise(z, phi, 1.5, R0, 2, seed + 29);
        const double v1 = 1 - smoothstep(0.0, 0.025, std::abs(n1 - 0.5));
        const double v2 = 0.6 * (1 - smoothstep(0.0, 0.03, std::abs(n2 - 0.5)));
        const double v = std::max(v1, v2);
        const cv::Vec3f vessel(0.07f, 0.05f, 0.32f);
        c = c * static_cast<float>(1 - v) + vessel * static_cast<float>(v);
        // Polyps: paler, with a fine pit pattern.
        if (pw > 0) {
          const double pits = tube_noise(z, phi, 0.6, R0, 1, seed + 43);
          const cv::Vec3f polyp(0.20f, 0.27f, 0.72f);
          const float w = static_cast<float>(smoothstep(0.0, 0.4, pw));
          c = c * (1 - w) + polyp * static_cast<float>(w * (0.85 + 0.3 * pits));
        }
        albedo_[tex_.idx(iz, ip)] = c;
      }
    });
    // Normals and bounds for the march, from the geometry table.
    const TableGrid& g = geo_;
    slope_.resize(radius_.size());
    for (int iz = 0; iz < g.nz; ++iz)
      for (int ip = 0; ip < g.nphi; ++ip)
        slope_[g.idx(iz, ip)] = cv::Vec2f(
            static_cast<float>((radius_[g.idx(iz + 1, ip)] - radius_[g.idx(iz - 1, ip)]) / (2 * g.dz)),
            static_cast<float>((radius_[g.idx(iz, ip + 1)] - radius_[g.idx(iz, ip - 1)]) / (2 * g.dphi)));
    r_min_ = 1e9;
    for (float r : radius_) r_min_ = std::min(r_min_, static_cast<double>(r));
    r_min_ -= 0.01;
    // Largest slopes of R per z block, then over windows of +-1 block.
    const int nb = static_cast<int>(std::lround(kPeriod / kBlock));
    std::vector<double> lz(nb, 0), lphi(nb, 0), rmin(nb, 1e9);
    for (int iz = 0; iz < g.nz; ++iz) {
      const int b = std::min(nb - 1, static_cast<int>(iz * g.dz / kBlock));
      for (int ip = 0; ip < g.nphi; ++ip) {
        const double r = radius_[g.idx(iz, ip)];
        const double sz =
            std::max(std::abs(radius_[g.idx(iz + 1, ip)] - r), std::abs(radius_[g.idx(iz - 1, ip)] - r)) /
            g.dz;
        lz[b] = std::max(lz[b], sz);
        lphi[b] = std::max(lphi[b], std::abs(radius_[g.idx(iz, ip + 1)] - r) / g.dphi);
        rmin[b] = std::min(rmin[b], r);
      }
    }
    rmin_skip_.assign(nb, 1e9);
    for (int b = 0; b < nb; ++b)
      for (int j = -kSkipBlocks - 1; j <= kSkipBlocks + 1; ++j)
        rmin_skip_[b] = std::min(rmin_skip_[b], rmin[(b + j + 2 * nb) % nb] - 0.01);
    lz_win_.assign(nb, 0);
    lphi_win_.assign(nb, 0);
    for (int b = 0; b < nb; ++b)
      for (int j = -1; j <= 1; ++j) {
        const int bb = (b + j + nb) % nb;
        lz_win_[b] = std::max(lz_win_[b], lz[bb]);
        lphi_win_[b] = std::max(lphi_win_[b], lphi[bb]);
      }
  }

  double radius_at(double z, double phi) const { return at(radius_, geo_.cell(z, phi)); }

  double gap(const Vec3& o, const Vec3& d, double s) const {
    const double x = o.x() + s * d.x(), y = o.y() + s * d.y(), z = o.z() + s * d.z();
    return radius_at(z, fast_phi(y, x)) - std::sqrt(x * x + y * y);
  }

  cv::Vec3f shade(const Vec3& p, const Vec3& light) const {
    const double phi = fast_phi(p.y(), p.x()), rho = std::hypot(p.x(), p.y());
    const cv::Vec2f slope = at(slope_, geo_.cell(p.z(), phi));  // dR/dz, dR/dphi
    // F = R(z, phi) - rho grows towards the axis; its gradient is the inward normal.
    const double cp = p.x() / rho, sp = p.y() / rho;
    const Vec3 e_rho(cp, sp, 0), e_phi(-sp, cp, 0);
    const Vec3 n = (slope[0] * Vec3::UnitZ() + (slope[1] / rho) * e_phi - e_rho).normalized();
    const Vec3 to_light = light - p;
    const double dist = to_light.norm();
    const double cos_i = std::max(0.0, n.dot(to_light) / std::max(dist, 1e-9));
    const double falloff = (p_.light_distance_mm * p_.light_distance_mm) / std::max(dist * dist, 1.0);
    const double shading = p_.light_power * falloff * (0.85 * cos_i + 0.15);  // 0.15: interreflection
    return at(albedo_, tex_.cell(p.z(), phi)) * static_cast<float>(shading);
  }

  ColonParams p_;
  std::vector<Polyp> polyps_;
  TableGrid geo_;                 // radius and slopes (kGeoCell)
  TableGrid tex_;                 // albedo (kTexCell)
  std::vector<cv::Vec2f> slope_;  // dR/dz (mm/mm), dR/dphi (mm/rad), central differences
  std::vector<float> radius_;
  std::vector<cv::Vec3f> albedo_;
  double r_min_ = 0;
  std::vector<double> lz_win_, lphi_win_;
  std::vector<double> rmin_skip_;  // smallest R within +-(kSkipBlocks + 1) blocks

  int block_of(double z) const {
    const int nb = static_cast<int>(lz_win_.size());
    int b = static_cast<int>(std::floor(z / kBlock)) % nb;
    return b < 0 ? b + nb : b;
  }
};

// Building the tables takes about a second of CPU; the last colon built is kept and shared, so
// tests, the demo and the engine pay it once per process.
class SharedScene final : public Scene {
 public:
  explicit SharedScene(std::shared_ptr<const Scene> s) : s_(std::move(s)) {}
  cv::Vec3f radiance(const Vec3& o, const Vec3& d, const Vec3& l) const override {
    return s_->radiance(o, d, l);
  }
  double distance(const Vec3& o, const Vec3& d) const override { return s_->distance(o, d); }
  std::string spec() const override { return s_->spec(); }

 private:
  std::shared_ptr<const Scene> s_;
};

}  // namespace

std::unique_ptr<Scene> make_colon_scene(const ColonParams& params) {
  static std::mutex mutex;
  static std::shared_ptr<const Scene> last;
  static ColonParams last_params;
  std::lock_guard lock(mutex);
  const bool same = last && last_params.radius_mm == params.radius_mm &&
                    last_params.light_distance_mm == params.light_distance_mm &&
                    last_params.light_power == params.light_power && last_params.seed == params.seed;
  if (!same) {
    last = std::make_shared<const ColonScene>(params);
    last_params = params;
  }
  return std::make_unique<SharedScene>(last);
}

}  // namespace omma::sim
