// The panorama pipeline of thesis Fig. 5.9-5.15, block by block, as integer functions with the
// inputs and outputs a Verilog module of that block would have (widths and formats: hw_config.h;
// the arithmetic step by step: docs/hw-model.md). No floating point anywhere in this file's
// functions. pipeline.h chains them over a whole panorama.
//
//   B1 angle generation        angle_regs / angles_at            eq. 5.11-5.14
//   B2 Cartesian unit          sincos_lookup / cartesian          eq. 5.15-5.18 (5.17 corrected)
//   B3 camera search           cone_test / camera_search          eq. 2.3
//      distance                distance_unit                      eq. 5.19-5.20
//   B4 projection + address    project / tap_address              eq. 5.21-5.27
//   B5 frame memory            FrameMemory (RGB565, §5.2)
//   B6 pixel value unit        bilinear_sample / vignetting_gain / block_float_mul / reciprocal_weights
//                              / blend                            eq. 2.6-2.8, 4.8-4.9 (§5.4.2)
//   B7 boundary unit           boundary_unit                      eq. 4.12-4.16 (§5.4.5)
//   B8 output                  rgb565_to_rgb888                   Fig. 5.15
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "omma/hw/hw_config.h"

namespace omma::hw {

// ---------------------------------------------------------------------------------------------
// Configuration registers (what the chip loads, Table 6.7; export.h writes them)
// ---------------------------------------------------------------------------------------------

// Angle generator registers (Table 6.7 pano_*; M-bit values, uQ0.M of a full turn). Pixel (col,
// row) looks at theta = theta_min + row * k_theta, phi = phi_min + col * k_phi (mod 2^M), which is
// what the accumulators hold after `row` and `col` increments (eq. 5.11-5.12); theta_min and
// phi_min are the angles of the first pixel CENTRE. k_phi is the two's complement (mod 2^M) of the
// column step: the column angle DEcreases to the right (conventions.h (G1), (G2): the panorama is
// not mirrored), which the modulo-2^M accumulator does with no extra logic.
// axes selects how (a, b, c) = (sin t cos p, sin t sin p, cos t) map onto the dome frame (a wire
// permutation, free in hardware):
//   kDome  (equirect grids): omega = (a, b, c)  -- theta from the dome axis +z, phi from +x (eq. 5.15)
//   kVr180 (vr180 grid):     omega = (b, c, a)  -- theta from +y (top row) down, phi = longitude
//                            about +y from +z towards +x (conventions.h (G2))
enum class AxisMap : int { kDome = 0, kVr180 = 1 };

struct AngleRegs {
  uint32_t theta_min = 0, k_theta = 0, phi_min = 0, k_phi = 0;
  int rows = 0, cols = 0;  // panorama_row_cnt, panorama_col_cnt
  AxisMap axes = AxisMap::kDome;
  bool wrap_cols = false;  // 360-degree grids: the left/right neighbours wrap (MRF, §5.4.2)
};

// Registers of one camera (Table 6.7 arrays plus the extensions documented in docs/hw-model.md).
// All 16-bit two's complement (signed) or unsigned words as stated.
struct CameraRegs {
  std::array<int32_t, 3> t{}, u{}, v{};  // sQ1.V: optical axis, image x, image y (dome frame)
  int32_t cos_half_aov = 0;              // sQ1.V: cos(aov/2) (near_cos_alpha_srch)
  std::array<int32_t, 3> c{};            // sQ(16-Pp).Pp mm: camera centre (extension)
  std::array<int32_t, 5> k{};            // sQ(16-K).K: k1..k5 (eq. 5.24-5.26)
  uint32_t fu = 0, fv = 0;               // uQ(16-Ff).Ff pixels
  uint32_t cu = 0, cv = 0;               // uQ(16-Fc).Fc pixels
  int width = 0, height = 0;             // frame size; lw of eq. 5.27 = width
};

// The sin and cos quarter-wave ROMs (B2). sin_rom[i] = round(sin(i * (pi/2) / 2^T) * 2^(W-1)),
// cos_rom[i] = round(cos(i * (pi/2) / 2^T) * 2^(W-1)), i = 0 .. 2^T - 1, uQ1.(W-1), round half up
// (tables.cc builds them; the only place where floating point meets the model: ROM initialisation).
struct SinCosRom {
  int addr_bits = 0, word_bits = 0;
  std::vector<uint32_t> sin_rom, cos_rom;
};

// Per-camera vignetting memory (Table 6.4 lut_vig 8192 x 16): a radial table of 2^vig_addr_bits
// gains per camera and three per-channel gains (R, G, B), all uQ2.14; vig_shift scales the squared
// radius into the table index. Unit tables (every gain 1.0) make the correction an exact no-op.
struct VignettingTables {
  int vig_shift = 0;
  std::vector<std::vector<uint32_t>> radial;     // [camera][index]
  std::vector<std::array<uint32_t, 3>> channel;  // [camera][R, G, B]
};

// ---------------------------------------------------------------------------------------------
// Datapath values
// ---------------------------------------------------------------------------------------------

struct Angles {
  uint32_t theta = 0, phi = 0;  // uQ0.M
};

struct Omega {
  std::array<int32_t, 3> w{};  // sQ1.W (W + 2 bits), dome frame
};

// One direction's camera search result: which cameras passed the cone test (eq. 2.3), at most
// max_contributors of them in camera order (the priority encoder's outputs), and the dot products
// omega . t the projection reuses.
struct SearchResult {
  int count = 0;                   // contributors passed on (<= max_contributors)
  int cone_count = 0;              // cameras that passed the cone test (>= count)
  std::array<int, 8> camera{};     // camera indices, ascending (camera_bits each)
  std::array<int64_t, 8> dot_t{};  // omega . t, sQ3.(W+V)
};

// Projection result for one camera (B4).
struct PixelPos {
  bool valid = false;  // omega . t > 0 and the point lies inside [0, W) x [0, H)
  int32_t col = 0;     // uQ.F, centres at +0.5 (conventions.h)
  int32_t row = 0;     // uQ.F
};

// Block-floating unsigned value m * 2^e (the distance product of the weight unit).
struct BlockFloat {
  uint64_t m = 0;  // mantissa, Mw bits, leading one at bit Mw-1 (or 0)
  int e = 0;       // exponent (LSB weight 2^e in units of uQ.D^k)
};

// ---------------------------------------------------------------------------------------------
// B1 angle generation
// ---------------------------------------------------------------------------------------------

// The registers of `grid` at cfg.angle_bits: k = round(2^M * span / (N * 2 pi)) (round half up),
// min = round(2^M * first_centre / (2 pi)) mod 2^M. (Register computation happens in software
// that loads the chip; this function alone uses floating point.)
AngleRegs angle_regs(const HwConfig& cfg, const PanoGrid& grid);
// Angles of pixel (col, row): the accumulators' content, (min + n * k) mod 2^M.
Angles angles_at(const HwConfig& cfg, const AngleRegs& regs, int col, int row);

// ---------------------------------------------------------------------------------------------
// B2 Cartesian unit
// ---------------------------------------------------------------------------------------------

// sin and cos of an M-bit angle from the quarter-wave ROMs. The angle is rounded to T+2 bits
// (rshift_round by M-T-2, mod 2^(T+2)); its top two bits are the quadrant q, the low T bits the
// index i; sin = {S[i], C[i], -S[i], -C[i]}[q], cos = {C[i], -S[i], -C[i], S[i]}[q]. sQ1.(W-1).
struct SinCos {
  int32_t s = 0, c = 0;
};
SinCos sincos_lookup(const HwConfig& cfg, const SinCosRom& rom, uint32_t angle);

// eq. 5.16-5.18 with the identity's eq. 5.17 (the thesis prints cos(t-p) - sin(t+p); the identity
// sin t sin p = [cos(t-p) - cos(t+p)] / 2 needs cos(t+p)):
//   a = S(t+p) + S(t-p),  b = C(t-p) - C(t+p),  c = 2 C(t)   (sQ1.(W-1) sums = sQ1.W of the halves)
// and the axis map of regs.axes. Three ROM reads per table (t+p, t-p, t): Th = 3 cycles with three
// table sets, 9 with one (§5.4.3).
Omega cartesian(const HwConfig& cfg, const SinCosRom& rom, const Angles& a, AxisMap axes);

// ---------------------------------------------------------------------------------------------
// B3 camera search, priority encoder, distance
// ---------------------------------------------------------------------------------------------

// omega . t as sQ3.(W+V) (exact: three sQ1.W x sQ1.V products summed).
int64_t dot_omega(const Omega& o, const std::array<int32_t, 3>& vec);
// eq. 2.3: omega . t >= cos(aov/2), both sides in sQ3.(W+V) (cos shifted left by W; exact).
bool cone_test(const HwConfig& cfg, int64_t dot_t, int32_t cos_half_aov);
// The N parallel cone tests and the N-to-log2 N priority encoder: the first max_contributors
// cameras (in index order) that pass.
SearchResult camera_search(const HwConfig& cfg, const std::vector<CameraRegs>& cams, const Omega& o);

// eq. 5.19-5.20 with q = 0 (the dome centre, thesis default): r = (c . omega) omega - c, d = |r|.
//   s  = c . omega                          sQ.(Pp+W), exact
//   sD = rshift_round(s, Pp + W - D)        sQ.D (round half up)
//   r_k = rshift_round(sD * w_k, W) - c_k * 2^(D - Pp)     sQ.D
//   d = isqrt_floor(sum r_k^2)              uQ(17-D).D, floor; d = max(d, 1) (the float's min_r)
uint32_t distance_unit(const HwConfig& cfg, const std::array<int32_t, 3>& c, const Omega& o);

// ---------------------------------------------------------------------------------------------
// B4 projection (eq. 5.21-5.26 on normalised coordinates, conventions.h) and address (eq. 5.27)
// ---------------------------------------------------------------------------------------------

// x = div_round(dot_u * 2^P, dot_t), y likewise (the restoring divider; sQ.P), then
//   xx = rs(x*x, P), yy = rs(y*y, P), xy = rs(x*y, P), R2 = xx + yy,
//   R4 = rs(R2*R2, P), R6 = rs(R4*R2, P),
//   p  = 2^P + rs(k1*R2 + k2*R4 + k5*R6, K),
//   x' = rs(p*x, P) + rs(k4*2xy + k3*(R2 + 2xx), K),  y' = rs(p*y, P) + rs(k3*2xy + k4*(R2 + 2yy), K),
//   col = rs(fu * x', Ff + P - F) + align(cu, Fc -> F),  row likewise with fv, y', cv
// (rs = rshift_round). valid = dot_t > 0 and 0 <= col < W * 2^F and 0 <= row < H * 2^F.
PixelPos project(const HwConfig& cfg, const CameraRegs& cam, const Omega& o, int64_t dot_t);

// The 2x2 quad of a bilinear tap: the pixel-centre shift xs = col - 2^(F-1), x0 = xs >> F (floor),
// fx = xs & (2^F - 1) (likewise y), the four addresses Addr = lw * Y + X (eq. 5.27, 0-based) with X
// and Y clamped to [0, W-1] x [0, H-1] (border replication, as the float sampler), and the frame
// address = camera << frame_addr_bits | Addr. With bilinear off: the single pixel (col >> F, row >> F)
// in addr[0] and fx = fy = 0.
struct TapAddress {
  std::array<uint32_t, 4> frame_addr{};  // (x0,y0), (x0+1,y0), (x0,y0+1), (x0+1,y0+1)
  uint32_t fx = 0, fy = 0;               // uQ0.F
  int pixel_x = 0, pixel_y = 0;          // the pixel containing the point (vignetting radius)
};
TapAddress tap_address(const HwConfig& cfg, const CameraRegs& cam, int camera, const PixelPos& p);

// ---------------------------------------------------------------------------------------------
// B5 frame memory (RGB565, §5.2) and B8 colour expansion
// ---------------------------------------------------------------------------------------------

// 24 (N) frame memories behind one address decoder: frame_addr[camera_bits+frame_addr_bits-1 :
// frame_addr_bits] selects the camera (the 5-to-24 decoder of Fig. 5.15), the low bits address it.
class FrameMemory {
 public:
  FrameMemory(const HwConfig& cfg, int cameras);
  // Words of camera `cam` (W*H RGB565, row-major from address 0: line 1 pixel 1 first, eq. 5.27).
  void load(int cam, std::vector<uint16_t> words);
  uint16_t read(uint32_t frame_addr) const { return mem_[frame_addr >> addr_bits_][frame_addr & addr_mask_]; }

