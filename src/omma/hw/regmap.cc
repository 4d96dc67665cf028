#include "omma/hw/regmap.h"

#include <map>
#include <stdexcept>

#include <fmt/format.h>

namespace omma::hw {
namespace {

enum GlobalId {
  kRowCnt,
  kColCnt,
  kMaxPhi,
  kKPhi,
  kMaxTheta,
  kMinTheta,
  kKTheta,
  kMinPhi,
  kFrameWidth,
  kFrameHeight,
  kAxes,
  kCs,
  kVigShift,
  kColorSource,
  kMethod,
  kBoundary,
  kCameraSelect,
  kVigSelect,
  kVersion,
  kNumGlobals
};

bool is_angle(int id) {
  return id == kMaxPhi || id == kKPhi || id == kMaxTheta || id == kMinTheta || id == kKTheta || id == kMinPhi;
}

int reg_bits(const HwConfig& cfg, int id) {
  return is_angle(id) ? cfg.angle_bits : global_registers()[id].bits;
}

uint16_t s16(int32_t v) { return static_cast<uint16_t>(v & 0xFFFF); }
int32_t sext16(uint32_t v) { return static_cast<int32_t>(static_cast<int16_t>(v & 0xFFFF)); }

}  // namespace

const std::vector<GlobalRegister>& global_registers() {
  static const std::vector<GlobalRegister> regs = {
      {"panorama_row_cnt", 0x1800, 11, 0x1D5, false, "panorama rows"},
      {"panorama_col_cnt", 0x2000, 11, 0x1AC, false, "panorama columns"},
      {"pano_max_phi", 0x2800, 13, 0x17F8, false, "phi after the last column (min + cols * k)"},
      {"pano_k_phi", 0x3000, 13, 0x00A, false,
       "horizontal angle step (two's complement: phi decreases to the right)"},
      {"pano_max_theta", 0x3800, 13, 0xDF8, false, "theta after the last row (min + rows * k)"},
      {"pano_min_theta", 0x4000, 13, 0x300, false, "theta of the first row (pixel centre)"},
      {"pano_k_theta", 0x4800, 13, 0x006, false, "vertical angle step"},
      {"pano_min_phi", 0x5000, 13, 0x740, false, "phi of the first column (pixel centre)"},
      {"frame_width", 0x5800, 16, 0, true, "camera frame width = line width lw of eq. 5.27"},
      {"frame_height", 0x6000, 16, 0, true, "camera frame height"},
      {"pano_axes", 0x6400, 2, 0, true,
       "bit 0: vr180 axis map (omega = (b, c, a)); bit 1: columns wrap (MRF)"},
      {"pano_cs", 0x6800, 1, 0x0, false, "panorama generation enable"},
      {"vig_shift", 0x6C00, 5, 0, true, "vignetting index = (dx^2 + dy^2) >> vig_shift"},
      {"sel_color_source", 0x7000, 1, 0x0, false, "test pattern select"},
      {"pix_method", 0x7400, 2, 0, true, "pixel value unit: 0 nn, 1 linear, 2 mrf"},
      {"boundary_ctrl", 0x7600, 9, 0, true,
       "bit 8: boundary unit enable; [7:0] threshold th_ob (8-bit gray)"},
      {"camera_select", 0x7800, 5, 0x1, false, "single camera output select"},
      {"vig_mem_select", 0x7C00, 1, 0x0, false, "vignetting memory: 0 ROM (power-up defaults), 1 SP SRAM"},
      {"hw_version", 0x7E00, 16, kHwVersion, true,
       "read-only: version of the model's contract (docs/hw-model.md)", true},
  };
  return regs;
}

const std::vector<ArrayField>& array_fields() {
  static const std::vector<ArrayField> f = {
      {"pixel_e_u", 0, 0, "u.x sQ1.V"},
      {"pixel_e_u", 0, 1, "u.y sQ1.V"},
      {"pixel_e_u", 0, 2, "u.z sQ1.V"},
      {"pixel_e_v", 0, 3, "v.x sQ1.V"},
      {"pixel_e_v", 0, 4, "v.y sQ1.V"},
      {"pixel_e_v", 0, 5, "v.z sQ1.V"},
      {"pixel_k_coefs", 0, 6, "k1 sQ.K"},
      {"pixel_k_coefs", 0, 7, "k2 sQ.K"},
      {"pixel_k_coefs", 0, 8, "k3 sQ.K"},
      {"pixel_fc", 0, 9, "fu uQ.Ff"},
      {"pixel_fc", 0, 10, "fv uQ.Ff"},
      {"pixel_cc", 0, 11, "cu uQ.Fc"},
      {"pixel_cc", 0, 12, "cv uQ.Fc"},
      {"pixel_k_coefs_ext (ext)", 0, 13, "k4 sQ.K"},
      {"pixel_k_coefs_ext (ext)", 0, 14, "k5 sQ.K"},
      {"near_t_vec_tmp_srch", 1, 0, "t.x sQ1.V"},
      {"near_t_vec_tmp_srch", 1, 1, "t.y sQ1.V"},
      {"near_t_vec_tmp_srch", 1, 2, "t.z sQ1.V"},
      {"near_cos_alpha_srch", 1, 3, "cos(aov/2) sQ1.V"},
      {"cam_centre (ext)", 1, 4, "c.x sQ.Pp mm"},
      {"cam_centre (ext)", 1, 5, "c.y sQ.Pp mm"},
      {"cam_centre (ext)", 1, 6, "c.z sQ.Pp mm"},
  };
  return f;
}

uint32_t array_address(const HwConfig& cfg, int channel, int word, int camera) {
  return (channel == 0 ? kPixPosBase : kCamSearchBase) + (static_cast<uint32_t>(word) << cfg.camera_bits) +
         static_cast<uint32_t>(camera);
}

uint32_t vig_radial_address(const HwConfig& cfg, int camera, int index) {
  return (static_cast<uint32_t>(camera) << cfg.vig_addr_bits) + static_cast<uint32_t>(index);
}
uint32_t vig_channel_address(const HwConfig& cfg, int camera, int channel) {
  return (uint32_t{1} << (cfg.camera_bits + cfg.vig_addr_bits)) + 4 * static_cast<uint32_t>(camera) +
         static_cast<uint32_t>(channel);
}
int vig_memory_words(const HwConfig& cfg) {
  return (1 << (cfg.camera_bits + cfg.vig_addr_bits)) + 4 * (1 << cfg.camera_bits);
}

ThesisAngleDefaults thesis_angle_defaults() {
  const auto& g = global_registers();
  return {g[kMaxPhi].thesis_default,   g[kMinPhi].thesis_default,   g[kKPhi].thesis_default,
          g[kMaxTheta].thesis_default, g[kMinTheta].thesis_default, g[kKTheta].thesis_default,
          g[kRowCnt].thesis_default,   g[kColCnt].thesis_default};
}

static std::array<int32_t, 15> pix_pos_words(const CameraRegs& c) {
  return {c.u[0],
          c.u[1],
          c.u[2],
          c.v[0],
          c.v[1],
          c.v[2],
          c.k[0],
          c.k[1],
          c.k[2],
          static_cast<int32_t>(c.fu),
          static_cast<int32_t>(c.fv),
          static_cast<int32_t>(c.cu),
          static_cast<int32_t>(c.cv),
          c.k[3],
          c.k[4]};
}
static std::array<int32_t, 7> cam_search_words(const CameraRegs& c) {
  return {c.t[0], c.t[1], c.t[2], c.cos_half_aov, c.c[0], c.c[1], c.c[2]};
}

WordStreams encode(const HwConfig& cfg, const ChipConfig& chip) {
  cfg.Check();
  if (cfg.camera_bits > 5)
    throw std::invalid_argument(
        fmt::format("camera_bits = {}: the Table 6.6 channels have a 5-bit camera select", cfg.camera_bits));
  if (chip.cameras.size() > (size_t{1} << cfg.camera_bits))
    throw std::invalid_argument("more cameras than camera_bits can address");
  WordStreams s;
  const uint32_t mask = cfg.angle_bits >= 32 ? 0xFFFFFFFFu : (uint32_t{1} << cfg.angle_bits) - 1;
  const AngleRegs& a = chip.angles;
  std::array<uint32_t, kNumGlobals> v{};
  v[kRowCnt] = static_cast<uint32_t>(a.rows);
  v[kColCnt] = static_cast<uint32_t>(a.cols);
  v[kMinPhi] = a.phi_min;
  v[kKPhi] = a.k_phi;
  v[kMaxPhi] = static_cast<uint32_t>(a.phi_min + static_cast<uint64_t>(a.k_phi) * a.cols) & mask;
  v[kMinTheta] = a.theta_min;
  v[kKTheta] = a.k_theta;
  v[kMaxTheta] = static_cast<uint32_t>(a.theta_min + static_cast<uint64_t>(a.k_theta) * a.rows) & mask;
  v[kFrameWidth] = static_cast<uint32_t>(chip.frame_width);
  v[kFrameHeight] = static_cast<uint32_t>(chip.frame_height);
  v[kAxes] = (a.axes == AxisMap::kVr180 ? 1u : 0u) | (a.wrap_cols ? 2u : 0u);
  v[kVigShift] = static_cast<uint32_t>(chip.vig_shift);
  v[kColorSource] = 0;
  v[kMethod] = chip.method == pano::Method::kNearest ? 0u : chip.method == pano::Method::kLinear ? 1u : 2u;
  if (chip.method != pano::Method::kNearest && chip.method != pano::Method::kLinear &&
      chip.method != pano::Method::kMrf)
    throw std::invalid_argument("the chip's pixel value unit implements nn, linear and mrf only");
  v[kBoundary] = (chip.boundary ? 0x100u : 0u) | (static_cast<uint32_t>(chip.boundary_threshold) & 0xFF);
  v[kCameraSelect] = 0;
  v[kVigSelect] = 1;  // the SP SRAM, loaded over pix_val below
  v[kCs] = 1;
  const auto& g = global_registers();
  auto put = [&](uint32_t addr, uint32_t data) {
    s.reg.push_back(0x80000000u | (addr << 16) | (data & 0xFFFF));
  };
  for (int id = 0; id < kNumGlobals; ++id) {
    if (id == kCs || g[id].read_only) continue;  // enable last; read-only registers are never written
    const int bits = reg_bits(cfg, id);
    if (bits < 32 && v[id] >= (uint32_t{1} << bits))
      throw std::invalid_argument(
          fmt::format("register {} = {} does not fit {} bits", g[id].name, v[id], bits));
    put(g[id].address, v[id] & 0xFFFF);
    if (bits > 16) put(g[id].address + 1, v[id] >> 16);
  }
  for (size_t cam = 0; cam < chip.cameras.size(); ++cam) {
    const auto pw = pix_pos_words(chip.cameras[cam]);
    for (int w = 0; w < 15; ++w)
      s.pix_pos.push_back((uint32_t(w) << 21) | (uint32_t(cam) << 16) | s16(pw[w]));
    const auto cw = cam_search_words(chip.cameras[cam]);
    for (int w = 0; w < 7; ++w)
      s.cam_search.push_back((uint32_t(w) << 21) | (uint32_t(cam) << 16) | s16(cw[w]));
  }
  const VignettingTables& vt = chip.vignetting;
  for (size_t cam = 0; cam < vt.radial.size(); ++cam) {
    for (size_t i = 0; i < vt.radial[cam].size(); ++i)
      s.pix_val.push_back(0x80000000u | (vig_radial_address(cfg, int(cam), int(i)) << 16) |
                          vt.radial[cam][i]);
    for (int ch = 0; ch < 3; ++ch)
      s.pix_val.push_back(0x80000000u | (vig_channel_address(cfg, int(cam), ch) << 16) | vt.channel[cam][ch]);
  }
  put(g[kCs].address, 1);
  return s;
}

ChipConfig decode(const HwConfig& cfg, const WordStreams& s) {
  cfg.Check();
  const auto& g = global_registers();
  std::map<uint32_t, uint32_t> regs;  // address -> 16-bit data
  for (size_t i = 0; i < s.reg.size(); ++i) {
    const uint32_t w = s.reg[i];
    if (!(w >> 31))
      throw std::invalid_argument(fmt::format("reg stream word {}: write enable (bit 31) is clear", i));
    regs[(w >> 16) & 0x7FFF] = w & 0xFFFF;
  }
  std::array<uint32_t, kNumGlobals> v{};
  for (int id = 0; id < kNumGlobals; ++id) {
    const int bits = reg_bits(cfg, id);
    if (g[id].read_only) {
      if (regs.count(g[id].address))
        throw std::invalid_argument(
            fmt::format("reg stream: register {} (0x{:04X}) is read-only", g[id].name, g[id].address));
      continue;
    }
    auto it = regs.find(g[id].address);
    if (it == regs.end())
      throw std::invalid_argument(
          fmt::format("reg stream: register {} (0x{:04X}) is never written", g[id].name, g[id].address));
    uint64_t val = it->second;
    if (bits > 16) {
      auto hi = regs.find(g[id].address + 1);
      if (hi == regs.end())
        throw std::invalid_argument(fmt::format("reg stream: the high half of {} (0x{:04X}) is never written",
                                                g[id].name, g[id].address + 1));
      val |= uint64_t{hi->second} << 16;
    }
    if (bits < 64 && (val >> bits) != 0)
      throw std::invalid_argument(
          fmt::format("reg stream: {} = 0x{:X} is wider than its {} bits", g[id].name, val, bits));
    v[id] = static_cast<uint32_t>(val);
  }
  for (const auto& [addr, data] : regs) {
    bool known = false;
    for (int id = 0; id < kNumGlobals; ++id)
      known |= addr == g[id].address || (reg_bits(cfg, id) > 16 && addr == g[id].address + 1);
    if (!known)
      throw std::invalid_argument(fmt::format("reg stream: unknown register address 0x{:04X}", addr));
  }
  ChipConfig c;
  c.angles.rows = static_cast<int>(v[kRowCnt]);
  c.angles.cols = static_cast<int>(v[kColCnt]);
  c.angles.phi_min = v[kMinPhi];
  c.angles.k_phi = v[kKPhi];
  c.angles.theta_min = v[kMinTheta];
  c.angles.k_theta = v[kKTheta];
  c.angles.axes = (v[kAxes] & 1) ? AxisMap::kVr180 : AxisMap::kDome;
  c.angles.wrap_cols = (v[kAxes] & 2) != 0;
  c.frame_width = static_cast<int>(v[kFrameWidth]);
  c.frame_height = static_cast<int>(v[kFrameHeight]);
  if (c.frame_width <= 0 || c.frame_height <= 0)
    throw std::invalid_argument("reg stream: frame_width and frame_height must be positive");
  c.vig_shift = static_cast<int>(v[kVigShift]);
  if (v[kMethod] > 2)
    throw std::invalid_argument(
        fmt::format("reg stream: pix_method = {} (0 nn, 1 linear, 2 mrf)", v[kMethod]));
  c.method = v[kMethod] == 0   ? pano::Method::kNearest
             : v[kMethod] == 1 ? pano::Method::kLinear
                               : pano::Method::kMrf;
  c.boundary = (v[kBoundary] & 0x100) != 0;
  c.boundary_threshold = static_cast<int>(v[kBoundary] & 0xFF);

  // Register arrays.
  const int max_cams = 1 << std::min(cfg.camera_bits, 5);
  std::vector<std::array<int32_t, 15>> pp(max_cams);
  std::vector<std::array<int32_t, 7>> cs(max_cams);
  std::vector<uint32_t> seen_pp(max_cams, 0), seen_cs(max_cams, 0);
  auto parse_array = [&](const std::vector<uint32_t>& words, const char* name, int nwords, auto& store,
                         std::vector<uint32_t>& seen) {
    for (size_t i = 0; i < words.size(); ++i) {
      const uint32_t w = words[i];
      if (w >> 25)
        throw std::invalid_argument(
            fmt::format("{} stream word {} (0x{:08X}): bits [31:25] must be 0", name, i, w));
      const int word = static_cast<int>((w >> 21) & 0xF), cam = static_cast<int>((w >> 16) & 0x1F);
      if (word >= nwords)
        throw std::invalid_argument(
            fmt::format("{} stream word {} (0x{:08X}): array select {} is not a register array (0..{})", name,
                        i, w, word, nwords - 1));
      if (cam >= max_cams)
        throw std::invalid_argument(
            fmt::format("{} stream word {}: camera select {} is beyond camera_bits", name, i, cam));
      store[cam][word] = static_cast<int32_t>(w & 0xFFFF);
      seen[cam] |= 1u << word;
    }
  };
  parse_array(s.pix_pos, "pix_pos", 15, pp, seen_pp);
  parse_array(s.cam_search, "cam_search", 7, cs, seen_cs);
  int ncams = 0;
  for (int cam = 0; cam < max_cams; ++cam)
    if (seen_pp[cam] || seen_cs[cam]) ncams = cam + 1;
  if (ncams == 0) throw std::invalid_argument("pix_pos / cam_search streams: no camera is configured");
  for (int cam = 0; cam < ncams; ++cam) {
    if (seen_pp[cam] != (1u << 15) - 1)
      throw std::invalid_argument(
          fmt::format("pix_pos stream: camera {} is missing array words (mask 0x{:04X})", cam, seen_pp[cam]));
    if (seen_cs[cam] != (1u << 7) - 1)
      throw std::invalid_argument(fmt::format(
          "cam_search stream: camera {} is missing array words (mask 0x{:02X})", cam, seen_cs[cam]));
    CameraRegs r;
    const auto& p = pp[cam];
    const auto& q = cs[cam];
    for (int k = 0; k < 3; ++k) {
      r.u[k] = sext16(p[k]);
      r.v[k] = sext16(p[3 + k]);
      r.t[k] = sext16(q[k]);
      r.c[k] = sext16(q[4 + k]);
    }
    r.k = {sext16(p[6]), sext16(p[7]), sext16(p[8]), sext16(p[13]), sext16(p[14])};
    r.fu = p[9] & 0xFFFF;
    r.fv = p[10] & 0xFFFF;
    r.cu = p[11] & 0xFFFF;
    r.cv = p[12] & 0xFFFF;
    r.cos_half_aov = sext16(q[3]);
    r.width = c.frame_width;
    r.height = c.frame_height;
    if (r.fu == 0 || r.fv == 0)
      throw std::invalid_argument(
          fmt::format("pix_pos stream: camera {} has a zero focal length (pixel_fc)", cam));
    c.cameras.push_back(r);
  }
  // Vignetting memory.
  const int words = vig_memory_words(cfg);
  std::vector<int> mem(words, -1);
  for (size_t i = 0; i < s.pix_val.size(); ++i) {
    const uint32_t w = s.pix_val[i];
    if (!(w >> 31))
      throw std::invalid_argument(fmt::format("pix_val stream word {}: write enable (bit 31) is clear", i));
    const uint32_t addr = (w >> 16) & 0x7FFF;
    if (addr >= static_cast<uint32_t>(words))
      throw std::invalid_argument(
          fmt::format("pix_val stream word {}: address 0x{:04X} is beyond the vignetting "
                      "memory ({} words)",
                      i, addr, words));
    if (mem[addr] >= 0)
      throw std::invalid_argument(
          fmt::format("pix_val stream word {}: address 0x{:04X} is written a second time", i, addr));
    mem[addr] = static_cast<int>(w & 0xFFFF);
  }
  // Every camera's table must be there: an empty, truncated or foreign stream is refused, not read
  // as unit gains.
  for (int cam = 0; cam < ncams; ++cam) {
    for (int i = 0; i < cfg.vig_entries(); ++i)
      if (mem[vig_radial_address(cfg, cam, i)] < 0)
        throw std::invalid_argument(fmt::format(
            "pix_val stream: camera {}'s vignetting entry {} is missing ({} words for {} cameras of {} "
            "entries and 3 channel gains)",
            cam, i, s.pix_val.size(), ncams, cfg.vig_entries()));
    for (int k = 0; k < 3; ++k)
      if (mem[vig_channel_address(cfg, cam, k)] < 0)
        throw std::invalid_argument(
            fmt::format("pix_val stream: camera {}'s channel gain {} is missing", cam, "RGB"[k]));
  }
  c.vignetting.vig_shift = c.vig_shift;
  const uint32_t one = 1u << cfg.vig_frac_bits;
  for (int cam = 0; cam < ncams; ++cam) {
    std::vector<uint32_t> radial(cfg.vig_entries(), one);
    for (int i = 0; i < cfg.vig_entries(); ++i) {
      const int m = mem[vig_radial_address(cfg, cam, i)];
      if (m >= 0) radial[i] = static_cast<uint32_t>(m);
    }
    std::array<uint32_t, 3> ch{one, one, one};
    for (int k = 0; k < 3; ++k) {
      const int m = mem[vig_channel_address(cfg, cam, k)];
      if (m >= 0) ch[k] = static_cast<uint32_t>(m);
    }
    c.vignetting.radial.push_back(radial);
    c.vignetting.channel.push_back(ch);
  }
  return c;
}

}  // namespace omma::hw
