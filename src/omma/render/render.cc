#include "omma/render/render.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "omma/core/valid.h"
#include "omma/pano/stitch.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define OMMA_X86 1
#endif

namespace omma::render {
namespace {

// Where a tile's taps are read from; the kernels advance it.
struct Cursor {
  const int16_t* delta;
  const uint32_t* weight;
  const uint8_t* prior;  // sad only
};

// Each kernel renders, with run<C>(store, base, cursor, n, out, room), a run of n pixels of C taps
// (see compiled_map.h) into out, 3 bytes per pixel, writing nothing beyond out + room bytes (the
// end of the tile's row in the output: the next tile may belong to another thread) and, before
// that, possibly up to 4 bytes past the run (the next run overwrites them).

// Channel ch of the neighbourhood at s (B G R of (x,y), (x,y+1), (x+1,y), (x+1,y+1)) weighted by
// the four weight bytes of w.
inline int32_t weighted_sum(const uint8_t* s, uint32_t w, int ch) {
  return int32_t(w & 255) * s[ch] + int32_t((w >> 8) & 255) * s[3 + ch] +
         int32_t((w >> 16) & 255) * s[6 + ch] + int32_t(w >> 24) * s[9 + ch];
}

// Portable kernel: the definition the SIMD kernels reproduce bit for bit: with weights summing to
// 128 over a pixel's taps, the output is (sum w v + 64) >> 7.
struct ScalarKernel {
  template <int C>
  void run(const uint8_t* store, const uint32_t* base, Cursor& cu, int n, uint8_t* o, int room) const {
    for (int p = 0; p < n; ++p, o += 3) {
      int32_t acc[3] = {64, 64, 64};
      for (int t = 0; t < C; ++t) {
        const uint8_t* s = store + 2 * (int64_t(base[t]) + *cu.delta++);
        const uint32_t w = *cu.weight++;
        for (int ch = 0; ch < 3; ++ch) acc[ch] += weighted_sum(s, w, ch);
      }
      for (int ch = 0; ch < 3; ++ch) o[ch] = static_cast<uint8_t>(acc[ch] >> 7);
    }
  }
};

// sad (eq. 4.17-4.18): per pixel, sample every tap (bilinear weights summing to 128 per tap), gray
// level Y of each sample, SAD_i = sum_j |Y_i - Y_j|, weights prior_i / (SAD_i + eps) normalised.
struct SadKernel {
  float eps;
  template <int C>
  void run(const uint8_t* store, const uint32_t* base, Cursor& cu, int n, uint8_t* o, int room) const {
    for (int p = 0; p < n; ++p, o += 3) {
      float s[C][3], y[C], pw[C];
      for (int t = 0; t < C; ++t) {
        const uint8_t* v = store + 2 * (int64_t(base[t]) + *cu.delta++);
        const uint32_t w = *cu.weight++;
        for (int ch = 0; ch < 3; ++ch) s[t][ch] = float(weighted_sum(v, w, ch));  // the sample times 128
        y[t] = (0.114f * s[t][0] + 0.587f * s[t][1] + 0.299f * s[t][2]) * (1.0f / (128.0f * 255.0f));
        pw[t] = float(*cu.prior++ + 1);
      }
      float acc[3] = {0, 0, 0}, sum = 0;
      for (int i = 0; i < C; ++i) {
        float sad = 0;
        for (int j = 0; j < C; ++j) sad += std::fabs(y[i] - y[j]);
        const float wi = C > 1 ? pw[i] / (sad + eps) : pw[i];
        sum += wi;
        for (int ch = 0; ch < 3; ++ch) acc[ch] += wi * s[i][ch];
      }
      for (int ch = 0; ch < 3; ++ch)
        o[ch] = static_cast<uint8_t>(std::min(255.0f, acc[ch] / (sum * 128.0f) + 0.5f));
    }
  }
};

// Renders tiles t0..t1-1 (in this order) with kernel K into out (row step `step` bytes). While a
// tile renders, the store lines of the next one are prefetched, a slice per row (`pf`). Measured
// with a prototype of this kernel
// (prototype rig, mrf 1080x1080, one thread, best of 15): 4.5 ms rendering row by row without
// prefetch, 3.0 ms by tiles prefetching each tile's lines at its start, 2.0 ms with the prefetch
// spread over the tile before, 1.7 ms with every camera pixel in the L1 cache.
template <class K>
inline void render_tiles(const K& kernel, const CompiledMap& map, const uint8_t* store, int t0, int t1,
                         uint8_t* out, size_t step, bool pf) {
  const uint32_t* lines = map.lines.data();
  if (pf)
    for (uint32_t a = map.tile_line[t0]; a < map.tile_line[t0 + 1]; ++a)
      __builtin_prefetch(store + lines[a], 0, 3);
  const int tiles_x = map.tiles_x();
  for (int t = t0; t < t1; ++t) {
    const uint32_t pa = pf && t + 1 < t1 ? map.tile_line[t + 1] : 0,
                   pb = pf && t + 1 < t1 ? map.tile_line[t + 2] : 0;
    const int c0 = (t % tiles_x) * kTileW, r0 = (t / tiles_x) * kTileH;
    const int w = std::min(map.width, c0 + kTileW) - c0, h = std::min(map.height, r0 + kTileH) - r0;
    const uint8_t* run = map.runs.data() + map.tile_run[t];
    const uint32_t* base = map.base.data() + map.tile_base[t];
    Cursor cu{map.delta.data() + map.tile_tap[t], map.weight.data() + map.tile_tap[t],
              map.prior.empty() ? nullptr : map.prior.data() + map.tile_tap[t]};
    for (int r = 0; r < h; ++r, run += 2) {
      for (uint32_t a = pa + (pb - pa) * r / h; a < pa + (pb - pa) * (r + 1) / h; ++a)
        __builtin_prefetch(store + lines[a], 0, 3);
      uint8_t* o = out + size_t(r0 + r) * step + 3 * size_t(c0);
      int room = 3 * w;
      for (; run[1] != 0; run += 2) {
        const int n = run[1], c = run[0];
        switch (c) {
          case 0:
            std::memset(o, 0, 3 * size_t(n));
            break;
          case 1:
            kernel.template run<1>(store, base, cu, n, o, room);
            break;
          case 2:
            kernel.template run<2>(store, base, cu, n, o, room);
            break;
          case 3:
            kernel.template run<3>(store, base, cu, n, o, room);
            break;
          case 4:
            kernel.template run<4>(store, base, cu, n, o, room);
            break;
          case 5:
            kernel.template run<5>(store, base, cu, n, o, room);
            break;
          case 6:
            kernel.template run<6>(store, base, cu, n, o, room);
            break;
          case 7:
            kernel.template run<7>(store, base, cu, n, o, room);
            break;
          default:
            kernel.template run<8>(store, base, cu, n, o, room);
            break;
        }
        base += c;
        o += 3 * n;
        room -= 3 * n;
      }
    }
  }
}

void render_tiles_scalar(const CompiledMap& map, const uint8_t* store, int t0, int t1, uint8_t* out,
                         size_t step, bool pf) {
  render_tiles(ScalarKernel{}, map, store, t0, t1, out, step, pf);
}
void render_tiles_sad(const CompiledMap& map, const uint8_t* store, int t0, int t1, uint8_t* out, size_t step,
                      bool pf) {
  render_tiles(SadKernel{map.sad_epsilon}, map, store, t0, t1, out, step, pf);
}

#ifdef OMMA_X86
#pragma GCC push_options
#pragma GCC target("ssse3,sse4.1")
// The next tap's neighbourhood (advances d): the 16 bytes at its offset are B G R of (x,y),
// (x,y+1), (x+1,y), (x+1,y+1), then 4 bytes of the next pixel; regrouped per channel into the
// dword lanes B, G, R of the four neighbours and zero, matching the weight bytes (w(x,y), w(x,y+1),
// w(x+1,y), w(x+1,y+1)).
inline __m128i neighbours(const uint8_t* p, const int16_t*& d) {
  const __m128i regroup = _mm_setr_epi8(0, 3, 6, 9, 1, 4, 7, 10, 2, 5, 8, 11, -1, -1, -1, -1);
  return _mm_shuffle_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p + 2 * ptrdiff_t(*d++))),
                          regroup);
}

