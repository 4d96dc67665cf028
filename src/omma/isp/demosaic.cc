#include "omma/isp/demosaic.h"

#include <cstdlib>
#include <stdexcept>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace omma::isp {

Demosaic parse_demosaic(const std::string& name) {
  if (name == "bilinear") return Demosaic::kBilinear;
  if (name == "hybrid") return Demosaic::kHybrid;
  if (name == "ah") return Demosaic::kAdamsHamilton;
  if (name == "cc") return Demosaic::kColourCorrelation;
  throw std::invalid_argument("unknown demosaicing method '" + name + "' (use bilinear, hybrid, ah or cc)");
}

std::string demosaic_name(Demosaic m) {
  switch (m) {
    case Demosaic::kBilinear:
      return "bilinear";
    case Demosaic::kHybrid:
      return "hybrid";
    case Demosaic::kAdamsHamilton:
      return "ah";
    case Demosaic::kColourCorrelation:
      return "cc";
  }
  return "?";
}

int opencv_bayer_code_bilinear() { return cv::COLOR_BayerBG2BGR; }
int opencv_bayer_code_ea() { return cv::COLOR_BayerBG2BGR_EA; }

void check_bayer(const cv::Mat& raw, int bits) {
  if (raw.empty()) throw std::invalid_argument("raw Bayer frame is empty");
  if (raw.channels() != 1)
    throw std::invalid_argument("raw Bayer frame must have 1 channel, got " + std::to_string(raw.channels()) +
                                " (expected a 16-bit single-channel RGGB image with " + std::to_string(bits) +
                                "-bit values)");
  if (raw.depth() != CV_16U && raw.depth() != CV_8U)
    throw std::invalid_argument("raw Bayer frame must be 16-bit (or 8-bit) unsigned, got OpenCV depth " +
                                std::to_string(raw.depth()));
  if (raw.cols % 2 || raw.rows % 2 || raw.cols < 4 || raw.rows < 4)
    throw std::invalid_argument(
        "raw Bayer frame must have even width and height of at least 4 (RGGB "
        "2x2 cells), got " +
        std::to_string(raw.cols) + "x" + std::to_string(raw.rows));
  if (bits < 1 || bits > 16) throw std::invalid_argument("bits must be in 1..16");
  double mx = 0;
  cv::minMaxLoc(raw, nullptr, &mx);
  if (mx > double((1 << bits) - 1))
    throw std::invalid_argument("raw Bayer frame has values up to " + std::to_string(int(mx)) +
                                ", more than " + std::to_string(bits) + " bits allow (" +
                                std::to_string((1 << bits) - 1) + "): wrong bit depth?");
}

cv::Mat mosaic_rggb(const cv::Mat& bgr) {
  if (bgr.channels() != 3 || (bgr.depth() != CV_8U && bgr.depth() != CV_16U))
    throw std::invalid_argument("mosaic_rggb: expected an 8- or 16-bit 3-channel image");
  cv::Mat src;
  bgr.convertTo(src, CV_16U);
  cv::Mat out(bgr.size(), CV_16UC1);
  for (int y = 0; y < src.rows; ++y) {
    const uint16_t* s = src.ptr<uint16_t>(y);
    uint16_t* o = out.ptr<uint16_t>(y);
    for (int x = 0; x < src.cols; ++x) {
      // channel index in BGR: R = 2 at (even, even), B = 0 at (odd, odd), G = 1 elsewhere
      const int ch = (y % 2 == 0 && x % 2 == 0) ? 2 : (y % 2 == 1 && x % 2 == 1) ? 0 : 1;
      o[x] = s[3 * x + ch];
    }
  }
  return out;
}

