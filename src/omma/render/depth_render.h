// The depth-adaptive renderer of the engine: per frame, the depth of the scene on
// a coarse grid of the output (pano::DepthSweep, the same estimator as `omma stitch --depth
// estimate`, with a temporal term against the previous frame's depth), then every output pixel
// rendered with its taps moved to where each camera sees the surface point at that depth.
//
// Map. Compiled once per rig + grid + method (like compiled_map.h, beside it): for every output
// pixel the contributors and static weights of the method on the sphere of radius reference_mm
// (pano::for_each_pixel_weights), plus, as fallbacks, the cameras that see the direction only at
// infinity (used only where every one of the method's taps leaves its image or cone at the pixel's
// depth). Taps lighter than min_weight are dropped as in MapOptions. Per tap the map holds the
// direction w in the camera's frame as the pixel's numerators at infinity p_u = cu w.t + fu w.u,
// p_v = cv w.t + fv w.v, and w.t, w.b (b = q - c_i); per camera the same numerators P_u, P_v of b, so
// that moving the tap to inverse depth s is (contributors.h, eq. 5.21-5.22 folded in):
//     z = w.t + s b.t,  pixel = ((p_u + s P_u) / z, (p_v + s P_v) / z)
//     cone (eq. 2.3): z^2 >= cos^2(aov/2) (1 + 2 s w.b + s^2 |b|^2)
// with the lens (eq. 5.23-5.26) applied in between for cameras with distortion; then a bilinear
// sample (fractions in 1/128) from the frame store (compiled_map.h's row pairs: one 12-byte neighbourhood).
// A tap whose moved position leaves its camera's image or cone is dropped and the remaining
// weights renormalised. Per pixel, s is the coarse inverse depth interpolated bilinearly.
// Kernel: tile by tile (compiled_map.h's kTileW x kTileH); inside a tile the taps are grouped by camera
// (structure of arrays) so that AVX2 moves 8 taps of one camera at a time with its constants broadcast,
// then the neighbourhoods are summed with the store prefetched a few taps ahead; a portable scalar
// kernel elsewhere (DepthRenderOptions::simd). Both sum the same integer bilinear terms.
//
// Static mrf reweighting by depth is not redone per frame: the weights are those at reference_mm
// (the reference stitcher recomputes the contributors at every pixel's own depth); measured against
// `omma stitch --depth estimate` in depth_render_test.cc and docs/results/depth_table.md.
#pragma once

#include <memory>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/pano/plane_sweep.h"
#include "omma/render/compiled_map.h"

namespace omma::render {

// The sweep the engine runs every frame: the reference's (pano::PlaneSweepOptions defaults) on a coarser
// grid (2 deg) with fewer candidates (16) and paths (4), a 3x3 patch, and the temporal term. Measured
// on the colon (4 seeds, against the truth; docs/results/depth_table.md, "Engine"): 16 candidates and
// the 3x3 patch +0.03 dB over 32 candidates and 5x5 at 40 % of the estimate's time; 12 candidates
// -0.2 dB, a 2.5 deg grid -0.2 dB, 3 deg -0.4 dB.
pano::PlaneSweepOptions engine_sweep_options();
// The engine's MapOptions::min_weight for the depth-adaptive map: taps lighter than 0.15 of a pixel
// dropped (1.60 -> 1.33 taps per pixel at vr180 1080x1080 on thesis-24). Measured on the colon (4
// seeds, vr180 270x270 against the truth): +0.06 dB over 0.05, the render about 20 % faster.
inline constexpr double kEngineDepthMinWeight = 0.15;

struct DepthRenderOptions {
  // grid, method (not sad), params (observer q), min_weight, and window: a band map (MapOptions::window)
  // covers only that window of the grid, its pixel (c, r) being grid pixel (window.x + c, window.y + r),
  // with the whole grid's taps (mrf neighbours outside the window included); empty = the whole grid.
  MapOptions map;
  pano::PlaneSweepOptions sweep =
      engine_sweep_options();  // the per-frame estimate (its temporal_weight is used between frames)
  double reference_mm = 22;    // the surface the static weights are computed on (the colon wall)
  // Temporal filter of the inverse depth between panoramas: s = s_prev + alpha (s_new - s_prev)
  // (1 = none). With sweep.temporal_weight it keeps the wall's depth from flickering with the noise.
  double temporal_alpha = 0.35;
  int threads = 0;  // 0 = all
  // false: no pano::DepthSweep is built (its memory and compile time saved); render() then needs a
  // fixed_inverse every call and sweep() throws std::logic_error.
  bool estimate = true;
  // false: the portable scalar tile kernel even where the CPU has AVX2 (the same pixels up to the order
  // of the float sums; for tests).
  bool simd = true;
  bool IsValid(std::string* why = nullptr) const;
};

struct DepthFrameStats {
  double estimate_ms = 0, render_ms = 0;
  double mean_depth_mm = 0;  // harmonic mean over the coarse grid
  double mean_confidence = 0;
  pano::DepthEstimate::Timing sweep;  // the estimate's phases (zero with a fixed depth)
};

class DepthRenderer {
 public:
  // Compiles the map and the sweep's geometry (seconds). Throws std::invalid_argument on invalid
  // options.
  DepthRenderer(const Rig& rig, const DepthRenderOptions& opt);
  ~DepthRenderer();

  // One panorama: estimates the depth from `frames` (one per camera, BGR 8-bit, rig order: the same
  // frames as in `store`) unless `fixed_inverse` is given, then renders from `store` into `out`
  // (CV_8UC3, the window's size: map.window, or the grid). fixed_inverse: CV_32FC1 inverse depth (1/mm,
  // 0 = infinity) on a coarse grid of the WHOLE panorama grid, W' x H' with grid.width / W' =
  // grid.height / H' = an integer factor f, its pixel (c, r) looking at the centre of the output's f x f
  // block (as DepthSweep's coarse grid); it is interpolated bilinearly onto every output pixel (grid x
  // at coarse (x + 0.5) / f - 0.5, clamped; cv::resize's INTER_LINEAR); the renderer keeps a reference to
  // it (not a copy) until the next call. `frames` is not read then (may
  // be empty). Throws std::invalid_argument on a wrong fixed_inverse, or none with estimate = false.
  DepthFrameStats render(const FrameStore& store, const std::vector<cv::Mat>& frames, cv::Mat& out,
                         const cv::Mat& fixed_inverse = {});

  // The last estimate (coarse grid; the fixed inverse depth when one was given): inverse depth (1/mm)
  // and confidence; and the depth interpolated onto the output (window-sized, mm, +inf where s = 0).
  const cv::Mat& coarse_inverse() const;
  const cv::Mat& coarse_confidence() const;
  cv::Mat depth() const;
  // Forget the previous frame's depth (the temporal term starts afresh).
  void reset();

  const StoreLayout& layout() const;
  const pano::DepthSweep& sweep() const;  // throws std::logic_error with estimate = false
  bool estimates() const;                 // whether a sweep was built (options.estimate)
  size_t taps() const;
  double bytes_per_pixel() const;
  double compile_seconds() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace omma::render
