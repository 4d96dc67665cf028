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
// grid with fewer candidates and paths, and the temporal term (measured in depth_render_test.cc and
// docs/results/depth_table.md: speed per frame and PSNR against `omma stitch --depth estimate`).
pano::PlaneSweepOptions engine_sweep_options();

struct DepthRenderOptions {
  MapOptions map;  // grid, method (not sad), params (observer q), min_weight
  pano::PlaneSweepOptions sweep =
      engine_sweep_options();  // the per-frame estimate (its temporal_weight is used between frames)
  double reference_mm = 22;    // the surface the static weights are computed on (the colon wall)
  // Temporal filter of the inverse depth between panoramas: s = s_prev + alpha (s_new - s_prev)
  // (1 = none). With sweep.temporal_weight it keeps the wall's depth from flickering with the noise.
  double temporal_alpha = 0.35;
  int threads = 0;  // 0 = all
  bool IsValid(std::string* why = nullptr) const;
};

struct DepthFrameStats {
  double estimate_ms = 0, render_ms = 0;
  double mean_depth_mm = 0;  // harmonic mean over the coarse grid
  double mean_confidence = 0;
};

class DepthRenderer {
 public:
  // Compiles the map and the sweep's geometry (seconds). Throws std::invalid_argument on invalid
  // options.
  DepthRenderer(const Rig& rig, const DepthRenderOptions& opt);
  ~DepthRenderer();

  // One panorama: estimates the depth from `frames` (one per camera, BGR 8-bit, rig order: the same
  // frames as in `store`) unless `fixed_inverse` is given (coarse grid, 1/mm), then renders from
  // `store` into `out` (CV_8UC3, grid-sized).
  DepthFrameStats render(const FrameStore& store, const std::vector<cv::Mat>& frames, cv::Mat& out,
                         const cv::Mat& fixed_inverse = {});

  // The last estimate (coarse grid): inverse depth (1/mm) and confidence; and the depth upsampled to
  // the output grid (mm).
  const cv::Mat& coarse_inverse() const;
  const cv::Mat& coarse_confidence() const;
  cv::Mat depth() const;
  // Forget the previous frame's depth (the temporal term starts afresh).
  void reset();

  const StoreLayout& layout() const;
  const pano::DepthSweep& sweep() const;
  size_t taps() const;
  double bytes_per_pixel() const;
  double compile_seconds() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace omma::render
