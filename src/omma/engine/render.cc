#include "omma/engine/render.h"

#include <array>
#include <cmath>

#include "omma/pano/stitch.h"
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define OMMA_X86 1
#endif

namespace omma::engine {
namespace {

constexpr uint32_t kIndexMask = (1u << kIndexBits) - 1;

// Fixed-point bilinear sample (5-bit fractions fx, fy) of channel ch of the 2x2 neighbourhood whose
// top-left pixel is at a (row below at a + stride_bytes): the value times 1024.
inline int32_t bilinear_x1024(const uint8_t* a, size_t stride_bytes, int32_t fx, int32_t fy, int ch) {
  const uint8_t* c = a + stride_bytes;
  const int32_t top = a[ch] * (32 - fy) + c[ch] * fy;
  const int32_t bot = a[ch + 3] * (32 - fy) + c[ch + 3] * fy;
  return top * (32 - fx) + bot * fx;
}

// Portable kernel: one output row. Same arithmetic as the SIMD kernel (bit-identical).
void render_row_scalar(const CompiledMap& map, const uint8_t* store, size_t stride_bytes, int row,
                       uint8_t* out) {
  const uint8_t* count = map.count.data() + size_t(row) * map.width;
  size_t k = map.row_start[row];
  for (int col = 0; col < map.width; ++col, out += 3) {
    int32_t acc[3] = {0, 0, 0};
    for (int t = 0; t < count[col]; ++t, ++k) {
      const uint32_t w = map.word[k];
      const int32_t wt = int32_t(map.weight[k]) + 1;
      const int32_t fx = (w >> 22) & 31, fy = w >> 27;
      const uint8_t* a = store + size_t(w & kIndexMask) * 3;
      for (int ch = 0; ch < 3; ++ch) acc[ch] += wt * bilinear_x1024(a, stride_bytes, fx, fy, ch);
    }
    for (int ch = 0; ch < 3; ++ch) out[ch] = static_cast<uint8_t>((acc[ch] + (1 << 17)) >> 18);
  }
}

// sad (eq. 4.17-4.18): per pixel, sample every tap (same fixed-point bilinear as above), gray
// level Y of each sample, SAD_i = sum_j |Y_i - Y_j|, weights prior_i / (SAD_i + eps) normalised.
void render_row_sad(const CompiledMap& map, const uint8_t* store, size_t stride_bytes, int row, uint8_t* out) {
  const uint8_t* count = map.count.data() + size_t(row) * map.width;
  size_t k = map.row_start[row];
  const float eps = map.sad_epsilon;
  for (int col = 0; col < map.width; ++col, out += 3) {
    const int n = count[col];
    float s[8][3], y[8], w[8];
    for (int t = 0; t < n; ++t, ++k) {
      const uint32_t wd = map.word[k];
      const int32_t fx = (wd >> 22) & 31, fy = wd >> 27;
      const uint8_t* a = store + size_t(wd & kIndexMask) * 3;
      for (int ch = 0; ch < 3; ++ch) s[t][ch] = float(bilinear_x1024(a, stride_bytes, fx, fy, ch));
      y[t] = (0.114f * s[t][0] + 0.587f * s[t][1] + 0.299f * s[t][2]) * (1.0f / (1024.0f * 255.0f));
      w[t] = float(map.weight[k] + 1);
    }
    float acc[3] = {0, 0, 0}, sum = 0;
    for (int i = 0; i < n; ++i) {
      float sad = 0;
      for (int j = 0; j < n; ++j) sad += std::fabs(y[i] - y[j]);
      const float wi = n > 1 ? w[i] / (sad + eps) : w[i];
      sum += wi;
      for (int ch = 0; ch < 3; ++ch) acc[ch] += wi * s[i][ch];
    }
    for (int ch = 0; ch < 3; ++ch)
      out[ch] = n ? static_cast<uint8_t>(std::min(255.0f, acc[ch] / (sum * 1024.0f) + 0.5f)) : 0;
  }
}

#ifdef OMMA_X86
// SSSE3 kernel. Per tap: two 8-byte loads (pixels a,b of row y and c,d of row y+1), interleave
// rows, pmaddubsw with (32-fy, fy) -> vertical sums per channel of a/c and b/d, shuffle the a and b
// halves into pairs, pmaddwd with ((32-fx) w, fx w) -> 32-bit channel sums.
__attribute__((target("ssse3,sse4.1"))) void render_row_simd(const CompiledMap& map, const uint8_t* store,
                                                             size_t stride_bytes, int row, uint8_t* out) {
  const uint8_t* count = map.count.data() + size_t(row) * map.width;
  const uint32_t* word = map.word.data();
  const uint8_t* weight = map.weight.data();
  size_t k = map.row_start[row];
  // After unpack+maddubs, 16-bit lanes: [v0 v1 v2 v3 v4 v5 x x] = a0' a1' a2' b0' b1' b2'.
  // Interleave to [a0' b0' a1' b1' a2' b2' 0 0] (bytes).
  const __m128i pair = _mm_setr_epi8(0, 1, 6, 7, 2, 3, 8, 9, 4, 5, 10, 11, -1, -1, -1, -1);
  const __m128i round = _mm_set1_epi32(1 << 17);
  const __m128i pack = _mm_setr_epi8(0, 4, 8, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1);
  const int W = map.width;
  // (32 - fy, fy) byte pairs for pmaddubsw, one register per fy.
  alignas(16) static const auto vy_lut = [] {
    std::array<std::array<uint8_t, 16>, 32> t{};
    for (int fy = 0; fy < 32; ++fy)
      for (int i = 0; i < 16; i += 2) t[fy][i] = uint8_t(32 - fy), t[fy][i + 1] = uint8_t(fy);
    return t;
  }();
  for (int col = 0; col < W; ++col, out += 3) {
    __m128i acc = round;
    const int n = count[col];
    for (int t = 0; t < n; ++t, ++k) {
      const uint32_t w = word[k];
      const int32_t wt = int32_t(weight[k]) + 1;
      const int32_t fx = (w >> 22) & 31, fy = w >> 27;
      const uint8_t* a = store + size_t(w & kIndexMask) * 3;
      const __m128i r0 = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(a));
      const __m128i r1 = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(a + stride_bytes));
      const __m128i il = _mm_unpacklo_epi8(r0, r1);
      const __m128i vy = _mm_load_si128(reinterpret_cast<const __m128i*>(vy_lut[fy].data()));
      const __m128i v = _mm_maddubs_epi16(il, vy);
      const __m128i hp = _mm_shuffle_epi8(v, pair);
      // ((32 - fx) w, fx w) as two int16 in one int32: w * (fx << 16 | (32 - fx)), no carry.
      const __m128i wx = _mm_set1_epi32(wt * ((fx << 16) + 32 - fx));
      acc = _mm_add_epi32(acc, _mm_madd_epi16(hp, wx));
    }
    const __m128i px = _mm_shuffle_epi8(_mm_srli_epi32(acc, 18), pack);
    if (col + 1 < W) {
      const uint32_t v32 = static_cast<uint32_t>(_mm_cvtsi128_si32(px));
      std::memcpy(out, &v32, 4);  // the 4th byte is overwritten by the next pixel
    } else {
      const uint32_t v32 = static_cast<uint32_t>(_mm_cvtsi128_si32(px));
      std::memcpy(out, &v32, 3);
    }
  }
}
#endif

}  // namespace

