// Manufacturing errors for the simulator: a "true" rig that differs from the nominal one.
//
// Spec (the --perturb option): comma-separated KEY=VALUE, any subset of
//   orient=DEG   each camera frame turned by exactly DEG degrees about a random axis
//   focal=REL    fu and fv both scaled by (1 + REL) or (1 - REL) (random sign, same for fu and fv)
//   center=PX    principal point (cu, cv) moved by exactly PX pixels in a random direction
//   k1=V         radial distortion k1 increased by V (eq. 5.24)
//   pos=MM       camera position moved by exactly MM millimetres in a random direction
// Every camera's error has exactly the given magnitude, with a random direction or sign drawn from
// (seed, camera id), so the true rig is reproducible. The angle of view is unchanged.
#pragma once

#include <cstdint>
#include <string>

#include "omma/core/rig.h"

namespace omma::sim {

struct PerturbSpec {
  double orient_deg = 0;
  double focal_rel = 0;
  double center_px = 0;
  double k1 = 0;
  double position_mm = 0;
  bool any() const {
    return orient_deg != 0 || focal_rel != 0 || center_px != 0 || k1 != 0 || position_mm != 0;
  }
};

// Parses "orient=0.5,focal=0.02,center=3,k1=-0.05,pos=0.1"; "" gives no perturbation. Throws
// std::invalid_argument naming the bad item (unknown key, not a number, negative magnitude,
// focal >= 1, orient > 45).
PerturbSpec parse_perturb(const std::string& spec);
std::string to_string(const PerturbSpec& spec);

// The true rig: a copy of `nominal` with every camera perturbed as above (validated).
Rig perturb_rig(const Rig& nominal, const PerturbSpec& spec, uint64_t seed);

// The same errors, but random in size: each drawn from a normal distribution whose RMS is the spec's
// value (orientation: a rotation about a random axis with RMS angle orient_deg; focal: fu and fv
// scaled by 1 + focal_rel * N(0, 1); centre: RMS displacement center_px; k1: k1 * N(0, 1) added;
// position unchanged), all drawn in camera order from one generator seeded with `seed`. The name is
// kept. The calibration tests' manufacturing errors.
Rig perturb_rig_rms(const Rig& nominal, const PerturbSpec& rms, uint64_t seed);

}  // namespace omma::sim