// The SIMD kernels' run loop, around K::pixel<C>(start pointers, deltas, weights): one output
// pixel as the dwords B, G, R, 0 (each 0..255). Four pixels are packed into one 16-byte store.
template <class K>
struct SimdRun {
  template <int C>
  void run(const uint8_t* store, const uint32_t* base, Cursor& cu, int n, uint8_t* o, int room) const {
    const __m128i squeeze = _mm_setr_epi8(0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, -1, -1, -1, -1);
    const __m128i pick = _mm_setr_epi8(0, 4, 8, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1);
    const uint8_t* p[C];  // the run's start neighbourhoods
    for (int t = 0; t < C; ++t) p[t] = store + 2 * size_t(base[t]);
    int i = 0;
    for (; i + 4 <= n && room >= 16; i += 4, o += 12, room -= 12) {
      const __m128i a0 = K::template pixel<C>(p, cu.delta, cu.weight),
                    a1 = K::template pixel<C>(p, cu.delta, cu.weight);
      const __m128i a2 = K::template pixel<C>(p, cu.delta, cu.weight),
                    a3 = K::template pixel<C>(p, cu.delta, cu.weight);
      const __m128i bytes =
          _mm_packus_epi16(_mm_packus_epi32(a0, a1), _mm_packus_epi32(a2, a3));  // B G R 0 x 4
      _mm_storeu_si128(reinterpret_cast<__m128i*>(o), _mm_shuffle_epi8(bytes, squeeze));
    }
    for (; i < n; ++i, o += 3, room -= 3) {
      const uint32_t v =
          uint32_t(_mm_cvtsi128_si32(_mm_shuffle_epi8(K::template pixel<C>(p, cu.delta, cu.weight), pick)));
      std::memcpy(o, &v, room >= 4 ? 4 : 3);
    }
  }
};
#pragma GCC pop_options

