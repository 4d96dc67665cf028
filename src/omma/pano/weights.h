// Static (geometry-only) blending weights per output pixel: the taps that both the reference
// stitcher (pano/) and the compiled maps of the engine (engine/) use.
#pragma once

#include <vector>

#include "omma/core/grid.h"
#include "omma/pano/contributors.h"
#include "omma/pano/method.h"

namespace omma::pano {

struct BlendParams {
  SearchOptions search;
  double gaussian_sigma_mm = 1.0;  // sigma_d of eq. 2.9, mm (on the w-plane)
};

struct Tap {
  int camera = 0;   // index into rig.cameras
  Vec2 px;          // continuous pixel coordinate in that camera
  double weight = 0;
};

// Taps of output pixel (col, row) for a static method (nn, linear, gaussian, mrf, mrf-spherical);
// the weights sum to 1; empty if no camera sees the direction. For sad (per-frame weights) this
// returns the contributors with linear weights.
std::vector<Tap> static_taps(const Rig& rig, const PanoGrid& grid, int col, int row, Method method,
                             const BlendParams& params = {});

}  // namespace omma::pano
