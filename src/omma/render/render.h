// The fast CPU renderer of compiled maps (thesis §5.4: the FPGA's per-pixel tap pipeline, here as
// SIMD kernels over output tiles split among oneTBB threads; sad has its own kernel with per-frame
// weights), and the plain reference it must match. Kernels, chosen at run time: AVX-512 VNNI,
// AVX2, portable scalar; all give bit-identical results (integer arithmetic, one final rounding).
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/render/compiled_map.h"

namespace omma::render {

enum class Kernel {
  kAuto,        // the fastest this CPU runs
  kScalar,      // portable C++
  kAvx2,        // AVX2: per tap one 16-byte load, pshufb, pmaddubsw
  kAvx512Vnni,  // AVX-512 VNNI (+VL, BW): per tap one 16-byte load, pshufb, vpdpbusd
};
std::string to_string(Kernel k);
bool kernel_available(Kernel k);
Kernel best_kernel();  // what kAuto runs here

// The most renderer threads one may ask for (RenderOptions::threads): one oneTBB arena of that many.
inline constexpr int kMaxRenderThreads = 1024;

struct RenderOptions {
  int threads =
      0;  // 0 = all hardware threads (oneTBB default), 1 = the calling thread only; <= kMaxRenderThreads
  Kernel kernel = Kernel::kAuto;  // one that the CPU lacks falls back to the best available
  bool prefetch = true;           // false: no prefetch of the next tile's camera pixels (diagnostic)
  bool IsValid(std::string* why = nullptr) const;  // threads >= 0, a known kernel
};

// Renders `map` from the frames in `store` into `out` (resized to CV_8UC3 height x width).
// The store's layout must be the map's layout.
void render(const CompiledMap& map, const FrameStore& store, cv::Mat& out, const RenderOptions& opt = {});

// Reference: for every output pixel, pano::static_taps evaluated in double precision with
// bilinear sampling (edges replicated, centres at integer + 0.5) of the 8-bit frames; no
// quantisation except the final rounding. `frames` are CV_8UC3, in rig order; `active` as in
// MapOptions. This is the readable definition of what render() computes.
cv::Mat reference_render(const Rig& rig, const MapOptions& opt, const std::vector<cv::Mat>& frames);

// PSNR in dB between two 8-bit images of equal size (inf if identical).
double psnr_u8(const cv::Mat& a, const cv::Mat& b);

}  // namespace omma::render
