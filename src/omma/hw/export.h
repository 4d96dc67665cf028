// `omma hw export` / `omma hw import`: the files a chip (and the RTL testbench, hw/rtl/) loads,
// written from a (calibrated) rig, and the way back. Formats: docs/hw-model.md §6. Every file is
// written atomically (temporary name, then rename).
//
//   DIR/config.json         format "omma-hw-config" v1: HwConfig, grid, method, boundary, camera count
//   DIR/regs.hex            global register writes (reg channel), one 32-bit word per line ($readmemh)
//   DIR/pix_pos.hex         Table 6.6 pix_pos_lutconfig words
//   DIR/cam_search.hex      Table 6.6 cam_search_lutconfig words
//   DIR/pix_val.hex         Table 6.6 pix_val_lutconfig words (vignetting memory)
//   DIR/config_stream.txt   the same writes, annotated (channel, address, field, value)
//   DIR/sin_rom.hex/.coe, cos_rom.hex/.coe   quarter-wave ROMs, 2^T words of W bits
//   DIR/vig_mem.hex/.coe    the whole vignetting memory image (vig_memory_words words of 16 bits)
//   DIR/pix_pos_regs.hex, cam_search_regs.hex   register-array images, entry (word << camera_bits) | camera
//   DIR/omma_hw_config.h    C header: widths, register addresses, the register values
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "omma/core/grid.h"
#include "omma/core/rig.h"
#include "omma/hw/regmap.h"
#include "omma/hw/tables.h"

namespace omma::hw {

nlohmann::json config_to_json(const HwConfig& cfg);
// Unknown keys and out-of-range values throw std::invalid_argument naming the key.
HwConfig config_from_json(const nlohmann::json& j);

struct ExportOptions {
  HwConfig config;
  PanoGrid grid;
  pano::Method method = pano::Method::kLinear;
  bool boundary = false;
  VignettingModel vignetting;  // empty: unit tables (no correction)
  // The exponent e of `vignetting` when it is the rig's photometric model (vignetting_from_rig; 1 or
  // kSrgbVignettingExponent), written to config.json so that import_chip can give the model back;
  // 0: the tables hold no model.
  double vignetting_exponent = 0;

  // False (with the reason in *why) when a value lies outside the range the code relies on.
  bool IsValid(std::string* why = nullptr) const;
};

struct ExportSummary {
  std::vector<std::string> files;
  size_t reg_words = 0, pix_pos_words = 0, cam_search_words = 0, pix_val_words = 0;
  ChipConfig chip;
};

// Throws std::invalid_argument (bad configuration / rig) or IoError (cannot write).
ExportSummary export_chip(const Rig& rig, const ExportOptions& options, const std::filesystem::path& dir);

struct ImportSummary {
  HwConfig config;
  PanoGrid grid;
  ChipConfig chip;
  Rig rig;  // cameras from the registers (tables.h camera_from_regs), with the photometric model
            // fitted to the vignetting memory where config.json names its exponent
  double vignetting_error = 0;  // largest relative error of that fit (0 without a model)
};
// Reads config.json and the four word streams. Throws std::invalid_argument / IoError naming the
// file, line and field on corrupt input: integers that are not JSON integers in their field's range,
// a grid outside core/limits.h, a vignetting memory (pix_val.hex) that does not set every entry of
// every camera exactly once.
ImportSummary import_chip(const std::filesystem::path& dir);

// Largest differences between two rigs with the same cameras (the round trip's error).
struct RigDifference {
  double axis_deg = 0;  // angle between t, u or v vectors
  double position_mm = 0;
  double focal_px = 0;
  double centre_px = 0;
  double k = 0;  // any distortion coefficient
  double aov_deg = 0;
};
RigDifference rig_difference(const Rig& a, const Rig& b);
// The bound the quantisation of each field allows (half an LSB of its register; the orientation
// bound from the unit vectors' 2^-V steps), used by the tests and reported by the command.
RigDifference quantisation_bound(const HwConfig& cfg);

// Text of a Verilog $readmemh file: one value per line, `digits` hex digits.
std::string readmemh_text(const std::vector<uint32_t>& words, int digits, const std::string& comment);
// Text of a Xilinx .coe file (radix 16).
std::string coe_text(const std::vector<uint32_t>& words, int digits);
// Parses a $readmemh-style file of 32-bit words (blank lines and // comments allowed); throws
// std::invalid_argument naming `name` and the line.
std::vector<uint32_t> parse_words(const std::string& text, const std::string& name);

}  // namespace omma::hw