namespace {

inline int clampv(int v, int maxv) { return v < 0 ? 0 : (v > maxv ? maxv : v); }

cv::Mat as_u16(const cv::Mat& raw) {
  if (raw.depth() == CV_16U) return raw;
  cv::Mat r;
  raw.convertTo(r, CV_16U);
  return r;
}

// ---------------------------------------------------------------------------------------------
// Reference: per-pixel, mirrored accessor, the equations as written.

int reflect101(int i, int n) {
  if (i < 0) return -i;
  if (i >= n) return 2 * n - 2 - i;
  return i;
}

enum Site { kR, kGr, kGb, kB };  // Gr: green on a red row, Gb: green on a blue row
Site site_at(int y, int x) {
  if (y % 2 == 0) return x % 2 == 0 ? kR : kGr;
  return x % 2 == 0 ? kGb : kB;
}

struct Window {
  const cv::Mat& m;  // CV_16UC1 or CV_32SC1
  int y, x;
  int operator()(int dy, int dx) const {
    const int yy = reflect101(y + dy, m.rows), xx = reflect101(x + dx, m.cols);
    return m.depth() == CV_16U ? int(m.at<uint16_t>(yy, xx)) : m.at<int>(yy, xx);
  }
};

// Bilinear (eq. 5.1-5.10), at one pixel: returns {R, G, B}.
std::array<int, 3> bilinear_ref(const Window& v, Site s) {
  const int c = v(0, 0);
  const int cross = v(-1, 0) + v(1, 0) + v(0, -1) + v(0, 1);   // G8 + G18 + G12 + G14
  const int diag = v(-1, -1) + v(-1, 1) + v(1, -1) + v(1, 1);  // R7 + R9 + R17 + R19
  const int horiz = v(0, -1) + v(0, 1), vert = v(-1, 0) + v(1, 0);
  switch (s) {
    case kR:
      return {c, (cross + 2) >> 2, (diag + 2) >> 2};  // (5.2), (5.5), (5.8)
    case kB:
      return {(diag + 2) >> 2, (cross + 2) >> 2, c};  // (5.1), (5.5), (5.7)
    case kGr:
      return {(horiz + 1) >> 1, c, (vert + 1) >> 1};  // (5.3), (5.6), (5.9)
    case kGb:
      return {(vert + 1) >> 1, c, (horiz + 1) >> 1};  // (5.4), (5.6), (5.10)
  }
  return {0, 0, 0};
}

// Hybrid linear method with gradient correction (eq. A.19-A.22, [88] Malvar, He & Cutler 2004):
// estimate = bilinear + gain * (centre - mean of the same colour at distance 2), alpha = 1/2 for G
// at R/B, beta = 5/8 for R/B at G, gamma = 3/4 for R at B / B at R. The green-site correction
// Delta G uses the 5x5 green support of [88] (Fig. 2): diagonal and along-neighbour greens at
// -1/8, across greens at distance 2 at +1/16. All terms are scaled by 16 and divided with rounding.
std::array<int, 3> hybrid_ref(const Window& v, Site s, int maxv) {
  const int c = v(0, 0);
  const int cross = v(-1, 0) + v(1, 0) + v(0, -1) + v(0, 1);
  const int diag = v(-1, -1) + v(-1, 1) + v(1, -1) + v(1, 1);
  const int far_h = v(0, -2) + v(0, 2), far_v = v(-2, 0) + v(2, 0);
  const int horiz = v(0, -1) + v(0, 1), vert = v(-1, 0) + v(1, 0);
  auto div16 = [&](int x16) { return clampv((x16 + 8) >> 4, maxv); };
  // (A.19)-(A.20): G at R (or B) = cross/4 + 1/2 (c - (far_h + far_v)/4)
  const int g_at_rb = div16(4 * cross + 8 * c - 2 * (far_h + far_v));
  // (A.22): R at B (or B at R) = diag/4 + 3/4 (c - (far_h + far_v)/4)
  const int x_at_xb = div16(4 * diag + 12 * c - 3 * (far_h + far_v));
  // (A.21): at a green site, colour with neighbours along the row / along the column
  const int along_row = div16(8 * horiz + 10 * c - 2 * far_h - 2 * diag + far_v);
  const int along_col = div16(8 * vert + 10 * c - 2 * far_v - 2 * diag + far_h);
  switch (s) {
    case kR:
      return {c, g_at_rb, x_at_xb};
    case kB:
      return {x_at_xb, g_at_rb, c};
    case kGr:
      return {along_row, c, along_col};
    case kGb:
      return {along_col, c, along_row};
  }
  return {0, 0, 0};
}

// Green at an R or B site by Adams-Hamilton (eq. A.1-A.5), optionally with the colour-correlation
// gradients (eq. A.13-A.18). Centre is "B13" of Fig. 5.6b; the diagonals are the other colour.
int green_ah_ref(const Window& v, bool colour_correlation, int maxv) {
  const int B13 = v(0, 0);
  const int G8 = v(-1, 0), G12 = v(0, -1), G14 = v(0, 1), G18 = v(1, 0);
  const int B3 = v(-2, 0), B11 = v(0, -2), B15 = v(0, 2), B23 = v(2, 0);
  int LH = std::abs(G14 - G12) + std::abs(2 * B13 - B11 - B15);  // (A.1)
  int LV = std::abs(G18 - G8) + std::abs(2 * B13 - B3 - B23);    // (A.2)
  if (colour_correlation) {
    // (A.13)-(A.14) for Q in {R7, R9, R17, R19}, doubled to stay integer:
    // 2 K_H(Q) = 2 Q - (left + right greens), 2 K_V(Q) = 2 Q - (upper + lower greens).
    const int dys[4] = {-1, -1, 1, 1}, dxs[4] = {-1, 1, -1, 1};
    int kh[4], kv[4];
    for (int i = 0; i < 4; ++i) {
      const int q = v(dys[i], dxs[i]);
      kh[i] = 2 * q - v(dys[i], dxs[i] - 1) - v(dys[i], dxs[i] + 1);
      kv[i] = 2 * q - v(dys[i] - 1, dxs[i]) - v(dys[i] + 1, dxs[i]);
    }
    // (A.15)-(A.16): the sum over all 16 ordered pairs of |K(Q) - K(Q')| equals the sum over the
    // 6 unordered pairs of |2K(Q) - 2K(Q')|.
    int MH = 0, MV = 0;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) {
        MH += std::abs(kh[i] - kh[j]);
        MV += std::abs(kv[i] - kv[j]);
      }
    LH += MH;  // (A.17)
    LV += MV;  // (A.18)
  }
  const int GH4 = 2 * (G12 + G14) + 2 * B13 - B11 - B15;  // 4 x (A.3)
  const int GV4 = 2 * (G8 + G18) + 2 * B13 - B3 - B23;    // 4 x (A.4)
  if (LH < LV) return clampv((GH4 + 2) >> 2, maxv);
  if (LH > LV) return clampv((GV4 + 2) >> 2, maxv);
  return clampv((GH4 + GV4 + 4) >> 3, maxv);  // (A.5)
}

