#include "omma/hw/tables.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "omma/core/photometric.h"

namespace omma::hw {
namespace {

int64_t quantise(double v, int frac) {
  return static_cast<int64_t>(std::floor(v * std::ldexp(1.0, frac) + 0.5));
}

int32_t reg_s16(double v, int frac, int cam_id, const char* field) {
  const int64_t q = quantise(v, frac);
  if (q < -32768 || q > 32767)
    throw std::invalid_argument(
        fmt::format("camera {}: {} = {} does not fit a signed 16-bit register with {} "
                    "fraction bits",
                    cam_id, field, v, frac));
  return static_cast<int32_t>(q);
}

uint32_t reg_u16(double v, int frac, int cam_id, const char* field) {
  const int64_t q = quantise(v, frac);
  if (q < 0 || q > 65535)
    throw std::invalid_argument(
        fmt::format("camera {}: {} = {} does not fit an unsigned 16-bit register with {} "
                    "fraction bits",
                    cam_id, field, v, frac));
  return static_cast<uint32_t>(q);
}

}  // namespace

SinCosRom make_sincos_rom(const HwConfig& cfg) {
  SinCosRom rom;
  rom.addr_bits = cfg.sincos_addr_bits;
  rom.word_bits = cfg.sincos_word_bits;
  const int n = 1 << cfg.sincos_addr_bits;
  rom.sin_rom.resize(n);
  rom.cos_rom.resize(n);
  const double scale = std::ldexp(1.0, cfg.sincos_word_bits - 1);  // uQ1.(W-1)
  for (int i = 0; i < n; ++i) {
    const double a = (kPi / 2) * i / n;
    rom.sin_rom[i] = static_cast<uint32_t>(std::floor(std::sin(a) * scale + 0.5));
    rom.cos_rom[i] = static_cast<uint32_t>(std::floor(std::cos(a) * scale + 0.5));
  }
  return rom;
}

CameraRegs camera_regs(const HwConfig& cfg, const RigCamera& cam) {
  CameraRegs r;
  const int V = cfg.vec_frac_bits;
  static const char* kT[3] = {"t.x", "t.y", "t.z"};
  static const char* kU[3] = {"u.x", "u.y", "u.z"};
  static const char* kV[3] = {"v.x", "v.y", "v.z"};
  static const char* kC[3] = {"position_mm.x", "position_mm.y", "position_mm.z"};
  for (int k = 0; k < 3; ++k) {
    r.t[k] = reg_s16(cam.frame.t[k], V, cam.id, kT[k]);  // sQ1.V
    r.u[k] = reg_s16(cam.frame.u[k], V, cam.id, kU[k]);
    r.v[k] = reg_s16(cam.frame.v[k], V, cam.id, kV[k]);
    r.c[k] = reg_s16(cam.position_mm[k], cfg.pos_frac_bits, cam.id, kC[k]);  // sQ.Pp mm
  }
  r.cos_half_aov = reg_s16(std::cos(cam.in.aov / 2), V, cam.id, "cos(aov/2)");
  static const char* kK[5] = {"k1", "k2", "k3", "k4", "k5"};
  for (int k = 0; k < 5; ++k) r.k[k] = reg_s16(cam.in.k[k], cfg.k_frac_bits, cam.id, kK[k]);
  r.fu = reg_u16(cam.in.fu, cfg.focal_frac_bits, cam.id, "fu");
  r.fv = reg_u16(cam.in.fv, cfg.focal_frac_bits, cam.id, "fv");
  r.cu = reg_u16(cam.in.cu, cfg.centre_frac_bits, cam.id, "cu");
  r.cv = reg_u16(cam.in.cv, cfg.centre_frac_bits, cam.id, "cv");
  r.width = cam.in.width;
  r.height = cam.in.height;
  return r;
}

std::vector<CameraRegs> camera_regs(const HwConfig& cfg, const Rig& rig) {
  check_rig(cfg, rig);
  std::vector<CameraRegs> out;
  out.reserve(rig.cameras.size());
  for (const auto& c : rig.cameras) out.push_back(camera_regs(cfg, c));
  return out;
}

RigCamera camera_from_regs(const HwConfig& cfg, const CameraRegs& r, int id) {
  RigCamera cam;
  cam.id = id;
  const double sv = std::ldexp(1.0, -cfg.vec_frac_bits);
  Vec3 t(r.t[0] * sv, r.t[1] * sv, r.t[2] * sv), u(r.u[0] * sv, r.u[1] * sv, r.u[2] * sv);
  // Re-orthonormalise: t exact direction, u orthogonalised against t, v = t x u (right-handed).
  t.normalize();
  u = (u - u.dot(t) * t).normalized();
  cam.frame.t = t;
  cam.frame.u = u;
  cam.frame.v = t.cross(u);
  const double sp = std::ldexp(1.0, -cfg.pos_frac_bits);
  cam.position_mm = Vec3(r.c[0] * sp, r.c[1] * sp, r.c[2] * sp);
  cam.in.width = r.width;
  cam.in.height = r.height;
  const double sf = std::ldexp(1.0, -cfg.focal_frac_bits), sc = std::ldexp(1.0, -cfg.centre_frac_bits);
  cam.in.fu = r.fu * sf;
  cam.in.fv = r.fv * sf;
  cam.in.cu = r.cu * sc;
  cam.in.cv = r.cv * sc;
  for (int k = 0; k < 5; ++k) cam.in.k[k] = r.k[k] * std::ldexp(1.0, -cfg.k_frac_bits);
  cam.in.aov = 2 * std::acos(std::clamp(r.cos_half_aov * sv, -1.0, 1.0));
  return cam;
}

double vignetting_rmax(const Intrinsics& in) {
  return std::max(1.0, std::hypot(std::max(in.cu, in.width - in.cu), std::max(in.cv, in.height - in.cv)));
}

VignettingTables make_vignetting_tables(const HwConfig& cfg, const Rig& rig, const VignettingModel& model) {
  VignettingTables vt;
  // Largest squared radius (pixels) of any camera: the farthest corner from the principal point.
  double r2max = 1;
  std::vector<double> rmax(rig.cameras.size(), 1.0);
  for (size_t i = 0; i < rig.cameras.size(); ++i) {
    const Intrinsics& in = rig.cameras[i].in;
    const double dx = std::max(in.cu, in.width - in.cu), dy = std::max(in.cv, in.height - in.cv);
    rmax[i] = vignetting_rmax(in);
    r2max = std::max(r2max, dx * dx + dy * dy);
  }
  vt.vig_shift = 0;
  while (std::ldexp(1.0, cfg.vig_addr_bits + vt.vig_shift) <= r2max) ++vt.vig_shift;
  const double one = std::ldexp(1.0, cfg.vig_frac_bits);
  auto q = [&](double g) {
    return static_cast<uint32_t>(std::clamp(std::floor(g * one + 0.5), 0.0, 4 * one - 1));  // uQ2.14
  };
  vt.radial.assign(rig.cameras.size(), std::vector<uint32_t>(cfg.vig_entries(), q(1.0)));
  vt.channel.assign(rig.cameras.size(), {q(1.0), q(1.0), q(1.0)});
  for (size_t i = 0; i < rig.cameras.size(); ++i) {
    if (model.radial)
      for (int e = 0; e < cfg.vig_entries(); ++e) {
        const double rho = std::sqrt((e + 0.5) * std::ldexp(1.0, vt.vig_shift)) / rmax[i];
        vt.radial[i][e] = q(model.radial(static_cast<int>(i), std::min(rho, 1.0)));
      }
    if (model.channel_gain) {
      const auto g = model.channel_gain(static_cast<int>(i));
      vt.channel[i] = {q(g[0]), q(g[1]), q(g[2])};
    }
  }
  return vt;
}

VignettingModel vignetting_from_rig(const Rig& rig, double exponent) {
  if (!has_photometric(rig)) return {};
  VignettingModel m;
  m.radial = [rig, exponent](int cam, double rho) {
    const RigCamera& c = rig.cameras[static_cast<size_t>(cam)];
    if (!c.photometric) return 1.0;
    const Photometric& p = *c.photometric;
    // Along +x from the model's centre (W/2 + x, H/2 + y): V depends on the radius only.
    const double col = c.in.width / 2.0 + p.center_px.x() + rho * vignetting_rmax(c.in);
    const double row = c.in.height / 2.0 + p.center_px.y();
    const double v = std::max(vignetting_falloff(p, c.in.width, c.in.height, col, row), 0.02);
    return std::pow(1.0 / v, exponent);
  };
  m.channel_gain = [rig, exponent](int cam) {
    const RigCamera& c = rig.cameras[static_cast<size_t>(cam)];
    if (!c.photometric) return std::array<double, 3>{1.0, 1.0, 1.0};
    const auto& g = c.photometric->gains;  // B, G, R
    return std::array<double, 3>{std::pow(1 / g[2], exponent), std::pow(1 / g[1], exponent),
                                 std::pow(1 / g[0], exponent)};
  };
  return m;
}

}  // namespace omma::hw