bool simd_available() {
#ifdef OMMA_X86
  static const bool ok = __builtin_cpu_supports("ssse3") && __builtin_cpu_supports("sse4.1");
  return ok;
#else
  return false;
#endif
}

void render(const CompiledMap& map, const FrameStore& store, cv::Mat& out, const RenderOptions& opt) {
  if (store.layout().stride_px != map.layout.stride_px || store.layout().rows != map.layout.rows)
    throw std::invalid_argument("render: frame store layout does not match the compiled map");
  out.create(map.height, map.width, CV_8UC3);
  const size_t stride_bytes = size_t(map.layout.stride_px) * 3;
  const uint8_t* data = store.data();
  const bool simd = opt.simd && simd_available();
  const bool sad = map.method == pano::Method::kSad;
  auto rows = [&](int r0, int r1) {
    for (int r = r0; r < r1; ++r) {
      uint8_t* o = out.ptr<uint8_t>(r);
      if (sad) {
        render_row_sad(map, data, stride_bytes, r, o);
        continue;
      }
#ifdef OMMA_X86
      if (simd) {
        render_row_simd(map, data, stride_bytes, r, o);
        continue;
      }
#endif
      render_row_scalar(map, data, stride_bytes, r, o);
    }
  };
  if (opt.threads == 1) {
    rows(0, map.height);
    return;
  }
  // Isolated: while waiting, this thread only runs render tasks (not tasks of other code sharing
  // the oneTBB workers, e.g. OpenCV in source threads), so a render never waits behind them.
  auto body = [&] {
    tbb::this_task_arena::isolate([&] {
    tbb::parallel_for(tbb::blocked_range<int>(0, map.height, 8),
                      [&](const tbb::blocked_range<int>& r) { rows(r.begin(), r.end()); });
    });
  };
  if (opt.threads <= 0) {
    body();
  } else {
    static thread_local std::unique_ptr<tbb::task_arena> arena;
    if (!arena || arena->max_concurrency() != opt.threads) arena = std::make_unique<tbb::task_arena>(opt.threads);
    arena->execute(body);
  }
}

