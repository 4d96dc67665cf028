#include "omma/hw/hw_config.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "omma/core/valid.h"

namespace omma::hw {
namespace {

bool in_range(int v, int lo, int hi) { return v >= lo && v <= hi; }

}  // namespace

bool HwConfig::IsValid(std::string* error) const {
  auto range = [&](const char* name, int v, int lo, int hi) {
    return in_range(v, lo, hi)
               ? true
               : invalid(error, fmt::format("{} = {} is out of range [{}, {}]", name, v, lo, hi));
  };
  if (!range("angle_bits", angle_bits, 4, 32)) return false;
  if (!range("sincos_addr_bits", sincos_addr_bits, 2, 20)) return false;
  if (!range("sincos_word_bits", sincos_word_bits, 4, 24)) return false;
  if (angle_bits < sincos_addr_bits + 2)
    return invalid(error,
                   fmt::format("sincos_addr_bits = {} needs angle_bits >= {} (quadrant + table address), "
                               "angle_bits is {}",
                               sincos_addr_bits, sincos_addr_bits + 2, angle_bits));
  if (!range("vec_frac_bits", vec_frac_bits, 2, 14)) return false;
  if (!range("pos_frac_bits", pos_frac_bits, 0, 14)) return false;
  if (!range("dist_frac_bits", dist_frac_bits, 2, 16)) return false;
  if (dist_frac_bits < pos_frac_bits)
    return invalid(error, fmt::format("dist_frac_bits = {} must be >= pos_frac_bits = {}", dist_frac_bits,
                                      pos_frac_bits));
  if (!range("camera_bits", camera_bits, 1, 8)) return false;
  if (!range("max_contributors", max_contributors, 1, 8)) return false;
  if (!range("proj_bits", proj_bits, 8, 24)) return false;
  if (!range("proj_frac_bits", proj_frac_bits, 2, 20)) return false;
  if (proj_frac_bits > proj_bits - 2)
    return invalid(error,
                   fmt::format("proj_frac_bits = {} leaves no integer bits in proj_bits = {} (need <= {})",
                               proj_frac_bits, proj_bits, proj_bits - 2));
  if (!range("k_frac_bits", k_frac_bits, 2, 15)) return false;
  if (!range("focal_frac_bits", focal_frac_bits, 0, 8)) return false;
  if (!range("centre_frac_bits", centre_frac_bits, 0, 8)) return false;
  if (!range("pix_frac_bits", pix_frac_bits, 1, 10)) return false;
  if (!range("frame_addr_bits", frame_addr_bits, 4, 24)) return false;
  if (!range("sample_frac_bits", sample_frac_bits, 0, 8)) return false;
  if (sample_frac_bits > 2 * pix_frac_bits)
    return invalid(error,
                   fmt::format("sample_frac_bits = {} exceeds the {} fraction bits of a bilinear product "
                               "(2 * pix_frac_bits)",
                               sample_frac_bits, 2 * pix_frac_bits));
  if (!range("weight_mant_bits", weight_mant_bits, 4, 24)) return false;
  if (!range("recip_bits", recip_bits, 2, 24)) return false;
  if (!range("vig_addr_bits", vig_addr_bits, 1, 12)) return false;
  if (!range("vig_frac_bits", vig_frac_bits, 14, 14)) return false;
  if (!range("boundary_threshold", boundary_threshold, 0, 255)) return false;
  return true;
}

void HwConfig::Check() const {
  std::string err;
  if (!IsValid(&err)) throw std::invalid_argument("hardware configuration: " + err);
}

HwConfig thesis_config() {
  HwConfig c;
  c.angle_bits = 13;        // Table 6.7: 13-bit angle registers
  c.sincos_addr_bits = 11;  // Table 6.4/6.8: 2048 x 16-bit sin and cos ROMs (quarter wave)
  c.sincos_word_bits = 16;
  c.proj_bits = 16;  // "a 16-bit precision is used for the variables in (5.21) to (5.27)"
  c.proj_frac_bits = 13;
  return c;
}

void check_rig(const HwConfig& cfg, const Rig& rig) {
  cfg.Check();
  const size_t max_cams = size_t{1} << cfg.camera_bits;
  if (rig.cameras.empty()) throw std::invalid_argument("the rig has no cameras");
  if (rig.cameras.size() > max_cams)
    throw std::invalid_argument(
        fmt::format("the rig has {} cameras, the camera search priority encoder holds {} (camera_bits = {})",
                    rig.cameras.size(), max_cams, cfg.camera_bits));
  for (const RigCamera& cam : rig.cameras) {
    const Intrinsics& in = cam.in;
    const int64_t pixels = int64_t{in.width} * in.height;
    if (pixels > (int64_t{1} << cfg.frame_addr_bits))
      throw std::invalid_argument(fmt::format(
          "camera {}: a {}x{} frame ({} pixels) does not fit the frame address space of 2^{} words "
          "(frame_addr_bits)",
          cam.id, in.width, in.height, pixels, cfg.frame_addr_bits));
    // Pixel coordinates uQ(ceil log2 W).F must fit the 16-bit "precision" budget plus the sign.
    auto fits16u = [&](const char* field, double value, int frac) {
      const double q = std::floor(value * std::ldexp(1.0, frac) + 0.5);
      if (!(q >= 0 && q <= 65535))
        throw std::invalid_argument(
            fmt::format("camera {}: {} = {} does not fit a 16-bit register with {} fraction bits (max {})",
                        cam.id, field, value, frac, 65535 / std::ldexp(1.0, frac)));
    };
    auto fits16s = [&](const char* field, double value, int frac) {
      const double q = std::floor(value * std::ldexp(1.0, frac) + 0.5);
      if (!(q >= -32768 && q <= 32767))
        throw std::invalid_argument(fmt::format(
            "camera {}: {} = {} does not fit a signed 16-bit register with {} fraction bits (|x| < {})",
            cam.id, field, value, frac, 32768 / std::ldexp(1.0, frac)));
    };
    fits16u("fu", in.fu, cfg.focal_frac_bits);
    fits16u("fv", in.fv, cfg.focal_frac_bits);
    fits16u("cu", in.cu, cfg.centre_frac_bits);
    fits16u("cv", in.cv, cfg.centre_frac_bits);
    static const char* kNames[5] = {"k1", "k2", "k3", "k4", "k5"};
    for (int i = 0; i < 5; ++i) fits16s(kNames[i], in.k[i], cfg.k_frac_bits);
    static const char* kPos[3] = {"position_mm.x", "position_mm.y", "position_mm.z"};
    for (int i = 0; i < 3; ++i) fits16s(kPos[i], cam.position_mm[i], cfg.pos_frac_bits);
    // |r| <= |c| must fit the 18-bit uQ(17-D).D distance.
    const double dmax = std::ldexp(1.0, 18 - cfg.dist_frac_bits);
    if (cam.position_mm.norm() >= dmax)
      throw std::invalid_argument(
          fmt::format("camera {}: |position| = {} mm does not fit the 18-bit distance uQ{}.{} (< {} mm)",
                      cam.id, cam.position_mm.norm(), 18 - cfg.dist_frac_bits, cfg.dist_frac_bits, dmax));
    // Normalised coordinates inside the cone: |x|, |y| <= tan(aov/2); x' adds the distortion.
    const double t = std::tan(std::min(in.aov / 2, deg2rad(89.9)));
    double r2 = 2 * t * t, p = 1 + in.k[0] * r2 + in.k[1] * r2 * r2 + in.k[4] * r2 * r2 * r2;
    const double xd = std::abs(p) * t + 2 * (std::abs(in.k[2]) + std::abs(in.k[3])) * 2 * r2;
    const double lim = std::ldexp(1.0, cfg.proj_bits - cfg.proj_frac_bits - 1);
    if (std::max({2 * t * t, xd, std::abs(p)}) >= lim)
      throw std::invalid_argument(fmt::format(
          "camera {}: the normalised image coordinates of a {:.1f} deg cone (and R^2 = {:.3f}) need more "
          "integer bits than proj_bits - proj_frac_bits = {} allow (|x| < {})",
          cam.id, rad2deg(in.aov), r2, cfg.proj_bits - cfg.proj_frac_bits, lim));
  }
}

void check_grid(const HwConfig& cfg, const PanoGrid& grid) {
  cfg.Check();
  if (grid.width <= 0 || grid.height <= 0) throw std::invalid_argument("panorama size must be positive");
  if (grid.width > 65535 || grid.height > 65535)
    throw std::invalid_argument("panorama width and height must be below 65536 (16-bit counters)");
  // One angle code per pixel step at least: span / N >= 2 pi / 2^M.
  const double turn = std::ldexp(1.0, cfg.angle_bits);
  const AngularSpan span = angular_span(grid.projection);
  const double col_span = span.width / (2 * kPi), row_span = span.height / (2 * kPi);
  if (turn * col_span / grid.width < 1 || turn * row_span / grid.height < 1)
    throw std::invalid_argument(
        fmt::format("angle_bits = {} gives less than one angle code per pixel step of a {}x{} {} panorama",
                    cfg.angle_bits, grid.width, grid.height, to_string(grid.projection)));
}

}  // namespace omma::hw