// Red (or blue) by Adams-Hamilton's second step (eq. A.6-A.12) from the raw window `v` and the
// full green plane `g`, at a site where that colour is missing. `along_row`: the colour's
// neighbours are left/right (A.7) rather than up/down (A.6); `diagonal`: the site is of the
// opposite colour (A.8-A.12).
int chroma_ah_ref(const Window& v, const Window& g, bool diagonal, bool along_row, int maxv) {
  const int G13 = g(0, 0);
  if (!diagonal) {
    const int dy = along_row ? 0 : 1, dx = along_row ? 1 : 0;
    const int a = v(-dy, -dx), b = v(dy, dx);
    return clampv((a + b + 2 * G13 - g(-dy, -dx) - g(dy, dx) + 1) >> 1, maxv);  // (A.6)/(A.7)
  }
  const int R7 = v(-1, -1), R9 = v(-1, 1), R17 = v(1, -1), R19 = v(1, 1);
  const int G7 = g(-1, -1), G9 = g(-1, 1), G17 = g(1, -1), G19 = g(1, 1);
  const int dN = std::abs(R7 - R19) + std::abs(2 * G13 - G7 - G19);  // (A.8)
  const int dP = std::abs(R9 - R17) + std::abs(2 * G13 - G9 - G17);  // (A.9)
  const int N2 = R7 + R19 + 2 * G13 - G7 - G19;                      // 2 x (A.10)
  const int P2 = R9 + R17 + 2 * G13 - G9 - G17;                      // 2 x (A.11)
  if (dN < dP) return clampv((N2 + 1) >> 1, maxv);
  if (dN > dP) return clampv((P2 + 1) >> 1, maxv);
  return clampv((N2 + P2 + 2) >> 2, maxv);  // (A.12)
}

void put(cv::Mat& out, int y, int x, const std::array<int, 3>& rgb) {
  uint16_t* o = out.ptr<uint16_t>(y) + 3 * x;
  o[0] = uint16_t(rgb[2]);
  o[1] = uint16_t(rgb[1]);
  o[2] = uint16_t(rgb[0]);
}

// ---------------------------------------------------------------------------------------------
// Fast path helpers.

struct Rows {
  const uint16_t* r[5];  // rows y-2 .. y+2, each valid for x in [-2, W+2)
  int operator()(int dy, int x) const { return r[dy + 2][x]; }
};

}  // namespace

cv::Mat demosaic_reference(const cv::Mat& raw_in, Demosaic method, int bits) {
  check_bayer(raw_in, bits);
  const cv::Mat raw = as_u16(raw_in);
  const int maxv = (1 << bits) - 1;
  cv::Mat out(raw.size(), CV_16UC3);
  if (method == Demosaic::kBilinear || method == Demosaic::kHybrid) {
    for (int y = 0; y < raw.rows; ++y)
      for (int x = 0; x < raw.cols; ++x) {
        const Window v{raw, y, x};
        put(out, y, x,
            method == Demosaic::kBilinear ? bilinear_ref(v, site_at(y, x))
                                          : hybrid_ref(v, site_at(y, x), maxv));
      }
    return out;
  }
  const bool cc = method == Demosaic::kColourCorrelation;
  cv::Mat green(raw.size(), CV_32SC1);
  for (int y = 0; y < raw.rows; ++y)
    for (int x = 0; x < raw.cols; ++x) {
      const Window v{raw, y, x};
      const Site s = site_at(y, x);
      green.at<int>(y, x) = (s == kGr || s == kGb) ? v(0, 0) : green_ah_ref(v, cc, maxv);
    }
  for (int y = 0; y < raw.rows; ++y)
    for (int x = 0; x < raw.cols; ++x) {
      const Window v{raw, y, x}, g{green, y, x};
      const int c = v(0, 0), gc = g(0, 0);
      switch (site_at(y, x)) {
        case kR:
          put(out, y, x, {c, gc, chroma_ah_ref(v, g, true, false, maxv)});
          break;
        case kB:
          put(out, y, x, {chroma_ah_ref(v, g, true, false, maxv), gc, c});
          break;
        case kGr:  // red left/right, blue up/down
          put(out, y, x,
              {chroma_ah_ref(v, g, false, true, maxv), gc, chroma_ah_ref(v, g, false, false, maxv)});
          break;
        case kGb:  // red up/down, blue left/right
          put(out, y, x,
              {chroma_ah_ref(v, g, false, false, maxv), gc, chroma_ah_ref(v, g, false, true, maxv)});
          break;
      }
    }
  return out;
}

// ---------------------------------------------------------------------------------------------