 private:
  int addr_bits_;
  uint32_t addr_mask_;
  std::vector<std::vector<uint16_t>> mem_;
};

// RGB565 word (R bits 15-11, G 10-5, B 4-0) -> 8-bit R, G, B by replicating the high bits into the
// low ones (31 -> 255, 63 -> 255; the same rule as isp::unpack_rgb565).
std::array<uint32_t, 3> rgb565_to_rgb888(uint16_t w);
// The native 5/6/5-bit channels of an RGB565 word (R, G, B).
std::array<uint32_t, 3> rgb565_fields(uint16_t w);
// 8-bit R, G, B -> RGB565: the 5/6/5 most significant bits (truncation, §5.2).
uint16_t rgb888_to_rgb565(uint32_t r, uint32_t g, uint32_t b);

// ---------------------------------------------------------------------------------------------
// B6 pixel value unit
// ---------------------------------------------------------------------------------------------

// Bilinear interpolation of one channel of the quad q (top-left, top-right, bottom-left,
// bottom-right; 8-bit, or the native 5/6/5 bits with expand_at_output) with weights fx, fy uQ0.F:
//   v = q0 (2^F - fx)(2^F - fy) + q1 fx (2^F - fy) + q2 (2^F - fx) fy + q3 fx fy     (uQ8.2F)
//   sample = rshift_round(v, 2F - S)                                                  (uQ8.S)
uint32_t bilinear_sample(const HwConfig& cfg, const std::array<uint32_t, 4>& q, uint32_t fx, uint32_t fy);

// Vignetting gain of channel ch (0 R, 1 G, 2 B) at pixel (x, y) of camera cam (uQ2.14):
//   dx = x - (cu >> Fc), dy = y - (cv >> Fc), i = min(2^vig_addr_bits - 1, (dx^2 + dy^2) >> vig_shift),
//   g = rshift_round(radial[cam][i] * channel[cam][ch], 14); corrected = min(max, rshift_round(s * g, 14)).
uint32_t vignetting_gain(const HwConfig& cfg, const VignettingTables& vt, const CameraRegs& cam, int camera,
                         int x, int y, int ch);

// Block-floating product (MRF evidence, §5.4.2): start from a = {d, 0} normalised, multiply by the
// uQ.D distance d: p = a.m * d, then keep the top Mw bits: sh = max(0, bit_length(p) - Mw),
// m = p >> sh (truncation), e = a.e + sh. normalise({d}) is the same with a.m = 1.
BlockFloat block_float(const HwConfig& cfg, uint64_t d);
BlockFloat block_float_mul(const HwConfig& cfg, const BlockFloat& a, uint64_t d);

// The reciprocal unit: weights w_i = floor(2^(R + Mw - 2) / m_i) >> (e_i - e_min), uQ0.R, for the n
// block-floating distance products D_i (m_i != 0), e_min = min e_i. The largest weight lies in
// (2^(R-2), 2^(R-1)]. A restoring divider with a (R + Mw - 1)-bit dividend and R-bit quotient.
void reciprocal_weights(const HwConfig& cfg, const BlockFloat* d, int n, uint32_t* w);

// Accumulation and the final division (per channel): num = sum w_i s_i, den = sum w_i,
//   out = floor((num + den * 2^(S-1)) / (den * 2^S))  (round half up to the integer channel value)
// saturated at max_value (255, or 31/63/31 with expand_at_output).
uint32_t blend(const HwConfig& cfg, const uint32_t* w, const uint32_t* samples, int n, uint32_t max_value);

// ---------------------------------------------------------------------------------------------
// B7 boundary unit (§5.4.5)
// ---------------------------------------------------------------------------------------------

// Gray level of a uQ8.S RGB sample, BT.601 integer weights: Y = rshift_round(77 R + 150 G + 29 B, 8)
// (uQ8.S).
uint32_t gray_level(uint32_t r, uint32_t g, uint32_t b);
// Single-pass min/max over the contributors' distances (strict < and >, so the first camera wins
// ties, as the float reference's min_element/max_element), |Y_k - Y_j| > th * 2^S. n >= 2 needed.
struct BoundaryResult {
  bool boundary = false;
  int nearest = 0, farthest = 0;  // indices into the contributor list (2 bits)
  uint32_t diff = 0;              // |Y_k - Y_j|, uQ8.S
};
BoundaryResult boundary_unit(const HwConfig& cfg, const uint32_t* dist, const uint32_t* gray, int n);

}  // namespace omma::hw
