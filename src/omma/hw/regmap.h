// What the chip loads: the configuration register map (thesis Table 6.7, with the extensions the
// model needs, marked "ext") and the three 32-bit configuration channels of Table 6.6. Encoding and
// decoding only; export.h writes and reads the files. Layout: docs/hw-model.md §6.
//
// Global registers: 16-bit register address, written over a fourth "reg" channel word
//   [31] write enable = 1, [30:16] register address (15 bits), [15:0] data.
// A register wider than 16 bits (the angle registers when angle_bits > 16) takes two consecutive
// addresses, the least significant half at the lower one.
// Per-camera arrays (Table 6.7): address = base + (word << camera_bits) + camera (0x20 per word for
// camera_bits = 5), written over the pix_pos (base 0x0800) or cam_search (base 0x1000) channel:
//   [31:25] 0, [24:21] array word select, [20:16] camera select, [15:0] data.
// Vignetting memory (pix_val channel): [31] write enable = 1, [30:16] memory address, [15:0] data.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "omma/hw/blocks.h"
#include "omma/pano/method.h"

namespace omma::hw {

struct GlobalRegister {
  const char* name;
  uint32_t address;
  int bits;                 // value width (angle registers: angle_bits)
  uint32_t thesis_default;  // Table 6.7 default (0 where the thesis gives none / ext registers)
  bool extension;           // not in Table 6.7
  const char* description;
  bool read_only = false;  // the chip's own value; a write is an error (decode refuses it)
};
// Value of the read-only hw_version register: the version of docs/hw-model.md's contract.
inline constexpr uint32_t kHwVersion = 1;

// The global registers, in address order. Angle registers have `bits` = 13 here (Table 6.7); the
// export uses cfg.angle_bits.
const std::vector<GlobalRegister>& global_registers();

struct ArrayField {
  const char* array;  // Table 6.7 name (or ext name)
  int channel;        // 0 pix_pos, 1 cam_search
  int word;           // 16-bit word index within the channel (array select)
  const char* field;  // what the word holds
};
// Every per-camera word of the two register-array channels, in (channel, word) order.
const std::vector<ArrayField>& array_fields();
inline constexpr uint32_t kPixPosBase = 0x0800, kCamSearchBase = 0x1000;

// The chip's whole configuration, as register values.
struct ChipConfig {
  AngleRegs angles;
  int frame_width = 0, frame_height = 0;
  pano::Method method = pano::Method::kLinear;
  bool boundary = false;
  int boundary_threshold = 51;
  int vig_shift = 0;
  std::vector<CameraRegs> cameras;
  VignettingTables vignetting;
};

// Word streams of the four channels.
struct WordStreams {
  std::vector<uint32_t> reg, pix_pos, cam_search, pix_val;
};

WordStreams encode(const HwConfig& cfg, const ChipConfig& chip);
// Decodes streams back; throws std::invalid_argument naming the channel, word index and field on a
// corrupt stream (write enable clear, unknown address or array word, camera beyond the count,
// a register value wider than its field, a camera whose words are missing, ...).
ChipConfig decode(const HwConfig& cfg, const WordStreams& streams);

// The Table 6.7 angle registers of the thesis with their defaults, decoded: columns = (max - min) / k.
struct ThesisAngleDefaults {
  uint32_t max_phi, min_phi, k_phi, max_theta, min_theta, k_theta, row_cnt, col_cnt;
  int columns_from_phi() const { return static_cast<int>((max_phi - min_phi) / k_phi); }
  int rows_from_theta() const { return static_cast<int>((max_theta - min_theta) / k_theta); }
};
ThesisAngleDefaults thesis_angle_defaults();

// The register address of word `word` of a channel's array for camera `camera`.
uint32_t array_address(const HwConfig& cfg, int channel, int word, int camera);
// Address of the vignetting memory's radial entry / channel gain.
uint32_t vig_radial_address(const HwConfig& cfg, int camera, int index);
uint32_t vig_channel_address(const HwConfig& cfg, int camera, int channel);
int vig_memory_words(const HwConfig& cfg);

}  // namespace omma::hw
