#include "omma/render/depth_render.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <deque>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>
#include <immintrin.h>
#include <opencv2/imgproc.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "omma/core/valid.h"
#include "omma/pano/contributors.h"
#include "omma/pano/method.h"
#include "omma/pano/stitch.h"
#include "omma/pano/surface.h"
#include "omma/pano/weights.h"

namespace omma::render {

pano::PlaneSweepOptions engine_sweep_options() {
  pano::PlaneSweepOptions o;
  o.pitch_deg = 2.0;
  o.steps = 16;
  o.window = 1;
  o.paths = 4;
  o.temporal_weight = 0.2;
  return o;
}

bool DepthRenderOptions::IsValid(std::string* why) const {
  if (!map.IsValid(why)) return false;
  if (map.method == pano::Method::kSad)
    return invalid(why, "the depth-adaptive renderer does not run sad (per-frame weights)");
  if (!sweep.IsValid(why)) return false;
  if (!(reference_mm > 0) || !std::isfinite(reference_mm))
    return invalid(why, "reference distance must be positive");
  if (threads < 0) return invalid(why, "threads must be >= 0");
  if (!(temporal_alpha > 0 && temporal_alpha <= 1)) return invalid(why, "temporal alpha must be in (0, 1]");
  return true;
}

namespace {

// One tap: the pixel numerators at infinity p_u, p_v, w.t, w.b (depth_render.h), the weight.
struct DTap {
  float pu, pv;  // cu w.t + fu w.u, cv w.t + fv w.v: the pixel's numerators at infinity (eq. 5.21-5.22)
  float wt, wb;
  float weight;
  uint16_t cam;
  uint16_t pad;
};

// Per camera: b = q - c in the camera's frame, |b|^2, cos^2(aov/2), intrinsics.
struct DCam {
  float bt, bb, cos2;
  float fu, fv, cu, cv;
  float pu, pv;      // cu b.t + fu b.u, cv b.t + fv b.v (DTap::pu, pv for b)
  float xmax, ymax;  // width - 1, height - 1
  size_t base;       // the camera's first byte in the frame store
  int width, height;
  bool distort;
  std::array<double, 5> k;
};

double ms_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

// Tile `tile` of a width x height output cut into compiled_map.h's kTileW x kTileH tiles, tiles_x a row.
cv::Rect tile_rect(int tile, int tiles_x, int width, int height) {
  const int c0 = (tile % tiles_x) * kTileW, r0 = (tile / tiles_x) * kTileH;
  return cv::Rect(c0, r0, std::min(width, c0 + kTileW) - c0, std::min(height, r0 + kTileH) - r0);
}

// The bilinear interpolation of a coarse map (W' x H') onto the window's pixels in cv::resize's
// INTER_LINEAR convention (coarse pixel c looks at the centre of the output's block: grid x maps to
// (x + 0.5) W' / W - 0.5, clamped to the coarse grid): per window column the coarse columns x0, x1 and
// the weight ax of x1, per window row y0, y1, ay.
struct Axes {
  std::vector<int> x0, x1, y0, y1;
  std::vector<float> ax, ay;
  cv::Mat rows;  // per coarse row, interpolated along x onto the window's columns (H' x window width)
};
void axis(int n_coarse, int n_grid, int from, int count, std::vector<int>& i0, std::vector<int>& i1,
          std::vector<float>& a) {
  i0.resize(count);
  i1.resize(count);
  a.resize(count);
  const double scale = double(n_coarse) / n_grid;
  for (int i = 0; i < count; ++i) {
    const double s = std::clamp((from + i + 0.5) * scale - 0.5, 0.0, double(n_coarse - 1));
    const int k = std::min(int(s), std::max(0, n_coarse - 2));
    i0[i] = k;
    i1[i] = std::min(k + 1, n_coarse - 1);
    a[i] = float(s - k);
  }
}
void make_axes(const cv::Mat& coarse, const PanoGrid& g, const cv::Rect& win, Axes& x) {
  axis(coarse.cols, g.width, win.x, win.width, x.x0, x.x1, x.ax);
  axis(coarse.rows, g.height, win.y, win.height, x.y0, x.y1, x.ay);
  x.rows.create(coarse.rows, win.width, CV_32FC1);
  // Only the coarse rows the window reads (a band of a fine fixed depth reads a few of thousands).
  const int r_first = x.y0.empty() ? 0 : x.y0.front(), r_last = x.y1.empty() ? -1 : x.y1.back();
  for (int r = r_first; r <= r_last; ++r) {
    const float* s = coarse.ptr<float>(r);
    float* o = x.rows.ptr<float>(r);
    for (int c = 0; c < win.width; ++c) o[c] = (1 - x.ax[c]) * s[x.x0[c]] + x.ax[c] * s[x.x1[c]];
  }
}

// The main taps of a tile grouped by camera (render order does not matter: each tap adds into its
// pixel's sums), structure of arrays, so that a run of one camera's taps moves 8 at a time with the
// camera's constants broadcast (AVX2).
struct TapRun {
  uint32_t begin, end;  // taps [begin, end)
  uint16_t cam;
};
struct SoaTaps {
  std::vector<float> pu, pv, wt, wb, weight;  // DTap's fields
  std::vector<uint16_t> pix;                  // the tap's pixel in its tile (row-major in the tile)
  void push(const DTap& t, uint16_t p) {
    pu.push_back(t.pu), pv.push_back(t.pv), wt.push_back(t.wt), wb.push_back(t.wb);
    weight.push_back(t.weight), pix.push_back(p);
  }
  size_t size() const { return pu.size(); }
};

// What a tile render reads and writes (DepthRenderer::render).
struct TileArgs {
  const uint8_t* data;  // the frame store
  size_t stride;        // its bytes per row
  const SoaTaps* taps;
  const TapRun* runs;
  const uint32_t* tile_run;  // per tile + 1: its first run
  const DTap* fb;            // fallback taps, per pixel in render order from ffirst
  const uint32_t* ffirst;
  const DCam* cams;
  const cv::Mat* coarse;  // inverse depth on the coarse grid (1/mm)
  const Axes* up;         // its bilinear interpolation onto the window's pixels
  cv::Mat* out;
  int tiles_x, width, height;
};

// A tile's scratch: per pixel the inverse depth and the sums (b, g, r, weight).
struct TileScratch {
  alignas(64) float s[kTileW * kTileH];
  alignas(64) float acc[kTileW * kTileH * 4];
};

// Where tap (pu, pv, wt, wb) of camera c lands at inverse depth s (contributors.h; eq. 2.3 and
// 5.21-5.26): false if it leaves the camera's cone or image; else the 2x2 neighbourhood's store offset
// within the camera and the bilinear fractions in 1/128.
inline bool move_tap(const DCam& c, size_t stride, float s, float tpu, float tpv, float twt, float twb,
                     int& off, int& ix, int& iy) {
  // contributors.h: the ray w + s b in the camera's frame; eq. 2.3 on it.
  const float z = twt + s * c.bt;
  if (z <= 0) return false;
  const float r2 = 1 + 2 * s * twb + s * s * c.bb;
  if (z * z < c.cos2 * r2) return false;
  const float iz = 1 / z;
  // eq. 5.21-5.22 folded into the ray: px = cu + fu x = (t.pu + s c.pu) / z
  float px = (tpu + s * c.pu) * iz, py = (tpv + s * c.pv) * iz;
  if (c.distort) {  // eq. 5.23-5.26 on the undistorted x = (px - cu) / fu
    const Vec2 d = distort(c.k, Vec2((px - c.cu) / c.fu, (py - c.cv) / c.fv));
    px = c.cu + c.fu * float(d.x());
    py = c.cv + c.fv * float(d.y());
  }
  if (!(px >= 0 && py >= 0 && px < c.width && py < c.height)) return false;
  // Bilinear, centres at +0.5, edges replicated: the row pair at (x0, y0) holds the 2x2.
  const float xx = std::clamp(px - 0.5f, 0.f, c.xmax), yy = std::min(std::max(py - 0.5f, 0.f), c.ymax);
  const int x0 = std::min(int(xx), c.width - 2), y0 = int(yy);
  // Fixed point: the fractions in 1/128 (rounded), the four weights sum to 2^14; a channel's sum of
  // weight x 8-bit value stays under 2^22 (int32).
  ix = int((xx - x0) * 128 + 0.5f);
  iy = int((yy - y0) * 128 + 0.5f);
  off = int(size_t(y0) * stride + size_t(x0) * 6);
  return true;
}

// Adds a tap's 2x2 neighbourhood n (compiled_map.h's row pairs: n[0..2] (x0, y0), n[3..5] (x0, y0+1),
// n[6..8] (x0+1, y0), n[9..11] (x0+1, y0+1)) with the integer bilinear weights (summing to 2^14) times
// the tap's weight w / 2^14 to a pixel's sums a (b, g, r), and w to a[3].
inline void add_scalar(const uint8_t* n, int ix, int iy, float w, float* a) {
  const int w00 = (128 - ix) * (128 - iy), w01 = (128 - ix) * iy, w10 = ix * (128 - iy), w11 = ix * iy;
  const float tw = w * (1.f / 16384);
  for (int ch = 0; ch < 3; ++ch)
    a[ch] += tw * float(w00 * n[ch] + w01 * n[3 + ch] + w10 * n[6 + ch] + w11 * n[9 + ch]);
  a[3] += w;
}

// The pixels' inverse depth of the tile (Axes) into sc.s, and the sums cleared.
inline void tile_inverse(const TileArgs& a, const cv::Rect& box, TileScratch& sc) {
  const Axes& up = *a.up;
  for (int row = box.y; row < box.y + box.height; ++row) {
    const float *s0 = up.rows.ptr<float>(up.y0[row]) + box.x, *s1 = up.rows.ptr<float>(up.y1[row]) + box.x;
    const float ay = up.ay[row], by = 1 - ay;
    float* o = sc.s + (row - box.y) * box.width;
    for (int c = 0; c < box.width; ++c) o[c] = by * s0[c] + ay * s1[c];
  }
  std::fill_n(sc.acc, size_t(box.area()) * 4, 0.f);
}

// The fallback taps of pixel p (render order) at inverse depth s: the cameras that see the direction
// only at infinity, added where every one of the method's taps left its image at this depth.
inline void add_fallbacks(const TileArgs& a, size_t p, float s, float* acc) {
  for (const DTap* t = a.fb + a.ffirst[p]; t < a.fb + a.ffirst[p + 1]; ++t) {
    const DCam& cam = a.cams[t->cam];
    int off, ix, iy;
    if (move_tap(cam, a.stride, s, t->pu, t->pv, t->wt, t->wb, off, ix, iy))
      add_scalar(a.data + cam.base + off, ix, iy, t->weight, acc);
  }
}

// The tile's output from the sums; the fallbacks (cameras that see the direction only at infinity)
// only where every one of the method's taps left its image at this depth.
inline void tile_finish(const TileArgs& a, const cv::Rect& box, size_t p0, TileScratch& sc) {
  for (int r = 0; r < box.height; ++r) {
    uint8_t* o = a.out->ptr<uint8_t>(box.y + r) + 3 * box.x;
    for (int c = 0; c < box.width; ++c) {
      const int i = r * box.width + c;
      float* acc = sc.acc + 4 * i;
      if (acc[3] == 0) add_fallbacks(a, p0 + i, sc.s[i], acc);
      if (acc[3] > 0) {
        const float inv = 1 / acc[3];
        for (int ch = 0; ch < 3; ++ch) o[3 * c + ch] = uint8_t(std::min(255.f, acc[ch] * inv + 0.5f));
      } else {
        o[3 * c + 0] = o[3 * c + 1] = o[3 * c + 2] = 0;
      }
    }
  }
}

// Renders tile `tile` (compiled_map.h's kTileW x kTileH; its pixels start at p0 in render order), one
// tap at a time.
void depth_tile_scalar(const TileArgs& a, int tile, size_t p0) {
  const cv::Rect box = tile_rect(tile, a.tiles_x, a.width, a.height);
  static thread_local TileScratch sc;
  tile_inverse(a, box, sc);
  const SoaTaps& T = *a.taps;
  for (uint32_t ri = a.tile_run[tile]; ri < a.tile_run[tile + 1]; ++ri) {
    const TapRun& run = a.runs[ri];
    const DCam& c = a.cams[run.cam];
    const uint8_t* cd = a.data + c.base;
    for (uint32_t j = run.begin; j < run.end; ++j) {
      const int pix = T.pix[j];
      int off, ix, iy;
      if (move_tap(c, a.stride, sc.s[pix], T.pu[j], T.pv[j], T.wt[j], T.wb[j], off, ix, iy))
        add_scalar(cd + off, ix, iy, T.weight[j], sc.acc + 4 * pix);
    }
  }
  tile_finish(a, box, p0, sc);
}

#pragma GCC push_options
#pragma GCC target("avx2,fma,ssse3,sse4.1")
// The same with AVX2: 8 taps of a camera run at a time (the arithmetic of move_tap, without fused
// multiply-adds so that the positions are those of the scalar kernel), then per tap one 16-byte load
// of the neighbourhood, the byte pairs (n[c], n[3+c]) and (n[6+c], n[9+c]) spread to 16 bits by a
// shuffle and two pmaddwd with the weight pairs: the channels' integer sums (identical to
// add_scalar's), and 2^14 in the fourth lane so that one multiply by w / 2^14 adds the weight too.
__attribute__((flatten)) void depth_tile_avx2(const TileArgs& a, int tile, size_t p0) {
  const cv::Rect box = tile_rect(tile, a.tiles_x, a.width, a.height);
  static thread_local TileScratch sc;
  tile_inverse(a, box, sc);
  const SoaTaps& T = *a.taps;
  const __m128i sh_l = _mm_setr_epi8(0, -1, 3, -1, 1, -1, 4, -1, 2, -1, 5, -1, -1, -1, -1, -1);
  const __m128i sh_r = _mm_setr_epi8(6, -1, 9, -1, 7, -1, 10, -1, 8, -1, 11, -1, -1, -1, -1, -1);

  // Pass 1: every main tap of the tile moved (8 at a time per camera run); those that stay inside
  // their camera appended to `list`. Pass 2: the sums, with the neighbourhood 8 taps ahead prefetched
  // (the gathers from the store, not the arithmetic, bound this loop).
  // The moved taps that stay inside their camera, structure of arrays, appended 8 lanes at a time
  // (compressed by a permutation); per camera run its end in the lists and the camera's first byte.
  struct Lists {
    std::vector<int> off, wl, wh, pix;  // offset in the camera; (w00, w01), (w10, w11) as 16-bit pairs
    std::vector<float> tw;              // the tap's weight / 2^14
    std::vector<std::pair<size_t, const uint8_t*>> seg;
  };
  static thread_local Lists L;
  size_t ntaps = 0;  // the tile's main taps
  for (uint32_t ri = a.tile_run[tile]; ri < a.tile_run[tile + 1]; ++ri)
    ntaps += a.runs[ri].end - a.runs[ri].begin;
  if (L.off.size() < ntaps + 16)
    for (auto* v : {&L.off, &L.wl, &L.wh, &L.pix}) v->resize(ntaps + 16);
  if (L.tw.size() < ntaps + 16) L.tw.resize(ntaps + 16);
  L.seg.clear();
  int *l_off = L.off.data(), *l_wl = L.wl.data(), *l_wh = L.wh.data(), *l_pix = L.pix.data();
  float* l_tw = L.tw.data();
  size_t e = 0;
  const float* tw_all = T.weight.data();
  const uint16_t* pix_all = T.pix.data();
  auto push = [&](int off, int ix, int iy, uint32_t j) {
    l_off[e] = off;
    l_wl[e] = ((128 - ix) * (128 - iy)) | (((128 - ix) * iy) << 16);
    l_wh[e] = (ix * (128 - iy)) | ((ix * iy) << 16);
    l_tw[e] = tw_all[j] * (1.f / 16384);
    l_pix[e] = pix_all[j];
    ++e;
  };
  // Per 8-lane mask: the permutation that moves the set lanes to the front.
  static const auto lut = [] {
    std::array<std::array<int, 8>, 256> t{};
    for (int m = 0; m < 256; ++m)
      for (int l = 0, k = 0; l < 8; ++l)
        if (m >> l & 1) t[m][k++] = l;
    return t;
  }();
  const float *tpu = T.pu.data(), *tpv = T.pv.data(), *twt = T.wt.data(), *twb = T.wb.data(),
              *weight = T.weight.data();
  const __m256 inv14 = _mm256_set1_ps(1.f / 16384);
  const __m256i i128 = _mm256_set1_epi32(128);
  for (uint32_t ri = a.tile_run[tile]; ri < a.tile_run[tile + 1]; ++ri) {
    const TapRun& run = a.runs[ri];
    const DCam& c = a.cams[run.cam];
    const uint8_t* cd = a.data + c.base;
    const __m256 bt = _mm256_set1_ps(c.bt), bb = _mm256_set1_ps(c.bb), cos2 = _mm256_set1_ps(c.cos2),
                 cpu = _mm256_set1_ps(c.pu), cpv = _mm256_set1_ps(c.pv), zero = _mm256_setzero_ps(),
                 one = _mm256_set1_ps(1.f), two = _mm256_set1_ps(2.f), half = _mm256_set1_ps(0.5f),
                 w = _mm256_set1_ps(float(c.width)), h = _mm256_set1_ps(float(c.height)),
                 xmax = _mm256_set1_ps(c.xmax), ymax = _mm256_set1_ps(c.ymax), k128 = _mm256_set1_ps(128.f);
    const __m256i wm2 = _mm256_set1_epi32(c.width - 2), stride = _mm256_set1_epi32(int(a.stride)),
                  six = _mm256_set1_epi32(6);
    uint32_t j = run.begin;
    for (; j + 8 <= run.end; j += 8) {
      const __m256i pix =
          _mm256_cvtepu16_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(pix_all + j)));
      const __m256 s = _mm256_i32gather_ps(sc.s, pix, 4);
      const __m256 z = _mm256_add_ps(_mm256_loadu_ps(twt + j), _mm256_mul_ps(s, bt));
      const __m256 r2 =
          _mm256_add_ps(_mm256_add_ps(one, _mm256_mul_ps(_mm256_mul_ps(two, s), _mm256_loadu_ps(twb + j))),
                        _mm256_mul_ps(_mm256_mul_ps(s, s), bb));
      __m256 ok = _mm256_and_ps(_mm256_cmp_ps(z, zero, _CMP_GT_OQ),
                                _mm256_cmp_ps(_mm256_mul_ps(z, z), _mm256_mul_ps(cos2, r2), _CMP_GE_OQ));
      const __m256 iz = _mm256_div_ps(one, z);
      __m256 px = _mm256_mul_ps(_mm256_add_ps(_mm256_loadu_ps(tpu + j), _mm256_mul_ps(s, cpu)), iz);
      __m256 py = _mm256_mul_ps(_mm256_add_ps(_mm256_loadu_ps(tpv + j), _mm256_mul_ps(s, cpv)), iz);
      if (c.distort) {  // the lens per lane (double, as move_tap)
        alignas(32) float lx[8], ly[8];
        _mm256_store_ps(lx, px);
        _mm256_store_ps(ly, py);
        for (int l = 0; l < 8; ++l) {
          const Vec2 d = distort(c.k, Vec2((lx[l] - c.cu) / c.fu, (ly[l] - c.cv) / c.fv));
          lx[l] = c.cu + c.fu * float(d.x());
          ly[l] = c.cv + c.fv * float(d.y());
        }
        px = _mm256_load_ps(lx);
        py = _mm256_load_ps(ly);
      }
      ok = _mm256_and_ps(
          ok, _mm256_and_ps(
                  _mm256_and_ps(_mm256_cmp_ps(px, zero, _CMP_GE_OQ), _mm256_cmp_ps(py, zero, _CMP_GE_OQ)),
                  _mm256_and_ps(_mm256_cmp_ps(px, w, _CMP_LT_OQ), _mm256_cmp_ps(py, h, _CMP_LT_OQ))));
      int mask = _mm256_movemask_ps(ok);
      if (!mask) continue;
      const __m256 xx = _mm256_min_ps(_mm256_max_ps(_mm256_sub_ps(px, half), zero), xmax);
      const __m256 yy = _mm256_min_ps(_mm256_max_ps(_mm256_sub_ps(py, half), zero), ymax);
      const __m256i x0 = _mm256_min_epi32(_mm256_cvttps_epi32(xx), wm2), y0 = _mm256_cvttps_epi32(yy);
      const __m256i ix = _mm256_cvttps_epi32(
          _mm256_add_ps(_mm256_mul_ps(_mm256_sub_ps(xx, _mm256_cvtepi32_ps(x0)), k128), half));
      const __m256i iy = _mm256_cvttps_epi32(
          _mm256_add_ps(_mm256_mul_ps(_mm256_sub_ps(yy, _mm256_cvtepi32_ps(y0)), k128), half));
      const __m256i jx = _mm256_sub_epi32(i128, ix), jy = _mm256_sub_epi32(i128, iy);
      const __m256i perm = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(lut[mask].data()));
      auto put = [&](int* dst, __m256i v) {
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(dst + e), _mm256_permutevar8x32_epi32(v, perm));
      };
      put(l_off, _mm256_add_epi32(_mm256_mullo_epi32(y0, stride), _mm256_mullo_epi32(x0, six)));
      put(l_wl,
          _mm256_or_si256(_mm256_mullo_epi32(jx, jy), _mm256_slli_epi32(_mm256_mullo_epi32(jx, iy), 16)));
      put(l_wh,
          _mm256_or_si256(_mm256_mullo_epi32(ix, jy), _mm256_slli_epi32(_mm256_mullo_epi32(ix, iy), 16)));
      put(l_pix, pix);
      _mm256_storeu_ps(l_tw + e,
                       _mm256_permutevar8x32_ps(_mm256_mul_ps(_mm256_loadu_ps(weight + j), inv14), perm));
      e += size_t(__builtin_popcount(mask));
    }
    for (; j < run.end; ++j) {
      int o, ix, iy;
      if (move_tap(c, a.stride, sc.s[pix_all[j]], T.pu[j], T.pv[j], T.wt[j], T.wb[j], o, ix, iy))
        push(o, ix, iy, j);
    }
    L.seg.emplace_back(e, cd);
  }
  size_t i = 0;
  for (const auto& [end, cd] : L.seg)
    for (; i < end; ++i) {
      _mm_prefetch(reinterpret_cast<const char*>(cd + l_off[i + 8]), _MM_HINT_T0);  // 16 entries of slack
      const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(cd + l_off[i]));  // kStorePadding
      __m128i sum = _mm_add_epi32(_mm_madd_epi16(_mm_shuffle_epi8(v, sh_l), _mm_set1_epi32(l_wl[i])),
                                  _mm_madd_epi16(_mm_shuffle_epi8(v, sh_r), _mm_set1_epi32(l_wh[i])));
      sum = _mm_insert_epi32(sum, 16384, 3);
      float* acc = sc.acc + 4 * l_pix[i];
      _mm_store_ps(acc, _mm_add_ps(_mm_load_ps(acc), _mm_mul_ps(_mm_set1_ps(l_tw[i]), _mm_cvtepi32_ps(sum))));
    }
  // The output: fallbacks where no main tap stayed, then the sums / their weight.
  for (int r = 0; r < box.height; ++r) {
    uint8_t* o = a.out->ptr<uint8_t>(box.y + r) + 3 * box.x;
    for (int cc = 0; cc < box.width; ++cc) {
      const int i = r * box.width + cc;
      float* acc = sc.acc + 4 * i;
      if (acc[3] == 0) {
        add_fallbacks(a, p0 + i, sc.s[i], acc);
        if (acc[3] == 0) {
          o[3 * cc + 0] = o[3 * cc + 1] = o[3 * cc + 2] = 0;
          continue;
        }
      }
      const __m128 v = _mm_load_ps(acc);
      const __m128 q = _mm_min_ps(_mm_add_ps(_mm_mul_ps(v, _mm_set1_ps(1 / acc[3])), _mm_set1_ps(0.5f)),
                                  _mm_set1_ps(255.f));
      const __m128i b = _mm_cvttps_epi32(q);
      const int packed = _mm_cvtsi128_si32(_mm_packus_epi16(_mm_packs_epi32(b, b), _mm_setzero_si128()));
      o[3 * cc + 0] = uint8_t(packed);
      o[3 * cc + 1] = uint8_t(packed >> 8);
      o[3 * cc + 2] = uint8_t(packed >> 16);
    }
  }
}
#pragma GCC pop_options

