// Camera placement on a dome (thesis §2.4.2 and §3.3-3.4): four designers, each producing a valid
// Rig of radial cameras whose pinholes sit on the outer dome surface (radius r_phys).
//   layered      the earlier "Panoptic" method [64, 65] (§2.4.2, §3.3): a camera at the pole and
//                whole floors of tightly packed circular camera faces; a whole floor is added
//                whenever the coverage at r_virtual fails.
//   min-cameras  §3.4.1, eq. 3.1-3.6: layers at (2i+1) beta_fine, cameras added one at a time per
//                layer with a rotational search until eq. 3.6 holds, then the layer's latitude is
//                trimmed towards the equator; the last layer is filled until the whole field of
//                view is covered at r_virtual.
//   max-volume   §3.4.2, eq. 3.7-3.11: as many cameras of the given size as fit on the inner
//                radius r_in = r_phys - l_cam.
//   cvt          §3.4.3, Algorithm 1: centroidal Voronoi tessellation of the sphere (or
//                hemisphere) with one more camera until the coverage at r_virtual is reached.
// Units: mm and radians inside; the CLI converts degrees.
#pragma once

#include <string>
#include <vector>

#include "omma/core/rig.h"

namespace omma::design {

enum class Method { kLayered, kMinCameras, kMaxVolume, kCvt };
Method parse_method(const std::string& name);  // "layered" | "min-cameras" | "max-volume" | "cvt"
std::string to_string(Method m);

struct CameraSize {
  double width_mm = 1.0, height_mm = 1.0, length_mm = 2.0;  // W x H sensor face, L pinhole..back
};
// Parses "WxHxL" in mm (e.g. "1x1x2", "1x1x1.85"); throws std::invalid_argument.
CameraSize parse_camera_size(const std::string& text);

struct DesignParams {
  double aov_rad = deg2rad(64);   // full angle of view of every camera (Table 3.1)
  double r_phys_mm = 5.0;         // outer dome radius, where the pinholes sit
  double r_virtual_mm = 18.0;     // overlap distance to reach (not used by max-volume)
  CameraSize cam;                 // used by max-volume only
  bool sphere = false;            // full sphere instead of the hemisphere around +z
  int width = 250, height = 250;  // pixels of every camera (Table 3.1)
  // Angular sampling (radians) of the field of view used by the designers' coverage checks. The
  // checks are conservative: a design passes only if the largest sampled gap plus the sampling
  // radius is within reach, so the rig also passes a finer coverage analysis.
  double check_step_rad = deg2rad(0.5);
  // Run the coverage analysis of the result (Design::r_virtual_mm); sweeps that only need the
  // count switch it off.
  bool compute_r_virtual = true;
};

struct Design {
  Rig rig;
  std::vector<int> layers;  // cameras per layer from the pole (one entry for cvt: all cameras)
  double r_virtual_mm = 0;  // overlap distance of the produced rig (coverage analysis; 0 if off)
};

// max-volume layer counts, eq. 3.7-3.11: d_cam = sqrt(w^2 + h^2), N_v = floor(pi/2 r_in / d_cam),
// beta = pi/2 / (2 N_v), N_h,i = floor(2 pi r_in sin((2i-1) beta) / d_cam), i = 1..N_v.
// For a sphere the southern layers mirror the northern ones.
struct MaxVolumeLayout {
  double r_in_mm = 0, d_cam_mm = 0, beta_rad = 0;
  std::vector<int> per_layer;     // N_h,i
  std::vector<double> polar_rad;  // (2i-1) beta
};
MaxVolumeLayout max_volume_layout(double r_phys_mm, const CameraSize& cam);

// The four designers. Each throws std::invalid_argument for impossible parameters (e.g. an
// r_virtual that no number of cameras can reach: r_virtual <= r_phys * sin(aov/2) / ...).
Design design_layered(const DesignParams& p);
Design design_min_cameras(const DesignParams& p);
Design design_max_volume(const DesignParams& p);
Design design_cvt(const DesignParams& p);
Design design_rig(Method m, const DesignParams& p);

// Only the camera count (faster; used by sweeps). Same result as design_rig(m, p).rig.cameras.size().
int cameras_needed(Method m, const DesignParams& p);

}  // namespace omma::design