namespace {

// Writes B, G, R and accumulates sums.
inline void store(uint16_t* o, int r, int g, int b, int64_t& sb, int64_t& sg, int64_t& sr) {
  o[0] = uint16_t(b);
  o[1] = uint16_t(g);
  o[2] = uint16_t(r);
  sb += b;
  sg += g;
  sr += r;
}

void bilinear_fast(const cv::Mat& pad, cv::Mat& out, std::array<int64_t, 3>& sums) {
  const int W = out.cols;
  int64_t sb = 0, sg = 0, sr = 0;
  for (int y = 0; y < out.rows; ++y) {
    const uint16_t* u = pad.ptr<uint16_t>(y + 1) + 2;
    const uint16_t* c = pad.ptr<uint16_t>(y + 2) + 2;
    const uint16_t* d = pad.ptr<uint16_t>(y + 3) + 2;
    uint16_t* o = out.ptr<uint16_t>(y);
    if (y % 2 == 0) {
      for (int x = 0; x < W; x += 2) {
        // R site at x
        const int cross = u[x] + d[x] + c[x - 1] + c[x + 1];
        const int diag = u[x - 1] + u[x + 1] + d[x - 1] + d[x + 1];
        store(o + 3 * x, c[x], (cross + 2) >> 2, (diag + 2) >> 2, sb, sg, sr);
        // G site on the red row at x+1
        const int x1 = x + 1;
        store(o + 3 * x1, (c[x1 - 1] + c[x1 + 1] + 1) >> 1, c[x1], (u[x1] + d[x1] + 1) >> 1, sb, sg, sr);
      }
    } else {
      for (int x = 0; x < W; x += 2) {
        // G site on the blue row at x
        store(o + 3 * x, (u[x] + d[x] + 1) >> 1, c[x], (c[x - 1] + c[x + 1] + 1) >> 1, sb, sg, sr);
        const int x1 = x + 1;  // B site
        const int cross = u[x1] + d[x1] + c[x1 - 1] + c[x1 + 1];
        const int diag = u[x1 - 1] + u[x1 + 1] + d[x1 - 1] + d[x1 + 1];
        store(o + 3 * x1, (diag + 2) >> 2, (cross + 2) >> 2, c[x1], sb, sg, sr);
      }
    }
  }
  sums = {sb, sg, sr};
}

void hybrid_fast(const cv::Mat& pad, cv::Mat& out, int maxv, std::array<int64_t, 3>& sums) {
  const int W = out.cols;
  int64_t sb = 0, sg = 0, sr = 0;
  auto d16 = [maxv](int x16) { return clampv((x16 + 8) >> 4, maxv); };
  for (int y = 0; y < out.rows; ++y) {
    const uint16_t* uu = pad.ptr<uint16_t>(y) + 2;
    const uint16_t* u = pad.ptr<uint16_t>(y + 1) + 2;
    const uint16_t* c = pad.ptr<uint16_t>(y + 2) + 2;
    const uint16_t* d = pad.ptr<uint16_t>(y + 3) + 2;
    const uint16_t* dd = pad.ptr<uint16_t>(y + 4) + 2;
    uint16_t* o = out.ptr<uint16_t>(y);
    for (int x = 0; x < W; x += 2) {
      // Two sites per step: x0 is R (even row) or Gb (odd row), x1 is Gr (even row) or B (odd row).
      const int x0 = x, x1 = x + 1;
      // x0: the 5x5 terms
      const int c0 = c[x0];
      const int cross0 = u[x0] + d[x0] + c[x0 - 1] + c[x0 + 1];
      const int diag0 = u[x0 - 1] + u[x0 + 1] + d[x0 - 1] + d[x0 + 1];
      const int fh0 = c[x0 - 2] + c[x0 + 2], fv0 = uu[x0] + dd[x0];
      const int c1 = c[x1];
      const int cross1 = u[x1] + d[x1] + c[x1 - 1] + c[x1 + 1];
      const int diag1 = u[x1 - 1] + u[x1 + 1] + d[x1 - 1] + d[x1 + 1];
      const int fh1 = c[x1 - 2] + c[x1 + 2], fv1 = uu[x1] + dd[x1];
      if (y % 2 == 0) {
        // R site: G (A.19), B (A.22)
        store(o + 3 * x0, c0, d16(4 * cross0 + 8 * c0 - 2 * (fh0 + fv0)),
              d16(4 * diag0 + 12 * c0 - 3 * (fh0 + fv0)), sb, sg, sr);
        // Gr site: R along the row, B along the column (A.21)
        const int h1 = c[x1 - 1] + c[x1 + 1], v1 = u[x1] + d[x1];
        store(o + 3 * x1, d16(8 * h1 + 10 * c1 - 2 * fh1 - 2 * diag1 + fv1), c1,
              d16(8 * v1 + 10 * c1 - 2 * fv1 - 2 * diag1 + fh1), sb, sg, sr);
      } else {
        // Gb site: R along the column, B along the row
        const int h0 = c[x0 - 1] + c[x0 + 1], v0 = u[x0] + d[x0];
        store(o + 3 * x0, d16(8 * v0 + 10 * c0 - 2 * fv0 - 2 * diag0 + fh0), c0,
              d16(8 * h0 + 10 * c0 - 2 * fh0 - 2 * diag0 + fv0), sb, sg, sr);
        // B site
        store(o + 3 * x1, d16(4 * diag1 + 12 * c1 - 3 * (fh1 + fv1)),
              d16(4 * cross1 + 8 * c1 - 2 * (fh1 + fv1)), c1, sb, sg, sr);
      }
    }
  }
  sums = {sb, sg, sr};
}

// Green at an R/B site, fast form of green_ah_ref (same arithmetic).
inline int green_ah_fast(const Rows& w, int x, bool cc, int maxv) {
  const int B13 = w(0, x);
  const int G8 = w(-1, x), G12 = w(0, x - 1), G14 = w(0, x + 1), G18 = w(1, x);
  const int B3 = w(-2, x), B11 = w(0, x - 2), B15 = w(0, x + 2), B23 = w(2, x);
  int LH = std::abs(G14 - G12) + std::abs(2 * B13 - B11 - B15);
  int LV = std::abs(G18 - G8) + std::abs(2 * B13 - B3 - B23);
  if (cc) {
    const int kh0 = 2 * w(-1, x - 1) - w(-1, x - 2) - w(-1, x);
    const int kh1 = 2 * w(-1, x + 1) - w(-1, x) - w(-1, x + 2);
    const int kh2 = 2 * w(1, x - 1) - w(1, x - 2) - w(1, x);
    const int kh3 = 2 * w(1, x + 1) - w(1, x) - w(1, x + 2);
    const int kv0 = 2 * w(-1, x - 1) - w(-2, x - 1) - w(0, x - 1);
    const int kv1 = 2 * w(-1, x + 1) - w(-2, x + 1) - w(0, x + 1);
    const int kv2 = 2 * w(1, x - 1) - w(0, x - 1) - w(2, x - 1);
    const int kv3 = 2 * w(1, x + 1) - w(0, x + 1) - w(2, x + 1);
    LH += std::abs(kh0 - kh1) + std::abs(kh0 - kh2) + std::abs(kh0 - kh3) + std::abs(kh1 - kh2) +
          std::abs(kh1 - kh3) + std::abs(kh2 - kh3);
    LV += std::abs(kv0 - kv1) + std::abs(kv0 - kv2) + std::abs(kv0 - kv3) + std::abs(kv1 - kv2) +
          std::abs(kv1 - kv3) + std::abs(kv2 - kv3);
  }
  const int GH4 = 2 * (G12 + G14) + 2 * B13 - B11 - B15;
  const int GV4 = 2 * (G8 + G18) + 2 * B13 - B3 - B23;
  const int g = LH < LV ? (GH4 + 2) >> 2 : LH > LV ? (GV4 + 2) >> 2 : (GH4 + GV4 + 4) >> 3;
  return clampv(g, maxv);
}

void ah_fast(const cv::Mat& pad, cv::Mat& out, bool cc, int maxv, std::array<int64_t, 3>& sums) {
  const int W = out.cols, H = out.rows;
  // Pass 1: the green plane, padded by 1 (mirrored) for pass 2.
  cv::Mat green(H, W, CV_16UC1);
  for (int y = 0; y < H; ++y) {
    Rows w;
    for (int k = 0; k < 5; ++k) w.r[k] = pad.ptr<uint16_t>(y + k) + 2;
    uint16_t* g = green.ptr<uint16_t>(y);
    const int first_rb = (y % 2 == 0) ? 0 : 1;  // R at even x on even rows, B at odd x on odd rows
    for (int x = 0; x < W; x += 2) {
      const int xr = x + first_rb, xg = x + 1 - first_rb;
      g[xg] = w.r[2][xg];
      g[xr] = uint16_t(green_ah_fast(w, xr, cc, maxv));
    }
  }
  cv::Mat gp;
  cv::copyMakeBorder(green, gp, 1, 1, 1, 1, cv::BORDER_REFLECT_101);
  int64_t sb = 0, sg = 0, sr = 0;
  for (int y = 0; y < H; ++y) {
    const uint16_t* u = pad.ptr<uint16_t>(y + 1) + 2;
    const uint16_t* c = pad.ptr<uint16_t>(y + 2) + 2;
    const uint16_t* d = pad.ptr<uint16_t>(y + 3) + 2;
    const uint16_t* gu = gp.ptr<uint16_t>(y) + 1;
    const uint16_t* gc = gp.ptr<uint16_t>(y + 1) + 1;
    const uint16_t* gd = gp.ptr<uint16_t>(y + 2) + 1;
    uint16_t* o = out.ptr<uint16_t>(y);
    auto along_row = [&](int x) {  // (A.7)
      return clampv((c[x - 1] + c[x + 1] + 2 * gc[x] - gc[x - 1] - gc[x + 1] + 1) >> 1, maxv);
    };
    auto along_col = [&](int x) {  // (A.6)
      return clampv((u[x] + d[x] + 2 * gc[x] - gu[x] - gd[x] + 1) >> 1, maxv);
    };
    auto diagonal = [&](int x) {  // (A.8)-(A.12)
      const int G13 = gc[x];
      const int dN = std::abs(u[x - 1] - d[x + 1]) + std::abs(2 * G13 - gu[x - 1] - gd[x + 1]);
      const int dP = std::abs(u[x + 1] - d[x - 1]) + std::abs(2 * G13 - gu[x + 1] - gd[x - 1]);
      const int N2 = u[x - 1] + d[x + 1] + 2 * G13 - gu[x - 1] - gd[x + 1];
      const int P2 = u[x + 1] + d[x - 1] + 2 * G13 - gu[x + 1] - gd[x - 1];
      const int v = dN < dP ? (N2 + 1) >> 1 : dN > dP ? (P2 + 1) >> 1 : (N2 + P2 + 2) >> 2;
      return clampv(v, maxv);
    };
    if (y % 2 == 0) {
      for (int x = 0; x < W; x += 2) {
        store(o + 3 * x, c[x], gc[x], diagonal(x), sb, sg, sr);                             // R site
        store(o + 3 * (x + 1), along_row(x + 1), gc[x + 1], along_col(x + 1), sb, sg, sr);  // Gr
      }
    } else {
      for (int x = 0; x < W; x += 2) {
        store(o + 3 * x, along_col(x), gc[x], along_row(x), sb, sg, sr);           // Gb
        store(o + 3 * (x + 1), diagonal(x + 1), gc[x + 1], c[x + 1], sb, sg, sr);  // B site
      }
    }
  }
  sums = {sb, sg, sr};
}

}  // namespace