// The tile renderer for this CPU (both give the same pixels up to the order of the float sums).
using TileFn = void (*)(const TileArgs&, int, size_t);
TileFn depth_tile_kernel() {
  static const TileFn fn = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
                                   __builtin_cpu_supports("ssse3") && __builtin_cpu_supports("sse4.1")
                               ? depth_tile_avx2
                               : depth_tile_scalar;
  return fn;
}

}  // namespace

struct DepthRenderer::Impl {
  Rig rig;
  DepthRenderOptions opt;
  StoreLayout layout;
  std::vector<DCam> cams;
  // Pixels in render order: tile by tile (compiled_map.h's kTileW x kTileH), row by row inside a
  // tile. The main taps tile by tile, inside a tile grouped by camera (runs); the fallbacks per pixel.
  SoaTaps taps;
  std::vector<TapRun> runs;
  std::vector<uint32_t> tile_run;    // per tile + 1: its first run
  std::vector<uint32_t> ffirst;      // per pixel in render order + 1: first fallback tap
  std::vector<uint32_t> tile_first;  // per tile: its first pixel in that order
  std::vector<DTap> fallbacks;
  std::unique_ptr<pano::DepthSweep> sweep;
  std::unique_ptr<tbb::task_arena> arena;
  cv::Rect window;                // of the grid, that the map covers
  cv::Mat inverse, confidence;    // coarse grid (inverse: the caller's fixed map itself when one was given)
  bool fixed_confidence = false;  // confidence holds the ones of a fixed depth
  Axes axes;                      // the interpolation of `inverse` onto the window
  double compile_s = 0;
};

