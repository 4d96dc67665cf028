// Figures for depth maps: depth error against a true depth, occlusion boundaries
// (depth discontinuities) and the precision / recall / F1 of a boundary map against them.
// Depth maps: CV_32FC1 mm (surface.h).
#pragma once

#include <opencv2/core.hpp>

namespace omma::pano {

// depth with every value above max_mm (and +infinity) replaced by max_mm: the true depth of a scene
// whose far parts are out of range (the colon's lumen) as a stitching surface.
cv::Mat clamp_depth(const cv::Mat& depth, double max_mm);

struct DepthError {
  double median_rel = 0;  // median of |D_est - D_true| / D_true
  double mean_rel = 0;
  double within_10 = 0;  // fraction with relative error < 10 %
  long pixels = 0;       // pixels compared: D_true finite and <= max_mm (and mask, if given)
};
// Compares where the true depth is finite and at most max_mm (and mask != 0 if a mask is given).
DepthError depth_error(const cv::Mat& estimate, const cv::Mat& truth, double max_mm,
                       const cv::Mat& mask = {});

// Relative depth jump at every pixel: max over its 4-neighbours farther than itself of
// (D_neighbour / D - 1) (the jump is marked on the nearer, occluding side), CV_32FC1, capped at 10;
// 10 next to +infinity. A boundary map "from depth" for best_boundary_score.
cv::Mat depth_jump_map(const cv::Mat& depth);
// Occlusion boundaries: CV_8UC1, 255 where the depth jumps to a 4-neighbour by more than the
// factor `ratio` (depth_jump_map > ratio - 1; +infinity next to a finite depth counts as a jump).
cv::Mat depth_discontinuities(const cv::Mat& depth, double ratio = 1.15);

struct BoundaryScore {
  double precision = 0, recall = 0, f1 = 0;
  long predicted = 0, truth = 0;  // pixels in each map (inside the mask)
};
// Boundary pixels of `predicted` (CV_8UC1, non-zero = boundary) within tolerance_px (chessboard) of
// a true boundary pixel are correct (precision); true boundary pixels within tolerance_px of a
// predicted one are found (recall); F1 their harmonic mean. Only pixels where mask != 0 count.
BoundaryScore boundary_score(const cv::Mat& predicted, const cv::Mat& truth, int tolerance_px,
                             const cv::Mat& mask = {});

// The best of boundary_score over the thresholds th = 0.005, 0.01, ... 0.5 of a boundary map L_ob
// (CV_32FC1, eq. 4.15) thresholded by eq. 4.16 (the "optimal dataset scale" of boundary
// benchmarks: each map at its own best threshold); *threshold gets the threshold.
BoundaryScore best_boundary_score(const cv::Mat& boundary, const cv::Mat& truth, int tolerance_px,
                                  double* threshold = nullptr, const cv::Mat& mask = {});

}  // namespace omma::pano