#pragma GCC push_options
#pragma GCC target("avx2,fma,bmi,bmi2")
// AVX2: pmaddubsw multiplies the neighbours (unsigned) with the weight bytes (signed, 0..127) in
// pairs, (w00 v00 + w01 v01, w10 v10 + w11 v11) per channel as 16-bit sums, added up in 16 bits:
// exact, since the weights of a pixel sum to 128, so every partial sum is at most 128 * 255.
// pmaddwd adds the pairs at the end of the pixel.
struct Avx2Kernel {
  template <int C>
  static __m128i pixel(const uint8_t* const* p, const int16_t*& d, const uint32_t*& w) {
    __m128i acc = _mm_setzero_si128();
#pragma GCC unroll 8
    for (int t = 0; t < C; ++t)
      acc = _mm_add_epi16(acc, _mm_maddubs_epi16(neighbours(p[t], d), _mm_set1_epi32(int(*w++))));
    return _mm_srli_epi32(_mm_add_epi32(_mm_madd_epi16(acc, _mm_set1_epi16(1)), _mm_set1_epi32(64)), 7);
  }
};
__attribute__((flatten)) void render_tiles_avx2(const CompiledMap& map, const uint8_t* store, int t0, int t1,
                                                uint8_t* out, size_t step, bool pf) {
  render_tiles(SimdRun<Avx2Kernel>{}, map, store, t0, t1, out, step, pf);
}
#pragma GCC pop_options

#pragma GCC push_options
#pragma GCC target("avx512f,avx512vl,avx512bw,avx512vnni,avx2,fma,bmi,bmi2")
// AVX-512 VNNI: vpdpbusd multiplies the four neighbours of one channel (unsigned) with the four
// weight bytes (signed, 0..127, broadcast from memory) and adds them to that channel's 32-bit sum:
// four instructions per tap in the compiled loop (offset delta load, 16-byte load addressed from
// the run's start pointer, pshufb, vpdpbusd).
struct VnniKernel {
  template <int C>
  static __m128i pixel(const uint8_t* const* p, const int16_t*& d, const uint32_t*& w) {
    __m128i acc = _mm_setr_epi32(64, 64, 64, 0);
#pragma GCC unroll 8
    for (int t = 0; t < C; ++t) {
      const __m128i v = neighbours(p[t], d);
      // acc += the four products per channel, the weights broadcast from memory ({1to4}; GCC 12
      // does not fold _mm_set1_epi32 into the instruction by itself)
      asm("vpdpbusd %2%{1to4%}, %1, %0" : "+v"(acc) : "v"(v), "m"(*w));
      ++w;
    }
    return _mm_srli_epi32(acc, 7);
  }
};
__attribute__((flatten)) void render_tiles_vnni(const CompiledMap& map, const uint8_t* store, int t0, int t1,
                                                uint8_t* out, size_t step, bool pf) {
  render_tiles(SimdRun<VnniKernel>{}, map, store, t0, t1, out, step, pf);
}
#pragma GCC pop_options
#endif

using TileRenderer = void (*)(const CompiledMap&, const uint8_t*, int, int, uint8_t*, size_t, bool);

TileRenderer tile_renderer(Kernel k) {
  switch (k) {
#ifdef OMMA_X86
    case Kernel::kAvx512Vnni:
      return render_tiles_vnni;
    case Kernel::kAvx2:
      return render_tiles_avx2;
#endif
    default:
      return render_tiles_scalar;
  }
}

}  // namespace

std::string to_string(Kernel k) {
  switch (k) {
    case Kernel::kAuto:
      return "auto";
    case Kernel::kScalar:
      return "scalar";
    case Kernel::kAvx2:
      return "avx2";
    case Kernel::kAvx512Vnni:
      return "avx512-vnni";
  }
  return "?";
}