namespace {

// Camera c's constants for the per-frame re-projection of a tap (DCam), relative to the rig's search
// centre q; `base`: the camera's first byte in the frame store.
DCam depth_camera(const RigCamera& c, const Vec3& q, size_t base) {
  const Vec3 b = q - c.position_mm;
  DCam d;
  d.bt = float(b.dot(c.frame.t));
  d.bb = float(b.squaredNorm());
  const double ca = std::cos(c.in.aov / 2);
  d.cos2 = float(ca * ca);
  d.fu = float(c.in.fu);
  d.fv = float(c.in.fv);
  d.cu = float(c.in.cu);
  d.cv = float(c.in.cv);
  d.width = c.in.width;
  d.height = c.in.height;
  d.pu = float(c.in.cu * b.dot(c.frame.t) + c.in.fu * b.dot(c.frame.u));
  d.pv = float(c.in.cv * b.dot(c.frame.t) + c.in.fv * b.dot(c.frame.v));
  d.xmax = float(c.in.width - 1);
  d.ymax = float(c.in.height - 1);
  d.base = base;
  d.distort = c.in.has_distortion();
  d.k = c.in.k;
  return d;
}

// The taps of the window's tile `tile` (render order: row by row inside the tile), as in
// pano::for_each_pixel_weights on the grid with the reference sphere: first the method's taps (the
// strongest always, the others if at least min_weight; renormalised), then fallback taps with a tiny
// weight from the cameras that see the direction at infinity only. The mrf neighbours of a pixel on the
// window's edge are the grid's (outside the window), so a band has the whole grid's taps.
struct TileTaps {
  std::vector<DTap> taps, fallbacks;
  std::vector<uint32_t> n_main, n_fb;  // per pixel of the tile
};
TileTaps tile_taps(const Rig& rig, const DepthRenderOptions& opt, const cv::Rect& win, int tiles_x,
                   int tile) {
  const PanoGrid& g = opt.map.grid;
  const Vec3 q = opt.map.params.search.q;
  const cv::Rect box = tile_rect(tile, tiles_x, win.width, win.height) + win.tl();  // grid pixels
  const bool nbr = pano::uses_neighbours(opt.map.method);
  const double R = opt.reference_mm;
  // The reference sphere |q + D w| = R (pano::sphere_depth, as float like its map).
  auto ref_depth = [&](const Vec3& w) {
    const double qw = q.dot(w);
    return double(float(-qw + std::sqrt(qw * qw - q.squaredNorm() + R * R)));
  };
  auto make_tap = [&](int cam, const Vec3& w, double weight) {
    const RigCamera& c = rig.cameras[cam];
    const Vec3 b = q - c.position_mm;
    const double wt = w.dot(c.frame.t), wu = w.dot(c.frame.u), wv = w.dot(c.frame.v);
    return DTap{float(c.in.cu * wt + c.in.fu * wu),
                float(c.in.cv * wt + c.in.fv * wv),
                float(wt),
                float(w.dot(b)),
                float(weight),
                uint16_t(cam),
                0};
  };
  // Contributors of the nodes of the tile and its one-pixel border (others, e.g. across the wrap of an
  // equirect grid, on demand), on the sphere (pass 0) and at infinity (pass 1).
  const cv::Rect ext =
      cv::Rect(box.x - 1, box.y - 1, box.width + 2, box.height + 2) & cv::Rect(0, 0, g.width, g.height);
  std::vector<std::vector<pano::Contributor>> nodes(size_t(ext.area()));
  std::vector<uint8_t> have(size_t(ext.area()));
  std::deque<std::pair<cv::Point, std::vector<pano::Contributor>>> extra;  // references stay valid
  auto node = [&](int c, int r, bool at_inf) -> const std::vector<pano::Contributor>& {
    auto find = [&] {
      const Vec3 w = g.pixel_direction(c, r);
      return pano::find_contributors(rig, w, at_inf ? pano::kInfiniteDepth : ref_depth(w),
                                     opt.map.params.search);
    };
    if (ext.contains(cv::Point(c, r))) {
      const size_t i = size_t(r - ext.y) * ext.width + (c - ext.x);
      if (!have[i]) nodes[i] = find(), have[i] = 1;
      return nodes[i];
    }
    for (const auto& e : extra)
      if (e.first == cv::Point(c, r)) return e.second;
    extra.emplace_back(cv::Point(c, r), find());
    return extra.back().second;
  };
  auto weights = [&](int c, int r, bool at_inf, const std::vector<pano::Contributor>*& centre) {
    centre = &node(c, r, at_inf);
    std::array<const std::vector<pano::Contributor>*, 4> nb{nullptr, nullptr, nullptr, nullptr};
    if (nbr) {
      const auto n = pano::grid_neighbours(g, c, r);  // left, right, up, down
      for (int k = 0; k < 4; ++k)
        if (n[k][0] >= 0) nb[k] = &node(n[k][0], n[k][1], at_inf);
    }
    // `extra` may grow while the neighbours are found: take the centre again.
    centre = &node(c, r, at_inf);
    return pano::method_weights(rig, opt.map.method, *centre, nb, opt.map.params);
  };
  TileTaps t;
  std::vector<std::vector<DTap>> px(size_t(box.area()));
  std::vector<std::vector<int>> cams(size_t(box.area()));
  for (int pass = 0; pass < 2; ++pass) {
    const bool at_inf = pass == 1;
    std::fill(have.begin(), have.end(), 0);
    extra.clear();
    for (int r = box.y; r < box.y + box.height; ++r)
      for (int c = box.x; c < box.x + box.width; ++c) {
        const size_t i = size_t(r - box.y) * box.width + (c - box.x);
        const std::vector<pano::Contributor>* cs = nullptr;
        if (node(c, r, at_inf).empty()) continue;
        const std::vector<double> w = weights(c, r, at_inf, cs);
        const Vec3 dir = g.pixel_direction(c, r);
        auto& out = px[i];
        if (!at_inf) {
          size_t best = 0;
          for (size_t k = 1; k < cs->size(); ++k)
            if (w[k] > w[best]) best = k;
          double sum = 0;
          std::vector<size_t> keep;
          for (size_t k = 0; k < cs->size(); ++k)
            if (w[k] > 0 && (k == best || w[k] >= opt.map.min_weight)) {
              keep.push_back(k);
              sum += w[k];
            }
          for (size_t k : keep) {
            out.push_back(make_tap((*cs)[k].camera, dir, w[k] / sum));
            cams[i].push_back((*cs)[k].camera);
          }
        } else {  // the cameras that see the direction at infinity only
          const auto& hv = cams[i];
          for (size_t k = 0; k < cs->size(); ++k)
            if (w[k] > 0 && std::find(hv.begin(), hv.end(), (*cs)[k].camera) == hv.end() && out.size() < 255)
              out.push_back(make_tap((*cs)[k].camera, dir, 1e-3 * std::max(w[k], 1e-3)));
        }
      }
  }
  for (size_t i = 0; i < px.size(); ++i) {
    const size_t nm = cams[i].size();
    t.n_main.push_back(uint32_t(nm));
    t.n_fb.push_back(uint32_t(px[i].size() - nm));
    t.taps.insert(t.taps.end(), px[i].begin(), px[i].begin() + nm);
    t.fallbacks.insert(t.fallbacks.end(), px[i].begin() + nm, px[i].end());
  }
  return t;
}

// The taps in render order (tile by tile of the window; inside a tile the main taps grouped by camera,
// the fallbacks per pixel row by row), with per tile its first pixel and first run (DepthRenderer::Impl).
struct PackedTaps {
  SoaTaps taps;
  std::vector<TapRun> runs;
  std::vector<uint32_t> tile_run, ffirst, tile_first;
  std::vector<DTap> fallbacks;
};
PackedTaps pack_taps(const Rig& rig, const DepthRenderOptions& opt, const cv::Rect& win) {
  const int tiles_x = (win.width + kTileW - 1) / kTileW, tiles_y = (win.height + kTileH - 1) / kTileH;
  std::vector<TileTaps> td(size_t(tiles_x) * tiles_y);
  tbb::parallel_for(0, tiles_x * tiles_y,
                    [&](int tile) { td[tile] = tile_taps(rig, opt, win, tiles_x, tile); });
  PackedTaps m;
  const size_t npx = size_t(win.width) * win.height;
  m.ffirst.assign(npx + 1, 0);
  m.tile_first.assign(td.size(), 0);
  m.tile_run.assign(td.size() + 1, 0);
  size_t nf = 0, qi = 0;
  for (size_t tile = 0; tile < td.size(); ++tile) {
    TileTaps& t = td[tile];
    m.tile_first[tile] = uint32_t(qi);
    // The main taps by camera (a stable sort: per camera in pixel order).
    std::vector<std::pair<uint16_t, uint16_t>> order;  // (camera, pixel) per tap
    std::vector<uint32_t> tap_of;
    for (size_t i = 0, k = 0; i < t.n_main.size(); ++i)
      for (uint32_t j = 0; j < t.n_main[i]; ++j, ++k)
        order.emplace_back(t.taps[k].cam, uint16_t(i)), tap_of.push_back(uint32_t(k));
    std::vector<uint32_t> idx(order.size());
    for (size_t i = 0; i < idx.size(); ++i) idx[i] = uint32_t(i);
    std::stable_sort(idx.begin(), idx.end(),
                     [&](uint32_t x, uint32_t y) { return order[x].first < order[y].first; });
    for (uint32_t i : idx) {
      const uint16_t cam = order[i].first;
      if (m.runs.size() == m.tile_run[tile] || m.runs.back().cam != cam)
        m.runs.push_back(TapRun{uint32_t(m.taps.size()), uint32_t(m.taps.size()), cam});
      m.taps.push(t.taps[tap_of[i]], order[i].second);
      m.runs.back().end = uint32_t(m.taps.size());
    }
    m.tile_run[tile + 1] = uint32_t(m.runs.size());
    for (size_t i = 0; i < t.n_fb.size(); ++i, ++qi) {
      m.ffirst[qi] = uint32_t(nf);
      nf += t.n_fb[i];
    }
    m.fallbacks.insert(m.fallbacks.end(), t.fallbacks.begin(), t.fallbacks.end());
    t = TileTaps();
  }
  m.ffirst[npx] = uint32_t(nf);
  return m;
}

}  // namespace

