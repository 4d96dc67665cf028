// The built-in rigs: the thesis's 24-camera prototype dome (§3.4.2, Fig. 3.8, Table 3.1) and the
// 44-camera Giga-Eye (ch. 7) with its sensor modes (Table 7.1).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "omma/core/rig.h"

namespace omma::design {

// The prototype: max-volume placement (eq. 3.7-3.11) of 1 x 1 x 2 mm cameras on a 5 mm outer
// radius (inner radius 3 mm), layers of 3, 9 and 12 cameras at polar angles 15, 45 and 75 deg.
// Every camera: 250 x 250 px, AOV 64 deg, fu = fv = Intrinsics::focal_for_aov(250, 64 deg)
// (= 200.04 px), principal point (125, 125), no distortion; pinhole on the dome surface at 5 mm
// along its radial optical axis t; image "down" (+v) points away from the pole (projection of -z),
// image +x (u) = v x t. Camera ids 0..23 go layer by layer from the pole, and within a layer by
// increasing azimuth. The layers' azimuth offsets are fixed values chosen to minimise R_vir
// (see kPrototypeLayerOffsetsDeg in prototype.cc). Deterministic; name "thesis-24".
Rig thesis_prototype_rig();

// ---------------------------------------------------------------------------------------------
// Giga-Eye (thesis ch. 7, ../shared/notes/gigaeye-spec.md §1-2): 44 cameras in layers of 1, 6, 15 and 22 at
// polar angles 0, 39.6, 59.3 and 80.8 deg, evenly spaced in azimuth (60, 24, 16.36 deg), pinholes
// on a 200 mm sphere along their radial optical axes. Every camera: 2592 x 1944 px (5 MP), angle of
// view 53 x 43 deg through the image centre (fu = 1296 / tan 26.5 deg = 2599.6 px, fv = 972 /
// tan 21.5 deg = 2463.3 px: the thesis's two angles taken at their word, so the pixels are not
// square; square 2.2 um pixels behind a 6 mm lens would give 50.8 x 39.2 deg), no distortion, and
// a rectangular field of view (Intrinsics::Field::kImage): the camera search uses the image bounds.
// The thesis does not give the layers' azimuth offsets nor the camera roll; they are chosen by
// coverage (kGigaEyeLayout in prototype.cc, found by search_gigaeye_layout). Camera ids: 0 = the
// zenith camera, then layer by layer downwards, by increasing azimuth. Name "gigaeye-44".
struct GigaEyeLayout {
  double offset_deg[4] = {0, 0, 0, 0};  // azimuth of each layer's first camera (layer 0 = zenith)
  double zenith_roll_deg = 0;           // rotation of the zenith camera about +z
  bool portrait = false;                // ring cameras: false = 53 deg along the azimuth
};
GigaEyeLayout gigaeye_layout();  // the chosen one
Rig gigaeye_rig(const GigaEyeLayout& layout = gigaeye_layout());

// Objective of the layout choice at `distance_mm` (may be +infinity) on a `step_rad` sampling of
// polar 0..100 deg: the solid angle (sr) seen by >= 2 cameras, then by >= 1 (tie-break), as one
// number: sr2 + 1e-3 sr1.
double gigaeye_layout_score(const GigaEyeLayout& layout, double distance_mm, double step_rad);
// Coordinate search over the layout (offsets of layers 1-2 on a 1 deg grid within their period,
// the zenith roll on 5 deg, both rolls of the ring cameras) maximising gigaeye_layout_score.
GigaEyeLayout search_gigaeye_layout(double distance_mm, double step_rad);

// Sensor modes of the Table 7.1 rows (notes §1): skipping keeps the field of view and divides the
// resolution by skip + 1 (binning adds the skipped pixels: same geometry); a sub-window keeps the
// focal length and crops a centred window (1024 x 768 gives 22.4 x 17.7 deg; thesis "21 x 16").
struct SensorMode {
  int skip = 0;                             // register value n: sub-sampling by n + 1 (0..7; even sizes)
  bool bin = false;                         // binning with the skipping (geometry unchanged)
  int window_width = 0, window_height = 0;  // centred sub-window of the full sensor; 0 = full
  std::string name() const;                 // "full", "skip1", "skip1-bin", "window1024x768", ...
};
// The rig as seen in a sensor mode (every camera; validated). Throws std::invalid_argument.
Rig derive_sensor_mode(const Rig& full, const SensorMode& mode);

// Built-in rigs by name: "thesis-24", "gigaeye-44", "gigaeye-44-skipN" (skip1 = 1296 x 972 of
// Table 7.1 rows 3-6, skip2 = 864 x 648 of row 7; skip3 = 648 x 486 and skip5 = 432 x 324 are
// simulation sizes: the sizes must stay even), "gigaeye-44-window" (1024 x 768 of row 8); nullopt
// for other names.
std::optional<Rig> builtin_rig(const std::string& name);
std::vector<std::string> builtin_rig_names();
// A rig file if `spec` names an existing file, else a built-in rig; RigError otherwise.
Rig load_rig_or_builtin(const std::string& spec);

}  // namespace omma::design
