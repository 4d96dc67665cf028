// The per-camera photometric model: how a camera's linear signal relates to the
// scene's radiance, the one source of truth for every stage that corrects it (stitcher, ISP,
// engine, calibration, PTO export, the hardware model's vignetting tables).
//
//   signal_c(px) = gain_c * V(px) * radiance_c(px)          (linear light, channel c in B, G, R)
//   V(px) = 1 + b r^2 + c r^4 + d r^6,                       r = |px - centre| / r_norm
//   centre = (W/2 + x, H/2 + y)   (pixel-centre convention of conventions.h: pixel (i, j) has its
//                                  centre at (i + 0.5, j + 0.5), so W/2 is the image's middle)
//   r_norm = sqrt((W/2)^2 + (H/2)^2)   (half the diagonal: r = 1 in the corners of a centred image)
//
// This is Hugin's radial vignetting model (Va = 1, Vb = b, Vc = c, Vd = d, Vx = x, Vy = y in pixels;
// libpano's/Hugin's centre (W-1)/2 + Vx with pixel centres at integers is the same point), and
// the gains are Hugin's exposure and white balance: gain_G = 2^-Eev, gain_R = 2^-Eev * Er, gain_B =
// 2^-Eev * Eb (calib/pto.h writes and reads them). The model describes the camera; correcting a
// frame divides its LINEAR signal by gain_c * V (frames are sRGB-encoded: decode, divide, encode;
// isp/photometric.h). Gains and vignetting are defined up to one global scale of the rig's gains:
// the calibration (calib/photometric.h) fixes V(centre) = 1 and the geometric mean of all gains = 1.
//
// Rig file (rig.h), optional per camera:
//   "photometric": {"vignetting": [b, c, d], "vignetting_center_px": [x, y], "gains_bgr": [B, G, R]}
// A camera without it (std::nullopt) is not corrected.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "omma/core/geometry.h"

namespace omma {

struct Photometric {
  std::array<double, 3> vignetting{0, 0, 0};  // b, c, d of V = 1 + b r^2 + c r^4 + d r^6
  Vec2 center_px = Vec2::Zero();              // (x, y): the vignetting centre's offset from (W/2, H/2)
  std::array<double, 3> gains{1, 1, 1};       // linear gain per channel, B, G, R order

  bool is_identity() const;
  bool operator==(const Photometric& o) const;
};

// Normalised radius r of continuous pixel coordinate (col, row) (see above).
double vignetting_radius(const Photometric& p, int width, int height, double col, double row);
// The falloff V at continuous pixel coordinate (col, row): pixel (i, j)'s value is at (i + 0.5,
// j + 0.5). The one function every stage evaluates (hardware tables included).
double vignetting_falloff(const Photometric& p, int width, int height, double col, double row);
// The smallest V over the image (pixel centres and corners; the polynomial in r^2 is checked at
// its interior critical points too). Used by validation and to size fixed-point gain tables.
double min_vignetting_falloff(const Photometric& p, int width, int height);

// Fits the vignetting coefficients (b, c, d) of V = 1 + b s + c s^2 + d s^3 (s = r^2) to samples
// (s_i, v_i), v_i > 0, minimising the LARGEST relative error |V(s_i) / v_i - 1| (minimax, by
// Lawson's iteratively reweighted least squares): a smooth falloff such as cos^4 is then matched
// evenly over the field instead of worst in the corners. *max_rel_error gets that error.
std::array<double, 3> fit_vignetting(const std::vector<double>& s, const std::vector<double>& v,
                                     double* max_rel_error = nullptr);

// Throws std::invalid_argument with a message naming `where` if a number is not finite, a gain
// is not positive, the centre offset is beyond the image, or V reaches 0.02 or less (or exceeds 50)
// anywhere on the image (a falloff that reaches zero cannot be divided out).
void validate_photometric(const Photometric& p, int width, int height, const std::string& where);

}  // namespace omma