DepthRenderer::DepthRenderer(const Rig& rig, const DepthRenderOptions& opt)
    : impl_(std::make_unique<Impl>()) {
  std::string why;
  if (!opt.IsValid(&why)) throw std::invalid_argument("depth renderer: " + why);
  const auto t0 = std::chrono::steady_clock::now();
  Impl& m = *impl_;
  m.rig = rig;
  m.opt = opt;
  m.window =
      opt.map.window.empty() ? cv::Rect(0, 0, opt.map.grid.width, opt.map.grid.height) : opt.map.window;
  m.layout = StoreLayout::for_rig(rig);
  m.arena =
      opt.threads > 0 ? std::make_unique<tbb::task_arena>(opt.threads) : std::make_unique<tbb::task_arena>();
  const Vec3 q = opt.map.params.search.q;
  pano::sphere_depth(rig, PanoGrid{opt.map.grid.projection, 1, 1}, opt.reference_mm,
                     q);  // throws inside the dome
  for (const auto& c : rig.cameras) {
    // The kernel's offsets inside a camera's rows are 32-bit.
    if (double(c.in.height) * double(m.layout.stride_bytes()) >= 2147483647.0)
      throw std::invalid_argument(fmt::format(
          "depth renderer: camera {}'s {} rows of {} store bytes exceed the kernel's 32-bit offsets", c.id,
          c.in.height, m.layout.stride_bytes()));
    m.cams.push_back(depth_camera(c, q, m.layout.offset(int(m.cams.size()), 0, 0)));
  }
  m.arena->execute([&] {
    PackedTaps packed = pack_taps(rig, opt, m.window);
    m.taps = std::move(packed.taps);
    m.runs = std::move(packed.runs);
    m.tile_run = std::move(packed.tile_run);
    m.ffirst = std::move(packed.ffirst);
    m.tile_first = std::move(packed.tile_first);
    m.fallbacks = std::move(packed.fallbacks);
    if (opt.estimate) m.sweep = std::make_unique<pano::DepthSweep>(rig, opt.map.grid, opt.sweep);
  });
  m.compile_s = ms_since(t0) / 1000;
}