namespace {

// Vectorisable planar kernels for raw values of at most 10 bits: every intermediate of the hybrid
// and bilinear filters then fits in int16 (the largest, 8 h + 10 c + fv, is at most 28 644), so
// the compiler can run 8 (SSE2) or 16 (AVX2) pixels per instruction. Each row computes every
// candidate estimate at every x with contiguous loads, then picks per CFA site with a parity mask.
// Same arithmetic as the per-site code above; the tests compare against the reference.
void linear_planar16(const cv::Mat& pad, bool hybrid, int maxv, cv::Mat planes[3]) {
  const int W = pad.cols - 4, H = pad.rows - 4;
  std::vector<int16_t> odd(static_cast<size_t>(W)), a(static_cast<size_t>(W)), bq(static_cast<size_t>(W)),
      rw(static_cast<size_t>(W)), cl(static_cast<size_t>(W));
  for (int x = 0; x < W; ++x) odd[size_t(x)] = int16_t((x & 1) ? -1 : 0);
  const int16_t mx = int16_t(maxv);
  for (int y = 0; y < H; ++y) {
    const uint16_t* __restrict uu = pad.ptr<uint16_t>(y) + 2;
    const uint16_t* __restrict u = pad.ptr<uint16_t>(y + 1) + 2;
    const uint16_t* __restrict c = pad.ptr<uint16_t>(y + 2) + 2;
    const uint16_t* __restrict d = pad.ptr<uint16_t>(y + 3) + 2;
    const uint16_t* __restrict dd = pad.ptr<uint16_t>(y + 4) + 2;
    int16_t* __restrict A = a.data();
    int16_t* __restrict Bq = bq.data();
    int16_t* __restrict Rw = rw.data();
    int16_t* __restrict Cl = cl.data();
    if (hybrid) {
#pragma GCC ivdep
      for (int x = 0; x < W; ++x) {
        const int16_t cc = int16_t(c[x]);
        const int16_t h = int16_t(c[x - 1] + c[x + 1]), v = int16_t(u[x] + d[x]);
        const int16_t dg = int16_t(u[x - 1] + u[x + 1] + d[x - 1] + d[x + 1]);
        const int16_t fh = int16_t(c[x - 2] + c[x + 2]), fv = int16_t(uu[x] + dd[x]);
        int16_t g = int16_t((int16_t(4 * (h + v) + 8 * cc - 2 * (fh + fv)) + 8) >> 4);
        int16_t o = int16_t((int16_t(4 * dg + 12 * cc - 3 * (fh + fv)) + 8) >> 4);
        int16_t r = int16_t((int16_t(8 * h + 10 * cc - 2 * fh - 2 * dg + fv) + 8) >> 4);
        int16_t l = int16_t((int16_t(8 * v + 10 * cc - 2 * fv - 2 * dg + fh) + 8) >> 4);
        A[x] = std::min(std::max(g, int16_t(0)), mx);
        Bq[x] = std::min(std::max(o, int16_t(0)), mx);
        Rw[x] = std::min(std::max(r, int16_t(0)), mx);
        Cl[x] = std::min(std::max(l, int16_t(0)), mx);
      }
    } else {
#pragma GCC ivdep
      for (int x = 0; x < W; ++x) {
        const int16_t h = int16_t(c[x - 1] + c[x + 1]), v = int16_t(u[x] + d[x]);
        const int16_t dg = int16_t(u[x - 1] + u[x + 1] + d[x - 1] + d[x + 1]);
        A[x] = int16_t((h + v + 2) >> 2);
        Bq[x] = int16_t((dg + 2) >> 2);
        Rw[x] = int16_t((h + 1) >> 1);
        Cl[x] = int16_t((v + 1) >> 1);
      }
    }
    int16_t* __restrict pb = planes[0].ptr<int16_t>(y);
    int16_t* __restrict pg = planes[1].ptr<int16_t>(y);
    int16_t* __restrict pr = planes[2].ptr<int16_t>(y);
    const int16_t* __restrict m = odd.data();
    if (y % 2 == 0) {  // R at even x, Gr at odd x
#pragma GCC ivdep
      for (int x = 0; x < W; ++x) {
        const int16_t cc = int16_t(c[x]);
        pr[x] = int16_t((Rw[x] & m[x]) | (cc & ~m[x]));
        pg[x] = int16_t((cc & m[x]) | (A[x] & ~m[x]));
        pb[x] = int16_t((Cl[x] & m[x]) | (Bq[x] & ~m[x]));
      }
    } else {  // Gb at even x, B at odd x
#pragma GCC ivdep
      for (int x = 0; x < W; ++x) {
        const int16_t cc = int16_t(c[x]);
        pr[x] = int16_t((Bq[x] & m[x]) | (Cl[x] & ~m[x]));
        pg[x] = int16_t((A[x] & m[x]) | (cc & ~m[x]));
        pb[x] = int16_t((cc & m[x]) | (Rw[x] & ~m[x]));
      }
    }
  }
}

inline int16_t abs16(int v) { return int16_t(v < 0 ? -v : v); }
inline int16_t clamp16(int v, int16_t mx) { return int16_t(v < 0 ? 0 : (v > mx ? mx : v)); }

// Pass 1 of ah_planar16: the green plane (H x W, CV_16UC1): the raw value at the green sites, the
// estimate at the R/B sites; t0 is scratch (W entries).
template <bool cc>
cv::Mat ah_green_plane16(const cv::Mat& pad, int16_t mx, const std::vector<int16_t>& odd,
                         std::vector<int16_t>& t0) {
  const int W = pad.cols - 4, H = pad.rows - 4;
  cv::Mat green(H, W, CV_16UC1);
  for (int y = 0; y < H; ++y) {
    const uint16_t* uu = pad.ptr<uint16_t>(y) + 2;
    const uint16_t* u = pad.ptr<uint16_t>(y + 1) + 2;
    const uint16_t* c = pad.ptr<uint16_t>(y + 2) + 2;
    const uint16_t* d = pad.ptr<uint16_t>(y + 3) + 2;
    const uint16_t* dd = pad.ptr<uint16_t>(y + 4) + 2;
    int16_t* est = t0.data();
#pragma GCC ivdep
    for (int x = 0; x < W; ++x) {
      const int B13 = c[x], G8 = u[x], G18 = d[x], G12 = c[x - 1], G14 = c[x + 1];
      const int B3 = uu[x], B23 = dd[x], B11 = c[x - 2], B15 = c[x + 2];
      int16_t LH = int16_t(abs16(G14 - G12) + abs16(2 * B13 - B11 - B15));
      int16_t LV = int16_t(abs16(G18 - G8) + abs16(2 * B13 - B3 - B23));
      if constexpr (cc) {
        const int16_t kh0 = int16_t(2 * u[x - 1] - u[x - 2] - u[x]);
        const int16_t kh1 = int16_t(2 * u[x + 1] - u[x] - u[x + 2]);
        const int16_t kh2 = int16_t(2 * d[x - 1] - d[x - 2] - d[x]);
        const int16_t kh3 = int16_t(2 * d[x + 1] - d[x] - d[x + 2]);
        const int16_t kv0 = int16_t(2 * u[x - 1] - uu[x - 1] - c[x - 1]);
        const int16_t kv1 = int16_t(2 * u[x + 1] - uu[x + 1] - c[x + 1]);
        const int16_t kv2 = int16_t(2 * d[x - 1] - c[x - 1] - dd[x - 1]);
        const int16_t kv3 = int16_t(2 * d[x + 1] - c[x + 1] - dd[x + 1]);
        LH = int16_t(LH + abs16(kh0 - kh1) + abs16(kh0 - kh2) + abs16(kh0 - kh3) + abs16(kh1 - kh2) +
                     abs16(kh1 - kh3) + abs16(kh2 - kh3));
        LV = int16_t(LV + abs16(kv0 - kv1) + abs16(kv0 - kv2) + abs16(kv0 - kv3) + abs16(kv1 - kv2) +
                     abs16(kv1 - kv3) + abs16(kv2 - kv3));
      }
      const int16_t GH4 = int16_t(2 * (G12 + G14) + 2 * B13 - B11 - B15);
      const int16_t GV4 = int16_t(2 * (G8 + G18) + 2 * B13 - B3 - B23);
      const int16_t gh = int16_t((GH4 + 2) >> 2), gv = int16_t((GV4 + 2) >> 2);
      const int16_t gm = int16_t((GH4 + GV4 + 4) >> 3);
      const int16_t g = LH < LV ? gh : (LH > LV ? gv : gm);
      est[x] = clamp16(g, mx);
    }
    int16_t* gp = green.ptr<int16_t>(y);
    const int16_t* m = odd.data();
    if (y % 2 == 0) {  // R sites at even x
#pragma GCC ivdep
      for (int x = 0; x < W; ++x) gp[x] = int16_t((int16_t(c[x]) & m[x]) | (est[x] & ~m[x]));
    } else {  // B sites at odd x
#pragma GCC ivdep
      for (int x = 0; x < W; ++x) gp[x] = int16_t((est[x] & m[x]) | (int16_t(c[x]) & ~m[x]));
    }
  }
  return green;
}

// Pass 2 of ah_planar16: the planes (B, G, R) from the padded raw values and the green plane;
// t0, t1 and t2 are scratch (W entries each).
void ah_chroma_planes16(const cv::Mat& pad, const cv::Mat& green, int16_t mx, const std::vector<int16_t>& odd,
                        std::vector<int16_t>& t0, std::vector<int16_t>& t1, std::vector<int16_t>& t2,
                        cv::Mat planes[3]) {
  const int W = pad.cols - 4, H = pad.rows - 4;
  cv::Mat gpad;
  cv::copyMakeBorder(green, gpad, 1, 1, 1, 1, cv::BORDER_REFLECT_101);
  for (int y = 0; y < H; ++y) {
    const uint16_t* u = pad.ptr<uint16_t>(y + 1) + 2;
    const uint16_t* c = pad.ptr<uint16_t>(y + 2) + 2;
    const uint16_t* d = pad.ptr<uint16_t>(y + 3) + 2;
    const int16_t* gu = gpad.ptr<int16_t>(y) + 1;
    const int16_t* gc = gpad.ptr<int16_t>(y + 1) + 1;
    const int16_t* gd = gpad.ptr<int16_t>(y + 2) + 1;
    int16_t* row = t0.data();  // (A.7)
    int16_t* col = t1.data();  // (A.6)
    int16_t* dia = t2.data();  // (A.8)-(A.12)
#pragma GCC ivdep
    for (int x = 0; x < W; ++x) {
      const int G13 = gc[x];
      row[x] = clamp16((c[x - 1] + c[x + 1] + 2 * G13 - gc[x - 1] - gc[x + 1] + 1) >> 1, mx);
      col[x] = clamp16((u[x] + d[x] + 2 * G13 - gu[x] - gd[x] + 1) >> 1, mx);
      const int16_t dN = int16_t(abs16(u[x - 1] - d[x + 1]) + abs16(2 * G13 - gu[x - 1] - gd[x + 1]));
      const int16_t dP = int16_t(abs16(u[x + 1] - d[x - 1]) + abs16(2 * G13 - gu[x + 1] - gd[x - 1]));
      const int16_t N2 = int16_t(u[x - 1] + d[x + 1] + 2 * G13 - gu[x - 1] - gd[x + 1]);
      const int16_t P2 = int16_t(u[x + 1] + d[x - 1] + 2 * G13 - gu[x + 1] - gd[x - 1]);
      const int16_t vn = int16_t((N2 + 1) >> 1), vp = int16_t((P2 + 1) >> 1);
      const int16_t vm = int16_t((N2 + P2 + 2) >> 2);
      dia[x] = clamp16(dN < dP ? vn : (dN > dP ? vp : vm), mx);
    }
    int16_t* pb = planes[0].ptr<int16_t>(y);
    int16_t* pg = planes[1].ptr<int16_t>(y);
    int16_t* pr = planes[2].ptr<int16_t>(y);
    const int16_t* m = odd.data();
    std::copy(gc, gc + W, pg);
    if (y % 2 == 0) {  // R at even x, Gr at odd x
#pragma GCC ivdep
      for (int x = 0; x < W; ++x) {
        pr[x] = int16_t((row[x] & m[x]) | (int16_t(c[x]) & ~m[x]));
        pb[x] = int16_t((col[x] & m[x]) | (dia[x] & ~m[x]));
      }
    } else {  // Gb at even x, B at odd x
#pragma GCC ivdep
      for (int x = 0; x < W; ++x) {
        pr[x] = int16_t((dia[x] & m[x]) | (col[x] & ~m[x]));
        pb[x] = int16_t((int16_t(c[x]) & m[x]) | (row[x] & ~m[x]));
      }
    }
  }
}

// Adams-Hamilton / colour correlation for raw values of at most 10 bits, planar and vectorisable
// (same arithmetic as green_ah_fast / ah_fast; every intermediate fits in int16: the largest,
// LH + MH, is at most 3069 + 24552). Pass 1 computes the green estimate at every x of a row and
// keeps it at the R/B sites; pass 2 computes the three chroma estimates at every x and picks.
template <bool cc>
void ah_planar16(const cv::Mat& pad, int maxv, cv::Mat planes[3]) {
  const int W = pad.cols - 4;
  const int16_t mx = int16_t(maxv);
  std::vector<int16_t> odd(static_cast<size_t>(W)), t0(static_cast<size_t>(W)), t1(static_cast<size_t>(W)),
      t2(static_cast<size_t>(W));
  for (int x = 0; x < W; ++x) odd[size_t(x)] = int16_t((x & 1) ? -1 : 0);
  const cv::Mat green = ah_green_plane16<cc>(pad, mx, odd, t0);
  ah_chroma_planes16(pad, green, mx, odd, t0, t1, t2, planes);
}
}  // namespace