bool kernel_available(Kernel k) {
#ifdef OMMA_X86
  static const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("bmi2");
  static const bool vnni = avx2 && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
                           __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512vnni");
#else
  constexpr bool avx2 = false, vnni = false;
#endif
  switch (k) {
    case Kernel::kAuto:
    case Kernel::kScalar:
      return true;
    case Kernel::kAvx2:
      return avx2;
    case Kernel::kAvx512Vnni:
      return vnni;
  }
  return false;
}

Kernel best_kernel() {
  if (kernel_available(Kernel::kAvx512Vnni)) return Kernel::kAvx512Vnni;
  if (kernel_available(Kernel::kAvx2)) return Kernel::kAvx2;
  return Kernel::kScalar;
}

bool RenderOptions::IsValid(std::string* why) const {
  if (threads < 0 || threads > kMaxRenderThreads)
    return invalid(why, fmt::format("threads must be 0 (all) .. {}, got {}", kMaxRenderThreads, threads));
  if (kernel != Kernel::kAuto && kernel != Kernel::kScalar && kernel != Kernel::kAvx2 &&
      kernel != Kernel::kAvx512Vnni)
    return invalid(why, "unknown render kernel");
  return true;
}

void render(const CompiledMap& map, const FrameStore& store, cv::Mat& out, const RenderOptions& opt) {
  if (std::string why; !opt.IsValid(&why)) throw std::invalid_argument("render: " + why);
  if (store.layout().stride_px != map.layout.stride_px || store.layout().rows != map.layout.rows)
    throw std::invalid_argument("render: frame store layout does not match the compiled map");
  out.create(map.height, map.width, CV_8UC3);
  Kernel k = opt.kernel;
  if (k == Kernel::kAuto || !kernel_available(k)) k = best_kernel();
  const TileRenderer tiles = map.method == pano::Method::kSad ? render_tiles_sad : tile_renderer(k);
  const uint8_t* data = store.data();
  uint8_t* o = out.data;
  const size_t step = out.step[0];
  const int n = map.tiles();
  if (opt.threads == 1) {
    tiles(map, data, 0, n, o, step, opt.prefetch);
    return;
  }
  // Ranges of at least 8 consecutive tiles per task (the prefetch runs one tile ahead inside a
  // range). Isolated: while waiting, this thread only runs render tasks (not tasks of other code
  // sharing the oneTBB workers, e.g. OpenCV in source threads), so a render never waits behind them.
  auto body = [&] {
    tbb::this_task_arena::isolate([&] {
      tbb::parallel_for(tbb::blocked_range<int>(0, n, 8), [&](const tbb::blocked_range<int>& r) {
        tiles(map, data, r.begin(), r.end(), o, step, opt.prefetch);
      });
    });
  };
  if (opt.threads <= 0) {
    body();
  } else {
    static thread_local std::unique_ptr<tbb::task_arena> arena;
    if (!arena || arena->max_concurrency() != opt.threads)
      arena = std::make_unique<tbb::task_arena>(opt.threads);
    arena->execute(body);
  }
}

cv::Mat reference_render(const Rig& rig, const MapOptions& opt, const std::vector<cv::Mat>& frames) {
  if (frames.size() != rig.cameras.size())
    throw std::invalid_argument("reference_render: need one frame per camera");
  const auto [sub, to_full] = active_cameras(rig, opt.active);
  const PanoGrid& g = opt.grid;
  const cv::Rect win =
      opt.window.empty() ? cv::Rect(0, 0, g.width, g.height) : opt.window;  // MapOptions::window
  cv::Mat out(win.height, win.width, CV_8UC3, cv::Scalar::all(0));
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
  tbb::parallel_for(0, win.height, [&](int row) {
    for (int col = 0; col < win.width; ++col) {
      if (sub.cameras.empty()) continue;
      auto taps = pano::static_taps(sub, g, col + win.x, row + win.y, opt.method, opt.params);
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
  if (a.size() != b.size() || a.type() != b.type())
    throw std::invalid_argument("psnr_u8: size/type mismatch");
  cv::Mat d;
  cv::absdiff(a, b, d);
  d.convertTo(d, CV_64F);
  cv::Scalar s = cv::mean(d.mul(d));
  double m = 0;
  for (int c = 0; c < a.channels(); ++c) m += s[c];
  m /= a.channels();
  if (m <= 0) return std::numeric_limits<double>::infinity();
  return 10 * std::log10(255.0 * 255.0 / m);
}

}  // namespace omma::render
