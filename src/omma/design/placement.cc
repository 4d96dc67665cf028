#include "omma/design/placement.h"

#include <algorithm>
#include <cmath>
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
    case Method::kLayered: return "layered";
    case Method::kMinCameras: return "min-cameras";
    case Method::kMaxVolume: return "max-volume";
    case Method::kCvt: return "cvt";
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
  l.d_cam_mm = std::hypot(cam.width_mm, cam.height_mm);                                // eq. 3.7
  const int nv = static_cast<int>(std::floor(kPi / 2 * l.r_in_mm / l.d_cam_mm + 1e-9));  // eq. 3.8
  if (nv < 1) throw std::invalid_argument("max-volume: not even one camera fits on the dome");
  l.beta_rad = (kPi / 2) / (2 * nv);                                                   // eq. 3.9
  for (int i = 1; i <= nv; ++i) {
    const double polar = (2 * i - 1) * l.beta_rad;                                     // eq. 3.10
    const int nh = static_cast<int>(
        std::floor(2 * kPi * l.r_in_mm * std::sin(polar) / l.d_cam_mm + 1e-9));           // eq. 3.11
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
  for (int k = 0; k < n; ++k)
    axes.push_back(direction_from_spherical(polar, offset + 2 * kPi * k / n));
}

}  // namespace

std::vector<double> search_layer_offsets(const std::vector<int>& counts,
                                         const std::vector<double>& polar, bool sphere) {
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
        const double r = covering_radius(axes_for(trial), coarse);
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
  d.r_virtual_mm = virtual_radius(d.rig, p.check_step_rad);
  return d;
}

}  // namespace omma::design