void demosaic_planes(const cv::Mat& raw_in, Demosaic method, int bits, cv::Mat planes[3]) {
  check_bayer(raw_in, bits);
  const cv::Mat raw = as_u16(raw_in);
  if (bits <= 10 && (method == Demosaic::kBilinear || method == Demosaic::kHybrid)) {
    cv::Mat pad;
    cv::copyMakeBorder(raw, pad, 2, 2, 2, 2, cv::BORDER_REFLECT_101);
    for (int c = 0; c < 3; ++c) planes[c].create(raw.size(), CV_16UC1);
    linear_planar16(pad, method == Demosaic::kHybrid, (1 << bits) - 1, planes);
    return;
  }
  if (bits <= 10) {  // Adams-Hamilton and colour correlation
    cv::Mat pad;
    cv::copyMakeBorder(raw, pad, 2, 2, 2, 2, cv::BORDER_REFLECT_101);
    for (int c = 0; c < 3; ++c) planes[c].create(raw.size(), CV_16UC1);
    if (method == Demosaic::kColourCorrelation)
      ah_planar16<true>(pad, (1 << bits) - 1, planes);
    else
      ah_planar16<false>(pad, (1 << bits) - 1, planes);
    return;
  }
  cv::Mat bgr = demosaic_interleaved(raw, method, bits);
  std::vector<cv::Mat> ch;
  cv::split(bgr, ch);
  for (int c = 0; c < 3; ++c) planes[c] = ch[size_t(c)];
}

