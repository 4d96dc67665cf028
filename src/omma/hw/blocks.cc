#include "omma/hw/blocks.h"

#include <cmath>
#include <stdexcept>

#include "omma/hw/fixed.h"

namespace omma::hw {
namespace {

uint32_t mask_bits(int bits) { return bits >= 32 ? 0xFFFFFFFFu : (uint32_t{1} << bits) - 1; }

// round half up of x (host-side register computation only)
int64_t round_half_up(double x) { return static_cast<int64_t>(std::floor(x + 0.5)); }

}  // namespace

// ------------------------------------------------------------------------------------------ B1

AngleRegs angle_regs(const HwConfig& cfg, const PanoGrid& grid) {
  const double turn = std::ldexp(1.0, cfg.angle_bits);  // 2^M codes = 2 pi
  const uint32_t mask = mask_bits(cfg.angle_bits);
  // Spans as fractions of a full turn (core/grid.h). The column angle follows conventions.h: it
  // DEcreases to the right, (G1) phi = -2 pi x / W and (G2) lon = 90 deg - 180 deg x / W, so the
  // column step is negative, held as its two's complement modulo 2^M (the accumulator wraps modulo
  // 2^M anyway, eq. 5.13: adding 2^M - k is subtracting k). First centre = start + step / 2.
  const AngularSpan span = angular_span(grid.projection);
  const double row_span = span.height / (2 * kPi), col_span = span.width / (2 * kPi);
  const bool vr180 = grid.projection == Projection::kVr180;
  // The angle of the left edge of column 0, in turns: +x there, i.e. longitude +90 deg for vr180
  // (G2), phi = 0 for the longitude-latitude grids (G1).
  const double col_start = vr180 ? 0.25 : 0.0;
  AngleRegs r;
  r.rows = grid.height;
  r.cols = grid.width;
  r.axes = vr180 ? AxisMap::kVr180 : AxisMap::kDome;
  r.wrap_cols = !vr180;                                                  // 360-degree grids wrap
  const int64_t col_step = round_half_up(turn * col_span / grid.width);  // |k_phi|, codes per column
  r.k_theta = static_cast<uint32_t>(round_half_up(turn * row_span / grid.height)) & mask;
  r.k_phi = static_cast<uint32_t>(-col_step) & mask;  // -|k_phi| mod 2^M
  r.theta_min = static_cast<uint32_t>(round_half_up(turn * (row_span / grid.height / 2))) & mask;
  // start - step / 2, rounded as the mirror image of the old start + step / 2 (exact in turns).
  r.phi_min = static_cast<uint32_t>(-round_half_up(turn * (col_span / grid.width / 2 - col_start))) & mask;
  return r;
}

Angles angles_at(const HwConfig& cfg, const AngleRegs& regs, int col, int row) {
  const uint32_t mask = mask_bits(cfg.angle_bits);
  // The accumulators after `row` / `col` increments of k (eq. 5.11-5.12), modulo 2^M (eq. 5.13).
  Angles a;
  a.theta = static_cast<uint32_t>(regs.theta_min + static_cast<uint64_t>(regs.k_theta) * row) & mask;
  a.phi = static_cast<uint32_t>(regs.phi_min + static_cast<uint64_t>(regs.k_phi) * col) & mask;
  return a;
}

// ------------------------------------------------------------------------------------------ B2

SinCos sincos_lookup(const HwConfig& cfg, const SinCosRom& rom, uint32_t angle) {
  const int T = cfg.sincos_addr_bits;
  const int sh = cfg.angle_bits - T - 2;
  // uQ0.M -> uQ0.(T+2): round half up, modulo a full turn.
  const uint64_t a = (sh > 0 ? (static_cast<uint64_t>(angle) + (uint64_t{1} << (sh - 1))) >> sh : angle) &
                     ((uint64_t{1} << (T + 2)) - 1);
  const uint32_t quadrant = static_cast<uint32_t>(a >> T);
  const uint32_t i = static_cast<uint32_t>(a & ((uint64_t{1} << T) - 1));
  const int32_t s = static_cast<int32_t>(rom.sin_rom[i]);  // uQ1.(W-1)
  const int32_t c = static_cast<int32_t>(rom.cos_rom[i]);
  switch (quadrant) {  // sQ1.(W-1) after the sign
    case 0:
      return {s, c};
    case 1:
      return {c, -s};
    case 2:
      return {-s, -c};
    default:
      return {-c, s};
  }
}

Omega cartesian(const HwConfig& cfg, const SinCosRom& rom, const Angles& ang, AxisMap axes) {
  const uint32_t mask = mask_bits(cfg.angle_bits);
  const uint32_t sum = (ang.theta + ang.phi) & mask;   // theta + phi, mod 2^M
  const uint32_t diff = (ang.theta - ang.phi) & mask;  // theta - phi, mod 2^M
  const SinCos p = sincos_lookup(cfg, rom, sum);
  const SinCos m = sincos_lookup(cfg, rom, diff);
  const SinCos t = sincos_lookup(cfg, rom, ang.theta);
  // sQ1.(W-1) + sQ1.(W-1) = 2 * value in sQ1.(W-1) = value in sQ1.W: the /2 of eq. 5.16-5.17 is a
  // change of format, not a shift (exact).
  const int32_t a = p.s + m.s;  // sin t cos p = [sin(t+p) + sin(t-p)] / 2        (5.16)
  const int32_t b = m.c - p.c;  // sin t sin p = [cos(t-p) - cos(t+p)] / 2        (5.17, corrected)
  const int32_t c = 2 * t.c;    // cos t, sQ1.(W-1) -> sQ1.W (exact)              (5.18)
  Omega o;
  if (axes == AxisMap::kDome)
    o.w = {a, b, c};
  else
    o.w = {b, c, a};
  return o;
}

// ------------------------------------------------------------------------------------------ B3

int64_t dot_omega(const Omega& o, const std::array<int32_t, 3>& v) {
  // sQ1.W x sQ1.V = sQ2.(W+V); three summed: sQ3.(W+V). Exact.
  return int64_t{o.w[0]} * v[0] + int64_t{o.w[1]} * v[1] + int64_t{o.w[2]} * v[2];
}

bool cone_test(const HwConfig& cfg, int64_t dot_t, int32_t cos_half_aov) {
  // cos(aov/2) sQ1.V -> sQ.(W+V) by a left shift of W (exact); eq. 2.3.
  return dot_t >= (int64_t{cos_half_aov} << cfg.sincos_word_bits);
}

SearchResult camera_search(const HwConfig& cfg, const std::vector<CameraRegs>& cams, const Omega& o) {
  SearchResult r;
  for (size_t i = 0; i < cams.size(); ++i) {
    const int64_t d = dot_omega(o, cams[i].t);
    if (!cone_test(cfg, d, cams[i].cos_half_aov)) continue;
    ++r.cone_count;
    if (r.count < cfg.max_contributors) {  // priority encoder: lowest indices first
      r.camera[r.count] = static_cast<int>(i);
      r.dot_t[r.count] = d;
      ++r.count;
    }
  }
  return r;
}

uint32_t distance_unit(const HwConfig& cfg, const std::array<int32_t, 3>& c, const Omega& o) {
  const int W = cfg.sincos_word_bits, Pp = cfg.pos_frac_bits, D = cfg.dist_frac_bits;
  // s = c . omega: sQ.Pp x sQ1.W -> sQ.(Pp+W), exact.
  const int64_t s = int64_t{c[0]} * o.w[0] + int64_t{c[1]} * o.w[1] + int64_t{c[2]} * o.w[2];
  const int64_t sd = align_frac(s, Pp + W, D);  // sQ.D, round half up
  int64_t r2 = 0;
  for (int k = 0; k < 3; ++k) {
    // (c . omega) omega_k: sQ.D x sQ1.W -> sQ.(D+W) -> sQ.D (round half up); c_k sQ.Pp -> sQ.D exact.
    const int64_t rk = rshift_round(sd * o.w[k], W) - align_frac(c[k], Pp, D);
    r2 += rk * rk;  // uQ.2D
  }
  const uint64_t d = isqrt_floor(static_cast<uint64_t>(r2));  // uQ.D, floor (restoring square root)
  return static_cast<uint32_t>(saturate(static_cast<int64_t>(d), 1, (int64_t{1} << 18) - 1));
}

// ------------------------------------------------------------------------------------------ B4

PixelPos project(const HwConfig& cfg, const CameraRegs& cam, const Omega& o, int64_t dot_t) {
  PixelPos out;
  if (dot_t <= 0) return out;
  const int P = cfg.proj_frac_bits, K = cfg.k_frac_bits, F = cfg.pix_frac_bits;
  const int64_t lim = (int64_t{1} << (cfg.proj_bits - 1)) - 1;
  const int64_t du = dot_omega(o, cam.u), dv = dot_omega(o, cam.v);
  // eq. 5.21-5.22 on normalised coordinates: sQ3.(W+V) * 2^P / sQ3.(W+V) -> sQ.P, the restoring
  // divider with round half away from zero, saturated to proj_bits.
  const int64_t x = saturate(div_round(du * (int64_t{1} << P), dot_t), -lim - 1, lim);
  const int64_t y = saturate(div_round(dv * (int64_t{1} << P), dot_t), -lim - 1, lim);
  int64_t xd = x, yd = y;
  const auto& k = cam.k;
  if (k[0] || k[1] || k[2] || k[3] || k[4]) {  // with every k = 0 the lines below give x' = x exactly
    const int64_t xx = rshift_round(x * x, P), yy = rshift_round(y * y, P),
                  xy = rshift_round(x * y, P);                                   // sQ.P
    const int64_t R2 = xx + yy;                                                  // eq. 5.23, sQ.P
    const int64_t R4 = rshift_round(R2 * R2, P), R6 = rshift_round(R4 * R2, P);  // sQ.P
    // eq. 5.24: k sQ.K x sQ.P -> sQ.(K+P), summed, -> sQ.P (round half up), + 1.0
    const int64_t p = (int64_t{1} << P) + rshift_round(k[0] * R2 + k[1] * R4 + k[4] * R6, K);
    // eq. 5.25-5.26 (conventions.h: k3, k4 tangential): products sQ.(P+P) -> sQ.P, sQ.(K+P) -> sQ.P
    xd = rshift_round(p * x, P) + rshift_round(k[3] * 2 * xy + k[2] * (R2 + 2 * xx), K);
    yd = rshift_round(p * y, P) + rshift_round(k[2] * 2 * xy + k[3] * (R2 + 2 * yy), K);
    xd = saturate(xd, -lim - 1, lim);
    yd = saturate(yd, -lim - 1, lim);
  }
  // col = fu x' + cu: uQ.Ff x sQ.P -> sQ.(Ff+P) -> sQ.F (round half up); cu uQ.Fc -> uQ.F.
  const int64_t col = align_frac(int64_t{cam.fu} * xd, cfg.focal_frac_bits + P, F) +
                      align_frac(cam.cu, cfg.centre_frac_bits, F);
  const int64_t row = align_frac(int64_t{cam.fv} * yd, cfg.focal_frac_bits + P, F) +
                      align_frac(cam.cv, cfg.centre_frac_bits, F);
  out.valid = col >= 0 && row >= 0 && col < (int64_t{cam.width} << F) && row < (int64_t{cam.height} << F);
  out.col = static_cast<int32_t>(col);
  out.row = static_cast<int32_t>(row);
  return out;
}

TapAddress tap_address(const HwConfig& cfg, const CameraRegs& cam, int camera, const PixelPos& p) {
  const int F = cfg.pix_frac_bits;
  TapAddress t;
  t.pixel_x = p.col >> F;
  t.pixel_y = p.row >> F;
  const uint32_t base = static_cast<uint32_t>(camera) << cfg.frame_addr_bits;
  const uint32_t lw = static_cast<uint32_t>(cam.width);  // eq. 5.27 line width
  if (!cfg.bilinear) {
    const uint32_t a = base | (static_cast<uint32_t>(t.pixel_y) * lw + static_cast<uint32_t>(t.pixel_x));
    t.frame_addr = {a, a, a, a};
    return t;
  }
  const int32_t xs = p.col - (1 << (F - 1)), ys = p.row - (1 << (F - 1));  // centres at +0.5
  const int32_t x0 = xs >> F, y0 = ys >> F;                                // floor
  t.fx = static_cast<uint32_t>(xs & ((1 << F) - 1));
  t.fy = static_cast<uint32_t>(ys & ((1 << F) - 1));
  auto cx = [&](int32_t x) { return static_cast<uint32_t>(saturate(x, 0, cam.width - 1)); };
  auto cy = [&](int32_t y) { return static_cast<uint32_t>(saturate(y, 0, cam.height - 1)); };
  const uint32_t X0 = cx(x0), X1 = cx(x0 + 1), Y0 = cy(y0), Y1 = cy(y0 + 1);
  t.frame_addr = {base | (Y0 * lw + X0), base | (Y0 * lw + X1), base | (Y1 * lw + X0), base | (Y1 * lw + X1)};
  return t;
}

// ------------------------------------------------------------------------------------------ B5, B8

FrameMemory::FrameMemory(const HwConfig& cfg, int cameras)
    : addr_bits_(cfg.frame_addr_bits), addr_mask_(mask_bits(cfg.frame_addr_bits)), mem_(cameras) {}

void FrameMemory::load(int cam, std::vector<uint16_t> words) {
  if (cam < 0 || cam >= static_cast<int>(mem_.size()))
    throw std::out_of_range("frame memory: no such camera");
  if (words.size() > (size_t{1} << addr_bits_))
    throw std::invalid_argument("frame memory: frame larger than the address space");
  mem_[cam] = std::move(words);
}

std::array<uint32_t, 3> rgb565_fields(uint16_t w) {
  return {uint32_t{w} >> 11, (uint32_t{w} >> 5) & 63u, w & 31u};
}

std::array<uint32_t, 3> rgb565_to_rgb888(uint16_t w) {
  const auto f = rgb565_fields(w);
  return {(f[0] << 3) | (f[0] >> 2), (f[1] << 2) | (f[1] >> 4), (f[2] << 3) | (f[2] >> 2)};
}

uint16_t rgb888_to_rgb565(uint32_t r, uint32_t g, uint32_t b) {
  return static_cast<uint16_t>(((r >> 3) << 11) | ((g >> 2) << 5) | (b >> 3));
}

// ------------------------------------------------------------------------------------------ B6

uint32_t bilinear_sample(const HwConfig& cfg, const std::array<uint32_t, 4>& q, uint32_t fx, uint32_t fy) {
  const int F = cfg.pix_frac_bits;
  const uint64_t one = uint64_t{1} << F;
  // uQ8.0 x uQ0.F x uQ0.F -> uQ8.2F (exact), then uQ8.2F -> uQ8.S round half up.
  const uint64_t v = q[0] * (one - fx) * (one - fy) + q[1] * fx * (one - fy) + q[2] * (one - fx) * fy +
                     uint64_t{q[3]} * fx * fy;
  return static_cast<uint32_t>(rshift_round(static_cast<int64_t>(v), 2 * F - cfg.sample_frac_bits));
}

uint32_t vignetting_gain(const HwConfig& cfg, const VignettingTables& vt, const CameraRegs& cam, int camera,
                         int x, int y, int ch) {
  const int64_t dx = x - static_cast<int64_t>(cam.cu >> cfg.centre_frac_bits);
  const int64_t dy = y - static_cast<int64_t>(cam.cv >> cfg.centre_frac_bits);
  const int64_t idx = std::min<int64_t>((dx * dx + dy * dy) >> vt.vig_shift, cfg.vig_entries() - 1);
  // uQ2.14 x uQ2.14 -> uQ4.28 -> uQ2.14 (round half up)
  return static_cast<uint32_t>(rshift_round(int64_t{vt.radial[camera][idx]} * vt.channel[camera][ch], 14));
}

static BlockFloat normalise(const HwConfig& cfg, uint64_t p, int e) {
  BlockFloat b;
  if (p == 0) return b;
  const int sh = bit_length(p) - cfg.weight_mant_bits;  // leading one to bit Mw-1
  b.m = sh >= 0 ? p >> sh : p << -sh;                   // truncation when narrowing
  b.e = e + sh;
  return b;
}

BlockFloat block_float(const HwConfig& cfg, uint64_t d) { return normalise(cfg, d, 0); }

BlockFloat block_float_mul(const HwConfig& cfg, const BlockFloat& a, uint64_t d) {
  return normalise(cfg, a.m * d, a.e);  // uQ.Mw x uQ.18 -> Mw + 18 bits, renormalised
}

void reciprocal_weights(const HwConfig& cfg, const BlockFloat* d, int n, uint32_t* w) {
  int emin = 0;
  bool first = true;
  for (int i = 0; i < n; ++i)
    if (d[i].m != 0 && (first || d[i].e < emin)) emin = d[i].e, first = false;
  const uint64_t num = uint64_t{1} << (cfg.recip_bits + cfg.weight_mant_bits - 2);
  for (int i = 0; i < n; ++i) {
    if (d[i].m == 0) {
      w[i] = 0;
      continue;
    }
    const int sh = d[i].e - emin;
    // restoring divider: floor(2^(R+Mw-2) / m), uQ0.R, then the exponent alignment (a right shift)
    w[i] = sh >= 64 ? 0u : static_cast<uint32_t>(udiv_floor(num, d[i].m) >> sh);
  }
}

uint32_t blend(const HwConfig& cfg, const uint32_t* w, const uint32_t* s, int n, uint32_t max_value) {
  uint64_t num = 0, den = 0;
  for (int i = 0; i < n; ++i) {
    num += uint64_t{w[i]} * s[i];  // uQ0.R x uQ8.S, acc_bits wide
    den += w[i];
  }
  if (den == 0) return 0;
  // round(num / (den * 2^S)) half up: floor((2 num + den 2^S) / (den 2^(S+1)))
  const int S = cfg.sample_frac_bits;
  const uint64_t q = udiv_floor(2 * num + (den << S), den << (S + 1));
  return static_cast<uint32_t>(std::min<uint64_t>(q, max_value));
}

// ------------------------------------------------------------------------------------------ B7

uint32_t gray_level(uint32_t r, uint32_t g, uint32_t b) {
  return static_cast<uint32_t>(rshift_round(int64_t{77} * r + int64_t{150} * g + int64_t{29} * b, 8));
}

BoundaryResult boundary_unit(const HwConfig& cfg, const uint32_t* dist, const uint32_t* gray, int n) {
  BoundaryResult b;
  if (n < 2) return b;
  for (int i = 1; i < n; ++i) {
    if (dist[i] < dist[b.nearest]) b.nearest = i;
    if (dist[i] > dist[b.farthest]) b.farthest = i;
  }
  const int64_t d = int64_t{gray[b.farthest]} - int64_t{gray[b.nearest]};
  b.diff = static_cast<uint32_t>(d < 0 ? -d : d);
  b.boundary = b.diff > (static_cast<uint32_t>(cfg.boundary_threshold) << cfg.sample_frac_bits);
  return b;
}

}  // namespace omma::hw