DepthRenderer::~DepthRenderer() = default;

namespace {
// Throws unless `inv` is a CV_32FC1 coarse map of the whole grid g at an integer factor.
void check_coarse(const cv::Mat& inv, const PanoGrid& g) {
  if (inv.type() != CV_32FC1 || inv.empty() || g.width % inv.cols != 0 || g.height % inv.rows != 0 ||
      g.width / inv.cols != g.height / inv.rows)
    throw std::invalid_argument(fmt::format(
        "depth renderer: the fixed inverse depth must be CV_32FC1 on a coarse grid of the whole {}x{} "
        "panorama at one integer factor, got {}x{}{}",
        g.width, g.height, inv.cols, inv.rows, inv.type() == CV_32FC1 ? "" : " (not CV_32FC1)"));
}
}  // namespace

DepthFrameStats DepthRenderer::render(const FrameStore& store, const std::vector<cv::Mat>& frames,
                                      cv::Mat& out, const cv::Mat& fixed_inverse) {
  Impl& m = *impl_;
  if (store.layout().row0 != m.layout.row0 || store.layout().stride_px != m.layout.stride_px)
    throw std::invalid_argument("depth renderer: the frame store's layout is not this rig's");
  if (!m.sweep && fixed_inverse.empty())
    throw std::invalid_argument(
        "depth renderer: built without the estimate (estimate = false): render() needs a fixed inverse "
        "depth");
  DepthFrameStats st;
  const PanoGrid& g = m.opt.map.grid;
  const cv::Rect win = m.window;
  m.arena->execute([&] {
    const auto t0 = std::chrono::steady_clock::now();
    if (!fixed_inverse.empty()) {
      check_coarse(fixed_inverse, g);
      // A reference, not a copy: the bands of one large panorama share one fine fixed depth.
      m.inverse = fixed_inverse;
      if (!m.fixed_confidence || m.confidence.size() != fixed_inverse.size())
        m.confidence = cv::Mat(fixed_inverse.size(), CV_32FC1, cv::Scalar(1));
      m.fixed_confidence = true;
    } else {
      const bool have_prev = !m.inverse.empty() && m.inverse.cols == m.sweep->coarse_grid().width &&
                             m.inverse.rows == m.sweep->coarse_grid().height;
      const bool temporal = m.opt.sweep.temporal_weight > 0 && have_prev;
      const pano::DepthEstimate e = m.sweep->estimate(frames, temporal ? m.inverse : cv::Mat(), false);
      if (have_prev && m.opt.temporal_alpha < 1)
        m.inverse = m.inverse + m.opt.temporal_alpha * (e.coarse_inverse - m.inverse);
      else
        m.inverse = e.coarse_inverse;
      m.confidence = e.coarse_confidence;
      m.fixed_confidence = false;
      st.sweep = e.timing;
    }
    make_axes(m.inverse, g, win, m.axes);
    st.estimate_ms = ms_since(t0);
    const auto t1 = std::chrono::steady_clock::now();
    out.create(win.height, win.width, CV_8UC3);
    const uint8_t* data = store.data();
    const size_t stride = m.layout.stride_bytes();
    // Tile by tile (compiled_map.h's kTileW x kTileH): the camera pixels a tile gathers stay in the
    // cache (row by row was 1.6x slower, bound by the gathers).
    const int tiles_x = (win.width + kTileW - 1) / kTileW, tiles_y = (win.height + kTileH - 1) / kTileH;
    const TileArgs args{data,
                        stride,
                        &m.taps,
                        m.runs.data(),
                        m.tile_run.data(),
                        m.fallbacks.data(),
                        m.ffirst.data(),
                        m.cams.data(),
                        &m.inverse,
                        &m.axes,
                        &out,
                        tiles_x,
                        win.width,
                        win.height};
    const auto tile_fn = m.opt.simd ? depth_tile_kernel() : depth_tile_scalar;
    tbb::parallel_for(0, tiles_x * tiles_y, [&](int tile) { tile_fn(args, tile, m.tile_first[tile]); });
    st.render_ms = ms_since(t1);
  });
  // Over the coarse rows the window reads.
  const cv::Range rows(m.axes.y0.empty() ? 0 : m.axes.y0.front(),
                       m.axes.y1.empty() ? 1 : m.axes.y1.back() + 1);
  st.mean_depth_mm = 1 / std::max(1e-9, cv::mean(m.inverse.rowRange(rows))[0]);
  st.mean_confidence = cv::mean(m.confidence.rowRange(rows))[0];
  return st;
}