cv::Mat demosaic_interleaved(const cv::Mat& raw_in, Demosaic method, int bits, std::array<int64_t, 3>* sums) {
  check_bayer(raw_in, bits);
  const cv::Mat raw = as_u16(raw_in);
  const int maxv = (1 << bits) - 1;
  cv::Mat pad;
  cv::copyMakeBorder(raw, pad, 2, 2, 2, 2, cv::BORDER_REFLECT_101);
  cv::Mat out(raw.size(), CV_16UC3);
  std::array<int64_t, 3> s{};
  switch (method) {
    case Demosaic::kBilinear:
      bilinear_fast(pad, out, s);
      break;
    case Demosaic::kHybrid:
      hybrid_fast(pad, out, maxv, s);
      break;
    case Demosaic::kAdamsHamilton:
      ah_fast(pad, out, false, maxv, s);
      break;
    case Demosaic::kColourCorrelation:
      ah_fast(pad, out, true, maxv, s);
      break;
  }
  if (sums) *sums = s;
  return out;
}

}  // namespace omma::isp

namespace omma::isp {

cv::Mat demosaic(const cv::Mat& raw, Demosaic method, int bits, std::array<int64_t, 3>* sums) {
  if (bits <= 10) {
    cv::Mat planes[3];
    demosaic_planes(raw, method, bits, planes);
    if (sums)
      for (int c = 0; c < 3; ++c) (*sums)[size_t(c)] = int64_t(cv::sum(planes[c])[0]);
    cv::Mat out;
    cv::merge(planes, 3, out);
    return out;
  }
  return demosaic_interleaved(raw, method, bits, sums);
}

}  // namespace omma::isp
