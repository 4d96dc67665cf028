// Memory and I/O model of the chip (thesis §5.2, §6.3-6.4: Tables 6.3, 6.4, 6.5, 6.8, 6.10) and a
// planner for other rigs and sizes (FPGA block RAM, clock).
//
// Sizes are recomputed from a configuration (cameras, frame size, bits per pixel, panorama width,
// table sizes); areas come from a per-macro table of the memory compiler's figures (Table 6.4 area
// / count: TSMC 40 nm, ARM Artisan compilers), so the thesis configuration reproduces Table 6.4
// exactly (3,415.552 KB, 25.620 mm^2) and any other one gets an estimate (area per bit of the
// nearest macro of the same kind).
#pragma once

#include <string>
#include <vector>

namespace omma::hw {

struct MemoryOptions {
  int cameras = 24;
  int frame_width = 250, frame_height = 250;
  int bits_per_pixel = 16;  // RGB565 (§5.2); 30 for 10-bit RGB
  int pano_width = 1080, pano_height = 1080;
  int sincos_words = 2048, sincos_bits = 16;  // per ROM (thesis: quarter wave 2^11 x 16)
  int cartesian_units = 5;                    // centre + 4 MRF neighbours (§5.4.2); 3 table sets each
  int vig_rom_words = 8192, vig_bits = 16;
  double fps = 25;
  int th_sys = 4;  // cycles per panorama pixel (throughput.h)

  bool IsValid(std::string* error = nullptr) const;
};

enum class MacroKind { kDualPortSram, kSinglePortSram, kRom };
std::string to_string(MacroKind k);

struct MemoryRow {
  std::string block;  // which block uses it (Table 6.10 macro name)
  MacroKind kind;
  int count = 0;
  int words = 0;
  int bits = 0;
  double kbytes = 0;    // count * words * bits / 8 / 1000 (the thesis's KBytes)
  double area_mm2 = 0;  // count * per-macro area (compiler table or estimate)
  bool area_estimated = false;
};

struct FifoRow {  // Table 6.5
  std::string name;
  int words = 0, bits = 0;
  std::string clocking;
};

struct WrapperRow {  // Table 6.8
  std::string name;
  int instances = 0;
  std::string kind;
  double kbytes = 0;
};

struct PinRow {  // Table 6.3
  std::string name;
  int initial = 0;
  int with_io = 0;  // after moving camera configuration on chip / sharing (second column)
};

struct MemoryReport {
  std::vector<MemoryRow> rows;  // Table 6.4
  double total_kbytes = 0, total_area_mm2 = 0;
  std::vector<FifoRow> fifos;
  std::vector<WrapperRow> wrappers;
  std::vector<PinRow> pins;
  int pins_initial = 0, pins_with_io = 0;
  double frame_memory_bits = 0;  // cameras x W x H x bpp (the FPGA's 24 Mbit)
  double macro_area_percent_of_core(double core_mm2, const std::string& block) const;
};

MemoryReport memory_report(const MemoryOptions& options);

// FPGA planner: Xilinx 7-series 36 Kbit block RAMs (aspect ratios 32Kx1 .. 512x72).
struct FpgaDevice {
  std::string name = "XC7VX485T";
  int bram36 = 1030;  // 37,080 Kbit ("37 Mbit", Table 5.4)
};
// Fewest 36 Kbit blocks that hold a depth x width memory.
int bram36_blocks(long depth, int width);

struct FpgaPlan {
  int frame_blocks_per_camera = 0;
  int frame_blocks = 0;
  int table_blocks = 0;  // line buffers, vignetting memory (sin/cos in distributed RAM, as §6.4)
  int total_blocks = 0;
  double utilisation = 0;  // total / device
  bool fits = false;
  double clock_mhz = 0;  // F_min = fps * pano pixels * Th_sys
};
FpgaPlan plan_fpga(const MemoryOptions& options, const FpgaDevice& device = {});

}  // namespace omma::hw
