// What software computes and loads into the chip: the sin/cos ROM contents, each camera's
// registers quantised from a (calibrated) rig, and the vignetting memory; and the way back
// (registers -> rig) for `omma hw import`. This is the only part of the model that uses floating
// point: it runs on the host, before the datapath (docs/hw-model.md §3).
#pragma once

#include <functional>
#include <vector>

#include "omma/core/rig.h"
#include "omma/hw/blocks.h"

namespace omma::hw {

// The ROMs of blocks.h SinCosRom: round half up of sin/cos(i (pi/2) / 2^T) * 2^(W-1).
SinCosRom make_sincos_rom(const HwConfig& cfg);

// Quantises one camera (round half up of value * 2^frac for every register, see CameraRegs).
// Throws std::invalid_argument naming the camera and field if a value does not fit its register.
CameraRegs camera_regs(const HwConfig& cfg, const RigCamera& cam);
std::vector<CameraRegs> camera_regs(const HwConfig& cfg, const Rig& rig);

// Registers -> rig camera (for import): t, u, v re-orthonormalised (the quantised vectors are unit
// to within 2^-V), aov = 2 acos(cos_half_aov), every other field value / 2^frac.
RigCamera camera_from_regs(const HwConfig& cfg, const CameraRegs& r, int id);

// A per-camera photometric model (radial vignetting and channel gains; vignetting_from_rig below
// makes one from the rig's core/photometric.h model). Given camera index and the normalised radius rho = r /
// r_max in [0, 1] (r_max = distance from the principal point to the farthest image corner), returns the gain
// that CORRECTS the fall-off (>= 1 towards the corners); channel_gain returns the R, G, B correction. The
// default (empty functions) gives unit tables: the correction is an exact no-op.
struct VignettingModel {
  std::function<double(int camera, double rho)> radial;
  std::function<std::array<double, 3>(int camera)> channel_gain;
};

// r_max of a camera (pixels, at least 1): the distance from its principal point to the farthest
// image corner, the radius that the vignetting table's rho = 1 stands for.
double vignetting_rmax(const Intrinsics& in);

// Fills the vignetting memory: vig_shift = the smallest shift that maps the largest squared radius
// of any camera (corner to principal point) below 2^vig_addr_bits; entry i holds the gain at
// rho = sqrt((i + 0.5) * 2^vig_shift) / r_max (uQ2.14, saturated at 4 - 2^-14).
VignettingTables make_vignetting_tables(const HwConfig& cfg, const Rig& rig,
                                        const VignettingModel& model = {});

// The rig's photometric model (core/photometric.h) as a VignettingModel:
//   radial(cam, rho)  = (1 / V(r))^e   at the pixel radius r = rho * r_max(cam) from the model's
//                       vignetting centre (the table is indexed by the distance from the principal
//                       point: a centre offset between the two is not represented, see docs/hw-model.md),
//   channel_gain(cam) = (1 / gain_c)^e  for c = R, G, B (the model stores B, G, R).
// e = 1 where the frame memories hold linear values (the thesis's front end keeps the linear MSBs,
// `omma isp --linear-output`), e = kSrgbVignettingExponent where they hold sRGB codes (omma's
// frames): the power-law approximation of dividing in linear light, sRGB ~ linear^(1/2.2).
// Cameras without a model get 1.0 (no correction); an empty model if no camera has one.
inline constexpr double kSrgbVignettingExponent = 1 / 2.2;
VignettingModel vignetting_from_rig(const Rig& rig, double exponent);

}  // namespace omma::hw