const cv::Mat& DepthRenderer::coarse_inverse() const { return impl_->inverse; }
const cv::Mat& DepthRenderer::coarse_confidence() const { return impl_->confidence; }
cv::Mat DepthRenderer::depth() const {
  const Impl& m = *impl_;
  if (m.inverse.empty()) return {};
  const Axes& up = m.axes;
  cv::Mat d(m.window.size(), CV_32FC1);
  for (int r = 0; r < d.rows; ++r) {
    const float *s0 = up.rows.ptr<float>(up.y0[r]), *s1 = up.rows.ptr<float>(up.y1[r]);
    const float ay = up.ay[r], by = 1 - ay;
    for (int c = 0; c < d.cols; ++c) {
      const float s = by * s0[c] + ay * s1[c];
      d.at<float>(r, c) = s > 0 ? 1 / s : std::numeric_limits<float>::infinity();
    }
  }
  return d;
}
void DepthRenderer::reset() { impl_->inverse.release(); }
const StoreLayout& DepthRenderer::layout() const { return impl_->layout; }
const pano::DepthSweep& DepthRenderer::sweep() const {
  if (!impl_->sweep) throw std::logic_error("depth renderer: built without the estimate (estimate = false)");
  return *impl_->sweep;
}
bool DepthRenderer::estimates() const { return bool(impl_->sweep); }
size_t DepthRenderer::taps() const { return impl_->taps.size(); }
double DepthRenderer::bytes_per_pixel() const {  // what a render streams: the taps and their index
  const cv::Rect& w = impl_->window;
  const Impl& m = *impl_;
  return double(m.taps.size() * (5 * sizeof(float) + sizeof(uint16_t)) + m.runs.size() * sizeof(TapRun) +
                m.ffirst.size() * 4) /
         (double(w.width) * w.height);
}
double DepthRenderer::compile_seconds() const { return impl_->compile_s; }

}  // namespace omma::render
