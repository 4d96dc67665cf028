// The camera's one-wire serial link (thesis §5.1.3, Table 5.1): an encoder (the camera model of the
// test bench) and a decoder (the FPGA's sampling and deserialisation block) that survives bit flips
// and lost samples.
//
// The stream, as the camera loops it after power-up (1 PP = one pixel period = bits + 2 clock
// cycles, 12 for 10-bit pixels):
//   for each row r = 0 .. height-1:
//     row gap:   `row_gap_pp` PP of data 0 XOR clock (no start bit)                       (3 PP)
//     pixels:    `width` words: start bit 1, `bits` data bits MSB first, stop bit 0,
//                each data bit XOR clock                                                  (250 PP)
//   end of frame: `eof_pp` PP of constant 0 (no XOR with the clock)                         (4 PP)
//   configuration window: `config_pp` PP in which the camera listens; modelled as constant 0
//                (the line is not driven by the camera)                                     (505 PP)
//   resynchronisation: `resync_pp` PP of data 0 XOR clock                                   (250 PP)
//
// Line samples ("chips"): one sample per half clock period, the clock high in the first half.
// A data bit b therefore becomes the two chips (!b, b): every bit carries a transition
// (Manchester-like, §5.1.2). Files (.bin) hold the chips packed 8 per byte, first chip in the
// most significant bit; the last byte is padded with 0 chips (the idle line).
//
// This header and link.cc use only the standard library (the fuzz target builds them alone).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace omma::isp {

struct LinkConfig {
  int width = 250;      // pixels per row (Table 5.1)
  int height = 250;     // rows per frame
  int bits = 10;        // ADC resolution, bits per pixel
  int row_gap_pp = 3;   // zeros before each row, in pixel periods
  int eof_pp = 4;       // end-of-frame marker (constant 0), PP
  int config_pp = 505;  // configuration window (constant 0 here), PP
  int resync_pp = 250;  // resynchronisation pattern (zeros XOR clock), PP

  int clocks_per_pp() const { return bits + 2; }  // start + data + stop bits
  int chips_per_pp() const { return 2 * clocks_per_pp(); }
  size_t row_chips() const { return size_t(row_gap_pp + width) * chips_per_pp(); }
  size_t frame_chips() const {
    return size_t(height) * row_chips() + size_t(eof_pp + config_pp + resync_pp) * chips_per_pp();
  }
  // Throws std::invalid_argument naming the bad field (sizes must be positive, bits in 1..16,
  // row gap >= 2 PP so that rows can be found, eof >= 1 PP).
  void validate() const;
};

// A frame of pixels (row-major, width x height, values < 2^bits) as it crosses the link.
struct LinkFrame {
  int width = 0, height = 0;
  std::vector<uint16_t> pixels;
  std::vector<uint8_t> row_ok;  // decoder output: 1 where the row was received intact
};

// Packed chip stream (see above) with its length in chips.
struct ChipStream {
  std::vector<uint8_t> bytes;
  size_t chips = 0;
  bool chip(size_t i) const { return (bytes[i >> 3] >> (7 - (i & 7))) & 1; }
  void push(bool c);
};

// Encodes frames back to back, each as rows, end-of-frame, configuration window and
// resynchronisation (the camera's loop). Throws std::invalid_argument if a frame's size differs
// from the config or a value does not fit in `bits`.
ChipStream encode_link(const std::vector<LinkFrame>& frames, const LinkConfig& config = {});

// Channel impairments for tests and the CLI: flips each chip with probability `flip_rate`, then
// drops each chip with probability `drop_rate` (a lost sample). Deterministic for a seed.
ChipStream impair_link(const ChipStream& in, double flip_rate, double drop_rate, uint64_t seed);

struct LinkSummary {
  int frames = 0;         // frames emitted (frames with at least one intact row)
  long rows_ok = 0;       // rows received intact, over the emitted frames
  long rows_damaged = 0;  // rows of emitted frames that were damaged or lost
  size_t bytes = 0;       // input size in bytes
};

// Decodes a chip stream. Calls on_frame for every frame with at least one intact row; rows that
// were damaged or never found have row_ok = 0 and pixels 0 (see conceal_damaged_rows).
// Resynchronises at the next row (a run of >= 32 alternating chips then a start bit) or the next
// frame (a constant run of >= half the end-of-frame marker, or the long resynchronisation run).
// Rows are placed by their timing after the last frame boundary. A stream whose first row start
// is not within 1 PP of a row slot counted from the stream start (a capture begun mid-row) is
// synchronised at its first frame boundary; rows before it are skipped and not counted. Runs in time linear
// in the input; never reads out of bounds, whatever the bytes.
LinkSummary decode_link(const uint8_t* data, size_t size, const LinkConfig& config,
                        const std::function<void(const LinkFrame&)>& on_frame);
LinkSummary decode_link(const std::vector<uint8_t>& bytes, const LinkConfig& config,
                        const std::function<void(const LinkFrame&)>& on_frame);

// Replaces each damaged row by the nearest intact row of the same Bayer colour (r-2, r+2, r-4,
// ...); rows with no intact partner stay 0. Returns the number of rows replaced.
int conceal_damaged_rows(LinkFrame& frame);

}  // namespace omma::isp
