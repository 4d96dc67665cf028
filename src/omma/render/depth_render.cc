#include "omma/render/depth_render.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>
#include <immintrin.h>
#include <opencv2/imgproc.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "omma/core/valid.h"
#include "omma/pano/stitch.h"
#include "omma/pano/surface.h"

namespace omma::render {

pano::PlaneSweepOptions engine_sweep_options() {
  pano::PlaneSweepOptions o;
  o.pitch_deg = 2.0;
  o.steps = 32;
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

// What a tile render reads and writes (DepthRenderer::render).
struct TileArgs {
  const uint8_t* data;  // the frame store
  size_t stride;        // its bytes per row
  const DTap *tap, *fb;
  const uint32_t *first, *ffirst;
  const DCam* cams;
  const cv::Mat* inverse;  // inverse depth on the output grid
  cv::Mat* out;
  int tiles_x, width, height;
};

// One output pixel's colour sums; Acc::add takes a tap's 2x2 neighbourhood n (compiled_map.h's row
// pairs: n[0..2] (x0, y0), n[3..5] (x0, y0+1), n[6..8] (x0+1, y0), n[9..11] (x0+1, y0+1)) with
// integer bilinear weights summing to 2^14 and the tap's weight tw / 2^14.
struct ScalarAcc {
  float a0 = 0, a1 = 0, a2 = 0;
  void add(const uint8_t* n, int w00, int w01, int w10, int w11, float tw) {
    a0 += tw * float(w00 * n[0] + w01 * n[3] + w10 * n[6] + w11 * n[9]);
    a1 += tw * float(w00 * n[1] + w01 * n[4] + w10 * n[7] + w11 * n[10]);
    a2 += tw * float(w00 * n[2] + w01 * n[5] + w10 * n[8] + w11 * n[11]);
  }
  void store(uint8_t* o, float inv) const {
    o[0] = uint8_t(std::min(255.f, a0 * inv + 0.5f));
    o[1] = uint8_t(std::min(255.f, a1 * inv + 0.5f));
    o[2] = uint8_t(std::min(255.f, a2 * inv + 0.5f));
  }
};

// Renders tile `tile` (compiled_map.h's kTileW x kTileH; its pixels start at p in render order).
template <class Acc>
inline void render_depth_tile(const TileArgs& a, int tile, size_t p) {
  const cv::Rect box = tile_rect(tile, a.tiles_x, a.width, a.height);
  for (int row = box.y; row < box.y + box.height; ++row) {
    const float* srow = a.inverse->ptr<float>(row);
    uint8_t* o = a.out->ptr<uint8_t>(row);
    for (int col = box.x; col < box.x + box.width; ++col, ++p) {
      const float s = srow[col];
      Acc acc;
      float wsum = 0;
      auto taps = [&](const DTap* t0, const DTap* t1) {
        for (const DTap* tp = t0; tp < t1; ++tp) {
          const DTap& t = *tp;
          const DCam& c = a.cams[t.cam];
          // contributors.h: the ray w + s b in the camera's frame; eq. 2.3 on it.
          const float z = t.wt + s * c.bt;
          if (z <= 0) continue;
          const float r2 = 1 + 2 * s * t.wb + s * s * c.bb;
          if (z * z < c.cos2 * r2) continue;
          const float iz = 1 / z;
          // eq. 5.21-5.22 folded into the ray: px = cu + fu x = (t.pu + s c.pu) / z
          float px = (t.pu + s * c.pu) * iz, py = (t.pv + s * c.pv) * iz;
          if (c.distort) {  // eq. 5.23-5.26 on the undistorted x = (px - cu) / fu
            const Vec2 d = distort(c.k, Vec2((px - c.cu) / c.fu, (py - c.cv) / c.fv));
            px = c.cu + c.fu * float(d.x());
            py = c.cv + c.fv * float(d.y());
          }
          if (!(px >= 0 && py >= 0 && px < c.width && py < c.height)) continue;
          // Bilinear, centres at +0.5, edges replicated: the row pair at (x0, y0) holds the 2x2.
          const float xx = std::clamp(px - 0.5f, 0.f, c.xmax),
                      yy = std::min(std::max(py - 0.5f, 0.f), c.ymax);
          const int x0 = std::min(int(xx), c.width - 2), y0 = int(yy);
          // Fixed point: the fractions in 1/128 (rounded), the four weights sum to 2^14; a
          // channel's sum of weight x 8-bit value stays under 2^22 (int32).
          const int ix = int((xx - x0) * 128 + 0.5f), iy = int((yy - y0) * 128 + 0.5f);
          const uint8_t* n = a.data + c.base + size_t(y0) * a.stride + size_t(x0) * 6;
          acc.add(n, (128 - ix) * (128 - iy), (128 - ix) * iy, ix * (128 - iy), ix * iy,
                  t.weight * (1.f / 16384));  // 2^14 -> 1
          wsum += t.weight;
        }
      };
      // The method's taps; the fallbacks (cameras that see the direction only at infinity) only
      // where every one of them left its image at this depth.
      taps(a.tap + a.first[p], a.tap + a.first[p + 1]);
      if (wsum == 0) taps(a.fb + a.ffirst[p], a.fb + a.ffirst[p + 1]);
      if (wsum > 0) {
        acc.store(o + 3 * col, 1 / wsum);
      } else {
        o[3 * col + 0] = o[3 * col + 1] = o[3 * col + 2] = 0;
      }
    }
  }
}

void depth_tile_scalar(const TileArgs& a, int tile, size_t p) { render_depth_tile<ScalarAcc>(a, tile, p); }

#pragma GCC push_options
#pragma GCC target("ssse3,sse4.1")
// The same sums with SSSE3/SSE4.1: one 16-byte load of the neighbourhood, the byte pairs
// (n[c], n[3+c]) and (n[6+c], n[9+c]) spread to 16 bits by a shuffle, two pmaddwd with the weight
// pairs (w00, w01), (w10, w11): the three channels' integer sums (identical to ScalarAcc's), one
// conversion to float.
struct SseAcc {
  __m128 a = _mm_setzero_ps();
  void add(const uint8_t* n, int w00, int w01, int w10, int w11, float tw) {
    const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(n));  // inside: kStorePadding
    const __m128i left =
        _mm_shuffle_epi8(v, _mm_setr_epi8(0, -1, 3, -1, 1, -1, 4, -1, 2, -1, 5, -1, -1, -1, -1, -1));
    const __m128i right =
        _mm_shuffle_epi8(v, _mm_setr_epi8(6, -1, 9, -1, 7, -1, 10, -1, 8, -1, 11, -1, -1, -1, -1, -1));
    const __m128i sum = _mm_add_epi32(_mm_madd_epi16(left, _mm_set1_epi32(w00 | (w01 << 16))),
                                      _mm_madd_epi16(right, _mm_set1_epi32(w10 | (w11 << 16))));
    a = _mm_add_ps(a, _mm_mul_ps(_mm_set1_ps(tw), _mm_cvtepi32_ps(sum)));
  }
  void store(uint8_t* o, float inv) const {
    alignas(16) float f[4];
    _mm_store_ps(
        f, _mm_min_ps(_mm_set1_ps(255.f), _mm_add_ps(_mm_mul_ps(a, _mm_set1_ps(inv)), _mm_set1_ps(0.5f))));
    o[0] = uint8_t(f[0]);
    o[1] = uint8_t(f[1]);
    o[2] = uint8_t(f[2]);
  }
};
__attribute__((flatten)) void depth_tile_ssse3(const TileArgs& a, int tile, size_t p) {
  render_depth_tile<SseAcc>(a, tile, p);
}
#pragma GCC pop_options

// The tile renderer for this CPU (both give the same pixels: the integer sums are exact).
using TileFn = void (*)(const TileArgs&, int, size_t);
TileFn depth_tile_kernel() {
  static const TileFn fn = __builtin_cpu_supports("ssse3") && __builtin_cpu_supports("sse4.1")
                               ? depth_tile_ssse3
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
  // tile, so that a render streams the taps and their index in order.
  std::vector<uint32_t> first, ffirst;  // per pixel in that order + 1: first tap, first fallback tap
  std::vector<uint32_t> tile_first;     // per tile: its first pixel in that order
  std::vector<DTap> taps, fallbacks;
  std::unique_ptr<pano::DepthSweep> sweep;
  std::unique_ptr<tbb::task_arena> arena;
  cv::Mat inverse, confidence, inverse_full;
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

// The taps of every pixel (row, column): first the method's taps on the reference sphere (the
// strongest always, the others if at least min_weight; renormalised), `main[row][col]` of them; then
// fallback taps with a tiny weight from the cameras that see the direction at infinity only.
struct PixelTapLists {
  std::vector<std::vector<std::vector<DTap>>> taps;
  std::vector<std::vector<std::vector<int>>> cams;  // the cameras of the main taps
};
PixelTapLists pixel_taps(const Rig& rig, const DepthRenderOptions& opt, const Vec3& q) {
  const PanoGrid& g = opt.map.grid;
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
  PixelTapLists p;
  p.cams.resize(g.height);
  for (auto& r : p.cams) r.resize(g.width);
  p.taps.resize(g.height);
  for (auto& r : p.taps) r.resize(g.width);
  pano::StitchOptions so;
  so.method = opt.map.method;
  so.grid = g;
  so.blend = opt.map.params;
  so.progress = false;
  so.depth = pano::sphere_depth(rig, g, opt.reference_mm, q);
  pano::for_each_pixel_weights(
      rig, so, [&](int col, int row, const std::vector<pano::Contributor>& cs, const std::vector<double>& w) {
        size_t best = 0;
        for (size_t i = 1; i < cs.size(); ++i)
          if (w[i] > w[best]) best = i;
        double sum = 0;
        std::vector<size_t> keep;
        for (size_t i = 0; i < cs.size(); ++i)
          if (w[i] > 0 && (i == best || w[i] >= opt.map.min_weight)) {
            keep.push_back(i);
            sum += w[i];
          }
        const Vec3 dir = g.pixel_direction(col, row);
        auto& out = p.taps[row][col];
        for (size_t i : keep) {
          out.push_back(make_tap(cs[i].camera, dir, w[i] / sum));
          p.cams[row][col].push_back(cs[i].camera);
        }
      });
  so.depth = cv::Mat();  // the cameras that see the direction at infinity only
  pano::for_each_pixel_weights(
      rig, so, [&](int col, int row, const std::vector<pano::Contributor>& cs, const std::vector<double>& w) {
        const Vec3 dir = g.pixel_direction(col, row);
        auto& out = p.taps[row][col];
        const auto& have = p.cams[row][col];
        for (size_t i = 0; i < cs.size(); ++i)
          if (w[i] > 0 && std::find(have.begin(), have.end(), cs[i].camera) == have.end() && out.size() < 255)
            out.push_back(make_tap(cs[i].camera, dir, 1e-3 * std::max(w[i], 1e-3)));
      });
  return p;
}

// The taps in render order (tile by tile, row by row inside a tile), main and fallback apart, with
// per pixel its first tap and first fallback tap and per tile its first pixel (DepthRenderer::Impl).
struct PackedTaps {
  std::vector<uint32_t> first, ffirst, tile_first;
  std::vector<DTap> taps, fallbacks;
};
PackedTaps pack_taps(const PanoGrid& g, const PixelTapLists& p);

}  // namespace

DepthRenderer::DepthRenderer(const Rig& rig, const DepthRenderOptions& opt)
    : impl_(std::make_unique<Impl>()) {
  std::string why;
  if (!opt.IsValid(&why)) throw std::invalid_argument("depth renderer: " + why);
  const auto t0 = std::chrono::steady_clock::now();
  Impl& m = *impl_;
  m.rig = rig;
  m.opt = opt;
  m.layout = StoreLayout::for_rig(rig);
  m.arena =
      opt.threads > 0 ? std::make_unique<tbb::task_arena>(opt.threads) : std::make_unique<tbb::task_arena>();
  const Vec3 q = opt.map.params.search.q;
  for (const auto& c : rig.cameras)
    m.cams.push_back(depth_camera(c, q, m.layout.offset(int(m.cams.size()), 0, 0)));
  PackedTaps packed = pack_taps(opt.map.grid, pixel_taps(rig, opt, q));
  m.first = std::move(packed.first);
  m.ffirst = std::move(packed.ffirst);
  m.tile_first = std::move(packed.tile_first);
  m.taps = std::move(packed.taps);
  m.fallbacks = std::move(packed.fallbacks);
  m.sweep = std::make_unique<pano::DepthSweep>(rig, opt.map.grid, opt.sweep);
  m.compile_s = ms_since(t0) / 1000;
}

namespace {

PackedTaps pack_taps(const PanoGrid& g, const PixelTapLists& p) {
  PackedTaps m;
  const auto& pix = p.taps;
  const auto& cams_of = p.cams;
  const size_t npx = size_t(g.width) * g.height;
  m.first.assign(npx + 1, 0);
  m.ffirst.assign(npx + 1, 0);
  const int tiles_x = (g.width + kTileW - 1) / kTileW, tiles_y = (g.height + kTileH - 1) / kTileH;
  m.tile_first.assign(size_t(tiles_x) * tiles_y, 0);
  size_t n = 0, nf = 0, qi = 0;
  for (int tile = 0; tile < tiles_x * tiles_y; ++tile) {
    const cv::Rect t = tile_rect(tile, tiles_x, g.width, g.height);
    m.tile_first[tile] = uint32_t(qi);
    for (int r = t.y; r < t.y + t.height; ++r)
      for (int c = t.x; c < t.x + t.width; ++c, ++qi) {
        m.first[qi] = uint32_t(n);
        m.ffirst[qi] = uint32_t(nf);
        n += cams_of[r][c].size();
        nf += pix[r][c].size() - cams_of[r][c].size();
      }
  }
  m.first[npx] = uint32_t(n);
  m.ffirst[npx] = uint32_t(nf);
  m.taps.resize(n);
  m.fallbacks.resize(nf);
  tbb::parallel_for(0, tiles_x * tiles_y, [&](int tile) {
    const cv::Rect t = tile_rect(tile, tiles_x, g.width, g.height);
    const size_t q0 = m.tile_first[tile];
    size_t k = m.first[q0], f = m.ffirst[q0];
    for (int r = t.y; r < t.y + t.height; ++r)
      for (int c = t.x; c < t.x + t.width; ++c) {
        const size_t nm = cams_of[r][c].size();
        for (size_t i = 0; i < pix[r][c].size(); ++i)
          (i < nm ? m.taps[k++] : m.fallbacks[f++]) = pix[r][c][i];
      }
  });
  return m;
}

}  // namespace

DepthRenderer::~DepthRenderer() = default;

DepthFrameStats DepthRenderer::render(const FrameStore& store, const std::vector<cv::Mat>& frames,
                                      cv::Mat& out, const cv::Mat& fixed_inverse) {
  Impl& m = *impl_;
  if (store.layout().row0 != m.layout.row0 || store.layout().stride_px != m.layout.stride_px)
    throw std::invalid_argument("depth renderer: the frame store's layout is not this rig's");
  DepthFrameStats st;
  const PanoGrid& g = m.opt.map.grid;
  m.arena->execute([&] {
    const auto t0 = std::chrono::steady_clock::now();
    if (!fixed_inverse.empty()) {
      const PanoGrid& cg = m.sweep->coarse_grid();
      if (fixed_inverse.type() != CV_32FC1 || fixed_inverse.cols != cg.width ||
          fixed_inverse.rows != cg.height)
        throw std::invalid_argument("depth renderer: the fixed inverse depth is not on the coarse grid");
      m.inverse = fixed_inverse.clone();
      m.confidence = cv::Mat(fixed_inverse.size(), CV_32FC1, cv::Scalar(1));
    } else {
      const bool have_prev = !m.inverse.empty();
      const bool temporal = m.opt.sweep.temporal_weight > 0 && have_prev;
      const pano::DepthEstimate e = m.sweep->estimate(frames, temporal ? m.inverse : cv::Mat(), false);
      if (have_prev && m.opt.temporal_alpha < 1)
        m.inverse = m.inverse + m.opt.temporal_alpha * (e.coarse_inverse - m.inverse);
      else
        m.inverse = e.coarse_inverse;
      m.confidence = e.coarse_confidence;
    }
    cv::resize(m.inverse, m.inverse_full, cv::Size(g.width, g.height), 0, 0, cv::INTER_LINEAR);
    st.estimate_ms = ms_since(t0);
    const auto t1 = std::chrono::steady_clock::now();
    out.create(g.height, g.width, CV_8UC3);
    const uint8_t* data = store.data();
    const size_t stride = m.layout.stride_bytes();
    const DTap* tap = m.taps.data();
    const DTap* fb = m.fallbacks.data();
    const uint32_t* first = m.first.data();
    const uint32_t* ffirst = m.ffirst.data();
    const DCam* cams = m.cams.data();
    // Tile by tile (compiled_map.h's kTileW x kTileH): the camera pixels a tile gathers stay in the
    // cache (row by row was 1.6x slower, bound by the gathers).
    const int tiles_x = (g.width + kTileW - 1) / kTileW, tiles_y = (g.height + kTileH - 1) / kTileH;
    const TileArgs args{data, stride,          tap,  fb,      first,   ffirst,
                        cams, &m.inverse_full, &out, tiles_x, g.width, g.height};
    const auto tile_fn = depth_tile_kernel();
    tbb::parallel_for(0, tiles_x * tiles_y, [&](int tile) { tile_fn(args, tile, m.tile_first[tile]); });
    st.render_ms = ms_since(t1);
  });
  st.mean_depth_mm = 1 / std::max(1e-9, cv::mean(m.inverse)[0]);
  st.mean_confidence = cv::mean(m.confidence)[0];
  return st;
}

const cv::Mat& DepthRenderer::coarse_inverse() const { return impl_->inverse; }
const cv::Mat& DepthRenderer::coarse_confidence() const { return impl_->confidence; }
cv::Mat DepthRenderer::depth() const {
  if (impl_->inverse_full.empty()) return {};
  cv::Mat d;
  cv::divide(1.0, impl_->inverse_full, d);
  return d;
}
void DepthRenderer::reset() { impl_->inverse.release(); }
const StoreLayout& DepthRenderer::layout() const { return impl_->layout; }
const pano::DepthSweep& DepthRenderer::sweep() const { return *impl_->sweep; }
size_t DepthRenderer::taps() const { return impl_->taps.size(); }
double DepthRenderer::bytes_per_pixel() const {  // what a render streams: the taps and their index
  const PanoGrid& g = impl_->opt.map.grid;
  return double(impl_->taps.size() * sizeof(DTap) + impl_->first.size() * 4 + impl_->ffirst.size() * 4) /
         (double(g.width) * g.height);
}
double DepthRenderer::compile_seconds() const { return impl_->compile_s; }

}  // namespace omma::render