cv::Mat reference_render(const Rig& rig, const MapOptions& opt, const std::vector<cv::Mat>& frames) {
  if (frames.size() != rig.cameras.size())
    throw std::invalid_argument("reference_render: need one frame per camera");
  const auto [sub, to_full] = active_cameras(rig, opt.active);
  const PanoGrid& g = opt.grid;
  cv::Mat out(g.height, g.width, CV_8UC3, cv::Scalar::all(0));
  // Bilinear sample with replicated edges; centres at integer + 0.5.
  auto sample = [](const cv::Mat& img, double x, double y, int ch) {
    const double sx = x - 0.5, sy = y - 0.5;
    const int x0 = int(std::floor(sx)), y0 = int(std::floor(sy));
    const double fx = sx - x0, fy = sy - y0;
    auto at = [&](int xi, int yi) {
      xi = std::clamp(xi, 0, img.cols - 1);
      yi = std::clamp(yi, 0, img.rows - 1);
      return double(img.at<cv::Vec3b>(yi, xi)[ch]);
    };
    return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) +
           fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
  };
  tbb::parallel_for(0, g.height, [&](int row) {
    for (int col = 0; col < g.width; ++col) {
      if (sub.cameras.empty()) continue;
      auto taps = pano::static_taps(sub, g, col, row, opt.method, opt.params);
      std::vector<std::array<double, 3>> s(taps.size());
      std::vector<double> gray(taps.size());
      for (size_t i = 0; i < taps.size(); ++i) {
        const cv::Mat& img = frames[to_full[taps[i].camera]];
        for (int ch = 0; ch < 3; ++ch) s[i][ch] = sample(img, taps[i].px.x(), taps[i].px.y(), ch);
        gray[i] = pano::luma(cv::Vec3f(s[i][0], s[i][1], s[i][2])) / 255.0;
      }
      if (opt.method == pano::Method::kSad && !taps.empty()) {  // eq. 4.17-4.18
        const auto w = pano::sad_weights(taps, gray, opt.params.sad_epsilon);
        for (size_t i = 0; i < taps.size(); ++i) taps[i].weight = w[i];
      }
      double v[3] = {0, 0, 0};
      for (size_t i = 0; i < taps.size(); ++i)
        for (int ch = 0; ch < 3; ++ch) v[ch] += taps[i].weight * s[i][ch];
      auto& o = out.at<cv::Vec3b>(row, col);
      for (int ch = 0; ch < 3; ++ch) o[ch] = cv::saturate_cast<uint8_t>(v[ch]);
    }
  });
  return out;
}

double psnr_u8(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type()) throw std::invalid_argument("psnr_u8: size/type mismatch");
  cv::Mat d;
  cv::absdiff(a, b, d);
  d.convertTo(d, CV_64F);
  const double mse = cv::mean(d.mul(d))[0] * d.channels() / d.channels();
  cv::Scalar s = cv::mean(d.mul(d));
  double m = 0;
  for (int c = 0; c < a.channels(); ++c) m += s[c];
  m /= a.channels();
  (void)mse;
  if (m <= 0) return std::numeric_limits<double>::infinity();
  return 10 * std::log10(255.0 * 255.0 / m);
}

}  // namespace omma::engine
