#include "omma/hw/memory.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "omma/core/valid.h"

namespace omma::hw {
namespace {

// Memory compiler figures: Table 6.4 area / count (mm^2 per macro).
struct Macro {
  MacroKind kind;
  int words, bits;
  double area_mm2;
};
const std::vector<Macro>& macro_table() {
  static const std::vector<Macro> t = {
      {MacroKind::kDualPortSram, 2048, 16, 0.080 / 2},   {MacroKind::kDualPortSram, 256, 24, 1.286 / 48},
      {MacroKind::kDualPortSram, 1024, 10, 0.921 / 48},  {MacroKind::kDualPortSram, 256, 10, 0.313 / 24},
      {MacroKind::kDualPortSram, 8192, 32, 22.681 / 96}, {MacroKind::kSinglePortSram, 4096, 16, 0.066 / 2},
      {MacroKind::kRom, 2048, 16, 0.251 / 30},           {MacroKind::kRom, 8192, 16, 0.022 / 1},
  };
  return t;
}

double macro_area(MacroKind kind, int words, int bits, bool* estimated) {
  const Macro* best = nullptr;
  double best_ratio = std::numeric_limits<double>::infinity();
  for (const Macro& m : macro_table()) {
    if (m.kind != kind) continue;
    if (m.words == words && m.bits == bits) {
      *estimated = false;
      return m.area_mm2;
    }
    const double ratio = std::abs(std::log(double(words) * bits / (double(m.words) * m.bits)));
    if (ratio < best_ratio) best_ratio = ratio, best = &m;
  }
  *estimated = true;
  return best->area_mm2 * (double(words) * bits) / (double(best->words) * best->bits);
}

int next_pow2(long v) {
  int p = 0;
  while ((1L << p) < v) ++p;
  return 1 << p;
}

}  // namespace

std::string to_string(MacroKind k) {
  switch (k) {
    case MacroKind::kDualPortSram:
      return "Dual Port SRAM";
    case MacroKind::kSinglePortSram:
      return "Single Port SRAM";
    case MacroKind::kRom:
      return "ROM";
  }
  return "?";
}

bool MemoryOptions::IsValid(std::string* error) const {
  if (cameras < 1 || cameras > 4096)
    return invalid(error, fmt::format("cameras = {} must be in [1, 4096]", cameras));
  if (frame_width < 1 || frame_height < 1 || frame_width > 16384 || frame_height > 16384)
    return invalid(error, "frame size must be in [1, 16384]");
  if (bits_per_pixel < 1 || bits_per_pixel > 64) return invalid(error, "bits_per_pixel must be in [1, 64]");
  if (pano_width < 1 || pano_height < 1 || pano_width > 65535 || pano_height > 65535)
    return invalid(error, "panorama size must be in [1, 65535]");
  if (sincos_words < 1 || sincos_bits < 1 || vig_rom_words < 1 || vig_bits < 1)
    return invalid(error, "table sizes must be positive");
  if (cartesian_units < 1) return invalid(error, "cartesian_units must be >= 1");
  if (!(fps > 0) || th_sys < 1) return invalid(error, "fps must be > 0 and th_sys >= 1");
  return true;
}

MemoryReport memory_report(const MemoryOptions& o) {
  std::string err;
  if (!o.IsValid(&err)) throw std::invalid_argument("memory model: " + err);
  MemoryReport r;
  const int N = o.cameras;
  const int line = next_pow2(o.frame_width);  // camera line buffers, power-of-two deep
  // Frame memory: 4 banks of 32-bit words per camera (§6.4.6), depth = the power of two that holds
  // the frame: 62,500 x 16 bit -> 4 x 8192 x 32.
  const double frame_bits = double(o.frame_width) * o.frame_height * o.bits_per_pixel;
  const int bank_words = next_pow2(static_cast<long>(std::ceil(frame_bits / (4.0 * 32))));
  auto add = [&](const char* block, MacroKind kind, int count, int words, int bits) {
    MemoryRow m{block, kind, count, words, bits, count * double(words) * bits / 8 / 1000, 0, false};
    m.area_mm2 = count * macro_area(kind, words, bits, &m.area_estimated);
    r.rows.push_back(m);
  };
  add("pan_line_buffer", MacroKind::kDualPortSram, 2, next_pow2(o.pano_width), 16);
  add("rgb_line_buffer", MacroKind::kDualPortSram, 2 * N, line, 24);
  add("row_buffer", MacroKind::kDualPortSram, 2 * N, 4 * line, 10);
  add("cam_int_buffer", MacroKind::kDualPortSram, N, line, 10);
  add("frame_mem_2", MacroKind::kDualPortSram, 4 * N, bank_words, 32);
  add("vig_ram_16x4096", MacroKind::kSinglePortSram, 2, o.vig_rom_words / 2, o.vig_bits);
  add("lut_sin + lut_cos", MacroKind::kRom, 2 * 3 * o.cartesian_units, o.sincos_words, o.sincos_bits);
  add("lut_vig", MacroKind::kRom, 1, o.vig_rom_words, o.vig_bits);
  for (const auto& m : r.rows) r.total_kbytes += m.kbytes, r.total_area_mm2 += m.area_mm2;

  r.fifos = {{"panorama_line_fifo", next_pow2(o.pano_width), 16, "Single-clock"},
             {"rgb_line_fifo249", line, 24, "Single-clock"},
             {"row_fifo249", 4 * line, 10, "Single-clock"},
             {"cam_int_fifo", line, 10, "Dual-clock"}};
  auto kb = [](int words, int bits) { return double(words) * bits / 8 / 1000; };
  auto log2i = [](int v) {
    int b = 0;
    while ((1 << b) < v) ++b;
    return b;
  };
  r.wrappers = {
      {fmt::format("fifo_memory_single_w10a{}", log2i(line)), 1, "DP SRAM", kb(line, 10)},
      {fmt::format("fifo_memory_single_w10a{}", log2i(4 * line)), 1, "DP SRAM", kb(4 * line, 10)},
      {fmt::format("fifo_memory_single_w16a{}", log2i(next_pow2(o.pano_width))), 1, "DP SRAM",
       kb(next_pow2(o.pano_width), 16)},
      {fmt::format("fifo_memory_single_w24a{}", log2i(line)), 1, "DP SRAM", kb(line, 24)},
      {"frame_mem_wrapper", 4, "DP SRAM", 4 * kb(bank_words, 32)},
      {"lut_cos_wrapper", 1, "ROM", kb(o.sincos_words, o.sincos_bits)},
      {"lut_sin_wrapper", 1, "ROM", kb(o.sincos_words, o.sincos_bits)},
      {"vig_memory_wrapper (SP SRAM)", 2, "SP SRAM", 2 * kb(o.vig_rom_words / 2, o.vig_bits)},
      {"vig_memory_wrapper (ROM)", 1, "ROM", kb(o.vig_rom_words, o.vig_bits)},
  };
  const int sel = std::max(1, log2i(N));
  r.pins = {
      {"clk_in", 1, 1},        {"rst_in", 1, 1},       {"serial_data_in", N, 2 * N}, {"I2C_data_in", 1, 1},
      {"I2C_clock", 1, 1},     {"spi_sclk", N, 0},     {"spi_sdata", N, 0},          {"I2C_data_out", 1, 0},
      {"I2C_direction", 1, 0}, {"DE_out", 1, 1},       {"data_out", 30, 30},         {"vblank_out", 1, 1},
      {"hblank_out", 1, 1},    {"clock_out", 1, 1},    {"selected_cam", sel, sel},   {"DE_out_0", 1, 1},
      {"data_out_0", 30, 30},  {"vblank_out_0", 1, 1}, {"hblank_out_0", 1, 1},       {"clock_out_0", 1, 1}};
  for (const auto& p : r.pins) r.pins_initial += p.initial, r.pins_with_io += p.with_io;
  r.frame_memory_bits = frame_bits * N;
  return r;
}

double MemoryReport::macro_area_percent_of_core(double core_mm2, const std::string& block) const {
  for (const auto& m : rows)
    if (m.block == block) return 100.0 * m.area_mm2 / core_mm2;
  throw std::invalid_argument("no memory block named " + block);
}

int bram36_blocks(long depth, int width) {
  static const int kDepth[] = {32768, 16384, 8192, 4096, 2048, 1024, 512};
  static const int kWidth[] = {1, 2, 4, 9, 18, 36, 72};
  long best = std::numeric_limits<long>::max();
  for (int i = 0; i < 7; ++i) {
    const long n = ((depth + kDepth[i] - 1) / kDepth[i]) * ((width + kWidth[i] - 1) / kWidth[i]);
    best = std::min(best, n);
  }
  return static_cast<int>(best);
}

FpgaPlan plan_fpga(const MemoryOptions& o, const FpgaDevice& dev) {
  std::string err;
  if (!o.IsValid(&err)) throw std::invalid_argument("memory model: " + err);
  FpgaPlan p;
  p.frame_blocks_per_camera = bram36_blocks(long(o.frame_width) * o.frame_height, o.bits_per_pixel);
  p.frame_blocks = p.frame_blocks_per_camera * o.cameras;
  const int line = next_pow2(o.frame_width);
  p.table_blocks =
      o.cameras * (2 * bram36_blocks(line, 24) + 2 * bram36_blocks(4 * line, 10) + bram36_blocks(line, 10)) +
      2 * bram36_blocks(next_pow2(o.pano_width), 16) + bram36_blocks(o.vig_rom_words, o.vig_bits);
  p.total_blocks = p.frame_blocks + p.table_blocks;
  p.utilisation = double(p.total_blocks) / dev.bram36;
  p.fits = p.total_blocks <= dev.bram36;
  p.clock_mhz = o.fps * double(o.pano_width) * o.pano_height * o.th_sys * 1e-6;
  return p;
}

}  // namespace omma::hw
