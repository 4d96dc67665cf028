// Every width and fixed-point format of the hardware model, in one place (thesis §5.4, ch. 6; the
// thesis states none of them except "16-bit precision" for eq. 5.21-5.27, 2048 x 16-bit sin/cos
// ROMs and 13-bit angle registers). docs/hw-model.md describes each block's arithmetic with these
// names; the RTL (hw/rtl/) takes the same values as Verilog parameters.
//
// Formats (Qm.n: value = integer / 2^n; "s" signed two's complement, "u" unsigned):
//   angle          uQ0.M of a full turn (eq. 5.14: B = 2 pi sum b_j 2^-(j+1)), M = angle_bits, wraps mod 2^M
//   sin/cos ROM    quarter wave, 2^T words of W bits, uQ1.(W-1) (1.0 = 2^(W-1)), T = sincos_addr_bits
//   sin/cos value  sQ1.(W-1) after the quadrant sign (W+1 bits)
//   omega          sQ1.W (W+2 bits): the sum of two table values (eq. 5.16-5.17) keeps the /2 exact
//   t, u, v        sQ1.V in 16-bit registers (Table 6.7's 48-bit arrays = 3 x 16), V = vec_frac_bits
//   cos(aov/2)     sQ1.V in a 16-bit register (Table 6.7 near_cos_alpha_srch)
//   position c     sQ(16-Pp).Pp millimetres, 16-bit registers (an extension of Table 6.7), Pp = pos_frac_bits
//   |r|            uQ(17-D).D millimetres (18 bits), D = dist_frac_bits
//   x, y (eq. 5.21-5.22, normalised), R^2, p, x', y'   sQ(proj_bits-P).P, P = proj_frac_bits
//   k1..k5         sQ(16-K).K in 16-bit registers, K = k_frac_bits
//   fu, fv         uQ(16-Ff).Ff pixels, 16-bit registers (Table 6.7 pixel_fc = 2 x 16)
//   cu, cv         uQ(16-Fc).Fc pixels, 16-bit registers (Table 6.7 pixel_cc = 2 x 16)
//   col, row       uQ(ceil log2 W).F pixels, F = pix_frac_bits (pixel centres at +0.5, conventions.h)
//   frame address  camera_bits + frame_addr_bits (eq. 5.27 with the camera index on top)
//   pixel          RGB565 in the frame memories (§5.2), expanded to 8 bits per channel
//   sample         uQ8.S per channel after bilinear interpolation, S = sample_frac_bits
//   weight         uQ0.R (R = recip_bits) from the reciprocal unit, block-floating (see blocks.h)
#pragma once

#include <string>

#include "omma/core/grid.h"
#include "omma/core/rig.h"

namespace omma::hw {

struct HwConfig {
  // --- B1 angle generation (eq. 5.11-5.14) ---
  int angle_bits = 24;  // M: angle accumulator / register width; a full turn = 2^M

  // --- B2 Cartesian unit (eq. 5.15-5.18) ---
  int sincos_addr_bits = 12;  // T: quarter-wave sin and cos ROMs of 2^T words each (thesis 2048 -> 11)
  int sincos_word_bits = 16;  // W: ROM word width, uQ1.(W-1) (thesis 16)

  // --- B3 camera search + distance (eq. 2.3, 5.19-5.20) ---
  int vec_frac_bits = 14;    // V: t, u, v and cos(aov/2) registers, sQ1.V in 16 bits (V <= 14)
  int pos_frac_bits = 10;    // Pp: camera centre registers, sQ(16-Pp).Pp mm
  int dist_frac_bits = 12;   // D: |r| in uQ(17-D).D mm, 18 bits
  int camera_bits = 5;       // ceil(log2 N) of the N-to-log2 N priority encoder (24 cameras -> 5)
  int max_contributors = 4;  // cameras the priority encoder passes on per direction (thesis: 4)

  // --- B4 projection + address (eq. 5.21-5.27) ---
  int proj_bits = 18;        // total width of x, y, R^2, p, x', y' (thesis: "16-bit precision")
  int proj_frac_bits = 14;   // P
  int k_frac_bits = 12;      // K: distortion coefficients, sQ(16-K).K
  int focal_frac_bits = 4;   // Ff: fu, fv, uQ(16-Ff).Ff
  int centre_frac_bits = 6;  // Fc: cu, cv, uQ(16-Fc).Fc
  int pix_frac_bits = 6;     // F: pixel coordinates / bilinear weights
  int frame_addr_bits = 16;  // address bits of one camera's frame memory (250 x 250 = 62500 < 2^16)

  // --- B5/B6 frame memory and pixel value unit ---
  bool bilinear = true;           // 2x2 reads per tap (the float reference samples bilinearly); false: the
                                  // thesis's single read at the pixel containing the point (eq. 5.27)
  int sample_frac_bits = 4;       // S: fraction bits kept of a bilinear sample, uQ8.S
  int weight_mant_bits = 18;      // Mw: mantissa of the block-floating distance product (MRF: 5 factors)
  int recip_bits = 16;            // R: reciprocal (weight) width
  bool expand_at_output = false;  // true: the thesis's order (blend 5/6/5-bit channels, RGB565 ->
                                  // RGB888 at the output); false: expand at the memory read

  // --- vignetting memory (Table 6.4/6.8 lut_vig 8192 x 16) ---
  int vig_addr_bits = 8;   // radial entries per camera (index = min(2^bits-1, (dx^2+dy^2) >> vig_shift))
  int vig_frac_bits = 14;  // gains uQ2.14 (1.0 = 16384)

  // --- B7 object boundary unit (§5.4.5, eq. 4.12-4.16) ---
  int boundary_threshold = 51;  // th_ob on the 8-bit gray scale, compared as |dY| > th (0.2 * 255)

  // Width-only checks (no rig needed). Returns true if valid; otherwise false and *error names the
  // field and the allowed range.
  bool IsValid(std::string* error = nullptr) const;
  // Throws std::invalid_argument with IsValid's message.
  void Check() const;

  // Derived widths (documented in docs/hw-model.md; the RTL uses the same expressions).
  int omega_bits() const { return sincos_word_bits + 2; }          // sQ1.W
  int sample_bits() const { return 8 + sample_frac_bits; }         // uQ8.S
  int acc_bits() const { return sample_bits() + recip_bits + 2; }  // sum of <= 4 products
  int quarter_entries() const { return 1 << sincos_addr_bits; }
  int vig_entries() const { return 1 << vig_addr_bits; }
};

// The thesis's own choices where it states them (M = 13 as its angle registers, 2048 x 16-bit
// quarter-wave ROMs, 16-bit projection datapath); the rest as HwConfig's defaults.
HwConfig thesis_config();

// Checks that `rig` (and the output grid) fit the configuration: cameras <= 2^camera_bits, frame
// width * height <= 2^frame_addr_bits, every register value representable (positions, focal
// lengths, principal points, distortion coefficients), the normalised image coordinates inside the
// cone of view fit proj_bits, and the grid's pixel count fits the angle bits (at least one code per
// pixel step). Throws std::invalid_argument naming the camera and field.
void check_rig(const HwConfig& cfg, const Rig& rig);
void check_grid(const HwConfig& cfg, const PanoGrid& grid);

}  // namespace omma::hw
