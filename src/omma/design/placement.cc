#include "omma/design/placement.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "omma/core/log.h"
#include "omma/design/coverage.h"
#include "omma/design/dome.h"

namespace omma::design {

Method parse_method(const std::string& name) {
  if (name == "layered") return Method::kLayered;
  if (name == "min-cameras") return Method::kMinCameras;
  if (name == "max-volume") return Method::kMaxVolume;
  if (name == "cvt") return Method::kCvt;
  throw std::invalid_argument("unknown placement method '" + name +
                              "' (expected layered, min-cameras, max-volume or cvt)");
}

std::string to_string(Method m) {
  switch (m) {
    case Method::kLayered:
      return "layered";
    case Method::kMinCameras:
      return "min-cameras";
    case Method::kMaxVolume:
      return "max-volume";
    case Method::kCvt:
      return "cvt";
  }
  return "?";
}

CameraSize parse_camera_size(const std::string& text) {
  CameraSize c;
  char x1 = 0, x2 = 0;
  std::istringstream in(text);
  if (!(in >> c.width_mm >> x1 >> c.height_mm >> x2 >> c.length_mm) || (x1 != 'x' && x1 != 'X') ||
      (x2 != 'x' && x2 != 'X') || (in >> std::ws, !in.eof()))
    throw std::invalid_argument("camera size '" + text + "' is not WxHxL in mm (e.g. 1x1x2)");
  if (!(c.width_mm > 0 && c.height_mm > 0 && c.length_mm > 0) || !std::isfinite(c.width_mm) ||
      !std::isfinite(c.height_mm) || !std::isfinite(c.length_mm))
    throw std::invalid_argument("camera size '" + text + "': W, H and L must be positive mm");
  return c;
}

MaxVolumeLayout max_volume_layout(double r_phys_mm, const CameraSize& cam) {
  MaxVolumeLayout l;
  l.r_in_mm = r_phys_mm - cam.length_mm;  // r_in = r_out - l_cam (Fig. 3.4a)
  if (!(l.r_in_mm > 0))
    throw std::invalid_argument("max-volume: the camera length must be smaller than the radius");
  l.d_cam_mm = std::hypot(cam.width_mm, cam.height_mm);                                  // eq. 3.7
  const int nv = static_cast<int>(std::floor(kPi / 2 * l.r_in_mm / l.d_cam_mm + 1e-9));  // eq. 3.8
  if (nv < 1) throw std::invalid_argument("max-volume: not even one camera fits on the dome");
  l.beta_rad = (kPi / 2) / (2 * nv);  // eq. 3.9
  for (int i = 1; i <= nv; ++i) {
    const double polar = (2 * i - 1) * l.beta_rad;  // eq. 3.10
    const int nh =
        static_cast<int>(std::floor(2 * kPi * l.r_in_mm * std::sin(polar) / l.d_cam_mm + 1e-9));  // eq. 3.11
    l.polar_rad.push_back(polar);
    l.per_layer.push_back(std::max(nh, 1));
  }
  return l;
}

namespace {

void check_params(const DesignParams& p, bool needs_rvir) {
  if (!(p.aov_rad > 0 && p.aov_rad < kPi))
    throw std::invalid_argument("angle of view must be in (0, 180) degrees");
  if (!(p.r_phys_mm > 0) || !std::isfinite(p.r_phys_mm))
    throw std::invalid_argument("dome radius must be a positive number of mm");
  if (needs_rvir && !(p.r_virtual_mm > p.r_phys_mm))
    throw std::invalid_argument("r_virtual must be larger than the dome radius r_phys");
  if (!(p.check_step_rad > 0)) throw std::invalid_argument("check step must be positive");
}

// Directions of one layer: n cameras at polar angle `polar`, the first at azimuth `offset`.
void add_layer(std::vector<Vec3>& axes, int n, double polar, double offset) {
  for (int k = 0; k < n; ++k) axes.push_back(direction_from_spherical(polar, offset + 2 * kPi * k / n));
}

}  // namespace

std::vector<double> search_layer_offsets(const std::vector<int>& counts, const std::vector<double>& polar,
                                         bool sphere) {
  // Coordinate descent on the layers' azimuth offsets (the first layer stays at phi = 0): each
  // round scans every other layer's offset over one camera spacing in 1 deg steps and keeps the
  // one with the smallest covering radius (0.5 deg sampling); stops when a round improves nothing.
  const Sampling coarse = make_sampling(deg2rad(0.5), sphere);
  const size_t nl = counts.size();
  std::vector<double> off(nl, 0.0);
  auto axes_for = [&](const std::vector<double>& o) {
    std::vector<Vec3> axes;
    for (size_t i = 0; i < nl; ++i) add_layer(axes, counts[i], polar[i], o[i]);
    return axes;
  };
  double best = covering_radius(axes_for(off), coarse);
  for (int round = 0; round < 4; ++round) {
    bool improved = false;
    for (size_t i = 1; i < nl; ++i) {
      const int steps = std::max(1, static_cast<int>(std::lround(360.0 / counts[i])));
      for (int s = 0; s < steps; ++s) {
        std::vector<double> trial = off;
        trial[i] = deg2rad(s * (360.0 / counts[i]) / steps);
        const std::vector<Vec3> axes = axes_for(trial);
        // Cheap rejection first: most trials have a gap wider than the best so far.
        if (!covers(axes, coarse, best - 1e-9)) continue;
        const double r = covering_radius(axes, coarse);
        if (r < best - 1e-9) {
          best = r;
          off = trial;
          improved = true;
        }
      }
    }
    if (!improved) break;
  }
  return off;
}

Design design_max_volume(const DesignParams& p) {
  check_params(p, false);
  const MaxVolumeLayout l = max_volume_layout(p.r_phys_mm, p.cam);
  std::vector<int> counts = l.per_layer;
  std::vector<double> polar = l.polar_rad;
  if (p.sphere)  // the southern hemisphere mirrors the northern one
    for (int i = static_cast<int>(l.per_layer.size()) - 1; i >= 0; --i) {
      counts.push_back(l.per_layer[i]);
      polar.push_back(kPi - l.polar_rad[i]);
    }
  const std::vector<double> off = search_layer_offsets(counts, polar, p.sphere);
  std::vector<Vec3> axes;
  Design d;
  for (size_t i = 0; i < counts.size(); ++i) {
    add_layer(axes, counts[i], polar[i], off[i]);
    d.layers.push_back(counts[i]);
  }
  const Intrinsics in = ideal_intrinsics(p.aov_rad, p.width, p.height);
  d.rig = radial_rig(axes, p.r_phys_mm, in, p.sphere, "max-volume", "max-volume");
  if (p.compute_r_virtual) d.r_virtual_mm = virtual_radius(d.rig, p.check_step_rad);
  return d;
}

namespace {

// What the designers check: the cap model of coverage.h with a conservative margin.
struct Checker {
  Sampling s;
  double beta = 0;   // eq. 3.2 reach at r_virtual
  double reach = 0;  // beta minus the sampling radius
  Checker(const DesignParams& p, bool sphere) : s(make_sampling(p.check_step_rad, sphere)) {
    beta = reach_angle(p.aov_rad, p.r_phys_mm, p.r_virtual_mm);
    reach = beta - sampling_radius(s);
    if (!(reach > 0))
      throw std::invalid_argument(
          "r_virtual is too close to the dome: the cameras' cones do not reach sideways there "
          "(eq. 3.2 gives beta <= 0; increase --r-virtual or --aov)");
  }
  bool covered(const std::vector<Vec3>& axes) const { return covers(axes, s, reach); }
};

std::vector<Vec3> mirrored(const std::vector<Vec3>& north) {
  std::vector<Vec3> all = north;
  for (const Vec3& a : north)
    if (a.z() > 1e-9) all.push_back(Vec3(a.x(), a.y(), -a.z()));  // equator cameras once
  return all;
}

Design finish(const DesignParams& p, std::vector<Vec3> axes, std::vector<int> layers,
              const std::string& method) {
  Design d;
  if (p.sphere && method != "cvt") {  // hemisphere designs mirror onto the southern half
    const size_t north = axes.size();
    axes = mirrored(axes);
    // Southern layers in mirror order; a layer on the equator is not repeated.
    const int on_equator = static_cast<int>(2 * north - axes.size());
    const int nl = static_cast<int>(layers.size());
    for (int i = nl - 1 - (on_equator > 0 ? 1 : 0); i >= 0; --i) layers.push_back(layers[i]);
  }
  d.layers = std::move(layers);
  const Intrinsics in = ideal_intrinsics(p.aov_rad, p.width, p.height);
  d.rig = radial_rig(axes, p.r_phys_mm, in, p.sphere, method, method);
  if (p.compute_r_virtual) d.r_virtual_mm = virtual_radius(d.rig, p.check_step_rad);
  return d;
}

// Panoptic floors (§2.4.2, [64, 65]): a camera at the pole whose circular face has angular
// radius a = (pi/2) / (2 floors + 1); floor i (1..floors) at polar angle 2 i a holds as many faces
// of radius a as fit around it without overlapping (neighbour separation >= 2a).
std::vector<Vec3> panoptic_floors(int floors, std::vector<int>& layers) {
  const double a = (kPi / 2) / (2 * floors + 1);
  std::vector<Vec3> axes = {Vec3::UnitZ()};
  layers = {1};
  for (int i = 1; i <= floors; ++i) {
    const double th = 2 * i * a;
    const double st2 = std::sin(th) * std::sin(th);
    const double cos_dphi = (std::cos(2 * a) - std::cos(th) * std::cos(th)) / st2;
    const int n = std::max(
        1, static_cast<int>(std::floor(2 * kPi / std::acos(std::clamp(cos_dphi, -1.0, 1.0)) + 1e-9)));
    add_layer(axes, n, th, 0.0);
    layers.push_back(n);
  }
  return axes;
}

// CVT of the sphere (or the hemisphere around +z) with n generators: Lloyd iterations over a
// Fibonacci point set, starting from a Fibonacci spiral of n points.
std::vector<Vec3> fibonacci(int n, bool sphere) {
  std::vector<Vec3> pts;
  const double golden = kPi * (3 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = sphere ? 1 - (2 * i + 1.0) / n : 1 - (i + 0.5) / n;
    const double r = std::sqrt(std::max(0.0, 1 - z * z));
    pts.emplace_back(r * std::cos(golden * i), r * std::sin(golden * i), z);
  }
  return pts;
}

std::vector<Vec3> cvt_generators(int n, bool sphere, int iterations) {
  std::vector<Vec3> gen = fibonacci(n, sphere);
  const std::vector<Vec3> pts = fibonacci(std::max(2000, 40 * n) * (sphere ? 2 : 1), sphere);
  std::vector<Vec3> sum(n);
  // Exact nearest-generator assignment, accelerated: if every point lies within angle D of its
  // previous owner, its nearest generator lies within 2D of that owner (triangle inequality), so
  // only those neighbours are searched.
  std::vector<int> owner(pts.size());
  for (size_t q = 0; q < pts.size(); ++q) {
    int best = 0;
    for (int g = 1; g < n; ++g)
      if (pts[q].dot(gen[g]) > pts[q].dot(gen[best])) best = g;
    owner[q] = best;
  }
  std::vector<std::vector<int>> near(n);
  for (int it = 0; it < iterations; ++it) {
    std::fill(sum.begin(), sum.end(), Vec3::Zero());
    for (size_t q = 0; q < pts.size(); ++q) sum[owner[q]] += pts[q];
    double moved = 0;
    for (int g = 0; g < n; ++g)
      if (sum[g].norm() > 0) {
        const Vec3 c = sum[g].normalized();
        moved = std::max(moved, (c - gen[g]).norm());
        gen[g] = c;
      }
    if (moved < 1e-5) break;
    // Reassign to the moved generators.
    double min_dot = 1.0;  // cos D
    for (size_t q = 0; q < pts.size(); ++q) min_dot = std::min(min_dot, pts[q].dot(gen[owner[q]]));
    const double D = std::acos(std::clamp(min_dot, -1.0, 1.0));
    const double cos2d = 2 * D >= kPi ? -2.0 : std::cos(2 * D);
    for (int g = 0; g < n; ++g) {
      near[g].clear();
      for (int h = 0; h < n; ++h)
        if (gen[g].dot(gen[h]) >= cos2d - 1e-12) near[g].push_back(h);
    }
    for (size_t q = 0; q < pts.size(); ++q) {
      int best = owner[q];
      double bd = pts[q].dot(gen[best]);
      for (int h : near[owner[q]]) {
        const double d = pts[q].dot(gen[h]);
        if (d > bd) {
          bd = d;
          best = h;
        }
      }
      owner[q] = best;
    }
  }
  return gen;
}

constexpr int kCvtIterations = 40;
constexpr int kMaxCameras = 5000;

// Area bound: caps of angular radius beta cannot cover the field of view with fewer cameras.
int area_bound(double beta, bool sphere) {
  const double cap = 2 * kPi * (1 - std::cos(beta));
  return std::max(1, static_cast<int>(std::floor((sphere ? 4 * kPi : 2 * kPi) / cap)));
}

}  // namespace

Design design_layered(const DesignParams& p) {
  check_params(p, true);
  const Checker chk(p, false);
  for (int floors = 1;; ++floors) {
    std::vector<int> layers;
    const std::vector<Vec3> axes = panoptic_floors(floors, layers);
    if (chk.covered(axes)) return finish(p, axes, layers, "layered");
    if (axes.size() > kMaxCameras) throw std::invalid_argument("layered: no design found");
  }
}

namespace {

// §3.4.1 with a given number of layers nl: layer i nominally at (2i+1) beta_fine, beta_fine =
// (pi/2) / (2 nl) (eq. 3.5). Returns false if no design was found.
// Gives up (returns false) as soon as the design would reach `limit` cameras.
bool min_cameras_with_layers(const Checker& chk, int nl, bool trim, size_t limit, std::vector<Vec3>& axes,
                             std::vector<int>& layers) {
  const double beta = chk.reach;
  const double beta_fine = (kPi / 2) / (2 * nl);  // eq. 3.5
  const double trim_step = deg2rad(0.5);
  axes.clear();
  layers.clear();
  double theta_uc = 0;  // everything above is covered by the layers placed so far
  for (int i = 0; i < nl; ++i) {
    const bool last = i + 1 == nl;
    const double next_centre = (2 * (i + 1) + 1) * beta_fine;
    // eq. 3.6 for the non-last layers, full coverage for the last one.
    double uc = 0;
    auto ok = [&](const std::vector<Vec3>& trial) {
      uc = first_uncovered_theta(trial, chk.s, beta, theta_uc);
      if (last) return std::isinf(uc);
      return next_centre - uc <= beta;
    };
    double polar = (2 * i + 1) * beta_fine;
    double offset = 0, placed_uc = 0;
    int n = 0;
    std::vector<Vec3> placed;
    const int max_n = static_cast<int>(std::ceil(2 * kPi / std::max(chk.s.step_rad, 0.02))) + 8;
    for (n = 1; n <= max_n; ++n) {
      if (axes.size() + n >= limit) return false;  // cannot beat the best design so far
      // Refinement 1: rotational search of the layer over one camera spacing (<= 60 steps).
      // The first layer has nothing to align with: all its rotations are equivalent.
      const int steps = i == 0 ? 1 : std::clamp(static_cast<int>(std::lround(360.0 / n)), 1, 60);
      bool found = false;
      for (int s = 0; s < steps && !found; ++s) {
        offset = 2 * kPi / n * s / steps;
        std::vector<Vec3> trial = axes;
        add_layer(trial, n, polar, offset);
        if (ok(trial)) {
          found = true;
          placed = std::move(trial);
          placed_uc = uc;
        }
      }
      if (found) break;
    }
    if (n > max_n) return false;
    // Refinement 2: trim the layer's latitude towards the equator while the condition holds
    // (not the last layer: there it cannot save a camera).
    while (trim && !last && polar + trim_step <= kPi / 2 + 1e-12) {
      std::vector<Vec3> trial = axes;
      add_layer(trial, n, polar + trim_step, offset);
      if (!ok(trial)) break;
      polar += trim_step;
      placed = std::move(trial);
      placed_uc = uc;
    }
    axes = std::move(placed);
    theta_uc = placed_uc;
    layers.push_back(n);
  }
  return true;
}

}  // namespace

Design design_min_cameras(const DesignParams& p) {
  check_params(p, true);
  const Checker chk(p, false);
  // eq. 3.3-3.4 give the least number of layers; with the 2-D gaps between the cameras of a layer
  // one more layer can need fewer cameras, so up to three more are tried and the design with the
  // fewest cameras is kept (ties: fewer layers).
  const int nv = static_cast<int>(std::ceil((kPi / 2) / (2 * chk.beta) - 1e-9));  // eq. 3.4
  std::vector<Vec3> best_axes, axes;
  std::vector<int> best_layers, layers;
  for (int nl = nv; nl <= nv + 3; ++nl)
    for (bool trim : {true, false}) {
      const size_t limit = best_axes.empty() ? std::numeric_limits<size_t>::max() : best_axes.size();
      if (!min_cameras_with_layers(chk, nl, trim, limit, axes, layers)) continue;
      if (best_axes.empty() || axes.size() < best_axes.size()) {
        best_axes = axes;
        best_layers = layers;
      }
    }
  if (best_axes.empty()) throw std::invalid_argument("min-cameras: no design found");
  return finish(p, best_axes, best_layers, "min-cameras");
}

Design design_cvt(const DesignParams& p) {
  check_params(p, true);
  const Checker chk(p, p.sphere);
  // Algorithm 1, one camera more at a time, starting at N_c = the area bound (no fewer caps of
  // radius beta can cover the field of view).
  for (int n = area_bound(chk.beta, p.sphere); n <= kMaxCameras; ++n) {
    const std::vector<Vec3> axes = cvt_generators(n, p.sphere, kCvtIterations);
    if (chk.covered(axes)) return finish(p, axes, {n}, "cvt");
  }
  throw std::invalid_argument("cvt: no design found");
}

Design design_rig(Method m, const DesignParams& p) {
  switch (m) {
    case Method::kLayered:
      return design_layered(p);
    case Method::kMinCameras:
      return design_min_cameras(p);
    case Method::kMaxVolume:
      return design_max_volume(p);
    case Method::kCvt:
      return design_cvt(p);
  }
  throw std::invalid_argument("unknown method");
}

int cameras_needed(Method m, const DesignParams& p) {
  DesignParams q = p;
  q.compute_r_virtual = false;
  return static_cast<int>(design_rig(m, q).rig.cameras.size());
}

}  // namespace omma::design
