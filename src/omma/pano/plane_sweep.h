// Depth of every panorama direction from the cameras' overlaps: a sweep of
// spheres around the observer q (the "plane sweep" of multi-view stereo with spheres as planes,
// since the panorama is a set of directions from q), a patch cost robust to noise, colour gain
// and vignetting, semi-global aggregation over the panorama grid with edge-aware penalties, a
// confidence, and a smooth fallback to a prior distance where nothing can be measured. The
// measurements behind the defaults: docs/results/tuning-depth-sweep.md.
//
// Grid. The sweep runs on a coarse grid of the output's projection, `factor` times smaller in each
// axis: by default the factor that gives a pitch of about pitch_deg, so that the estimate does not
// depend on the output size. It is the same projection at a lower resolution, so its pixel (c, r)
// looks at the centre of the output's f x f block there. A (2 median + 1)^2 median filter of the
// winners removes isolated wrong minima. The depth is upsampled to the output grid at the end
// (bilinear in inverse depth).
//
// Candidates. D_k, k = 0 .. steps-1, uniform in inverse depth s = 1/D between 1/near and 1/far
// (the parallax of a camera at baseline b is b * s, so equal steps in s are equal steps in pixels).
//
// Cost (per coarse pixel u and candidate k). Every camera i that sees the surface point
// X = q + D_k w_u (contributors.h) is sampled there, as the band-pass of the gray level Y (BT.601
// luma of the frame's values in [0,1]): Y blurred to the coarse grid's pitch (Gaussian, sigma = half
// a coarse pixel in camera pixels) minus that blurred again with band_ratio times the sigma, into the
// layer L_ik. The band-pass removes what ZNCC's per-patch gain and offset cannot: the vignetting's
// ramp across a patch near the image edge, which two cameras share and which otherwise "matches" at
// whatever candidate puts both patches at their image edges. The band-pass holds less variance than
// the plain gray levels, so the texture weight's sigma_n (noise_sigma) is smaller than theirs would
// be. For every pair of cameras (i, j) that both see u at D_k, over the (2 window + 1)^2 patch of
// coarse pixels P around u where both see the surface:
//     ZNCC_ij = cov(L_i, L_j) / sqrt(var L_i var L_j)   (zero-mean normalised cross-correlation:
//               invariant to a gain and an offset per camera and patch, i.e. to the colour gains
//               and the slowly varying vignetting)
//     w_ij    = (n/|P|)^2 * v / (v + sigma_n^2),  v = min(var L_i, var L_j)  (texture weight: a flat
//               patch gives no evidence; n = pixels of P both cameras see, squared so that the
//               slivers where an overlap begins count little)
//     C(u, k) = (sum_ij w_ij (1 - ZNCC_ij) + w_0 * neutral) / (sum_ij w_ij + w_0)
// in [0, 2]. A candidate without evidence (sum_ij w_ij < 0.05: no two cameras see the point there)
// is "unknown", not "bad": overlaps shrink as the surface comes nearer (at the colon wall's 20 mm much
// of the panorama is seen by one camera only), and at infinity a far-field scene's footprints part at
// the edge of the coverage. It takes the cost of the nearest candidate (in k) with evidence, at most
// the pixel's best cost + unknown_cost (and at most neutral): the cost curve is continued flat, so
// that the smoothness term, not where the overlap happens to begin or end, decides (a constant
// cost for unknown candidates pulls the estimate to where overlaps begin or end).
// The SAD of eq. 4.17 is the special case of one candidate (D = infinity), a 1-pixel patch and
// absolute differences instead of ZNCC.
//
// Aggregation (semi-global matching, Hirschmueller 2008) along `paths` (4 or 8) directions r of
// the coarse grid:
//     L_r(u, k) = C(u, k) + min(L_r(u-r, k), L_r(u-r, k+-1) + P1, min_j L_r(u-r, j) + P2(u))
//                 - min_j L_r(u-r, j),       P2(u) = max(P1, P2 / (1 + |G(u) - G(u-r)| / edge_gray))
// with G the mean gray level of the cameras at the middle candidate (edge-aware: depth may jump
// where the image has an edge). S(u, k) = sum_r L_r(u, k); k* = argmin S, refined by a parabola
// through S(k*-1), S(k*), S(k*+1) to a fractional k.
//
// Confidence in [0, 1]: c = (1 - exp(-margin / (paths * margin_scale))) * E / (E + w_0), margin =
// the lowest S at least two candidates from k* minus S(k*), E = the mean evidence sum_ij w_ij of u.
// Fallback: s_fill = (G_sigma * (c s) + lambda s_prior) / (G_sigma * c + lambda) (normalised
// convolution, sigma = fill_sigma coarse pixels) and the result s = c s* + (1 - c) s_fill, so
// untextured or single-camera directions take the depth of confident neighbours, and far from any
// the prior distance (prior_mm, or the median of the confident estimates).
//
// Camera grid (grid_camera >= 0): instead of a projection's grid the sweep runs on one rig camera's
// own pixel grid, `factor` times smaller (factor 1: the camera's pixels; factor 0: the factor that
// makes the pitch closest to pitch_deg, the camera's pitch being atan(1 / max(fu, fv)) at its centre).
// Coarse pixel (c, r) looks along the camera's ray through its pixel (factor (c + 0.5), factor
// (r + 0.5)) (CameraModel::unproject), the output grid is the camera's image (the `grid` passed in
// must have its size; its projection is not used) and the guide G of the edge-aware P2 is that
// camera's own gray level (the other cameras' at the middle candidate would double its edges). With
// q at that camera's centre, a sphere |X - q| = D is the depth D along the camera's ray: for a
// rectified pair (rectified_pair_rig below) the disparity is d = f B / (D (w.t)) (eq. 2.4 of both
// cameras on X), so candidates uniform in 1/D are uniform in disparity along every ray, and a
// 180-degree projection at the camera's pitch (most of it outside the camera's field) is not needed.
//
// Temporal (the engine): a previous inverse-depth map (coarse grid) adds
// temporal_weight * min(|s_k - s_prev(u)| / (s_0 - s_{K-1}) * (K - 1), 1) to C, which keeps the
// depth of static wall from flickering with the sensor noise.
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/core/grid.h"
#include "omma/core/rig.h"
#include "omma/pano/contributors.h"

namespace omma::pano {

inline constexpr int kMaxSteps = 256;
inline constexpr double kMaxSweepMm = 1e9;  // finite NEAR and FAR at most 1000 km (beyond: use inf)  //
                                            // candidates per sweep at most (PlaneSweepOptions::steps)

struct PlaneSweepOptions {
  double near_mm = 8;  // nearest candidate distance from q, mm (must lie outside the dome)
  // Farthest candidate, mm; +infinity (the default) makes the last candidate the scene at infinity.
  // A 5 mm dome still sees 2 pixels of parallax at 300 mm: far-field scenes need infinity.
  double far_mm = std::numeric_limits<double>::infinity();
  int steps = 96;  // number of candidates (uniform in 1/D), 2 .. kMaxSteps
  // Coarse grid = output / factor; 0: the factor that makes its pitch closest to pitch_deg.
  int factor = 0;
  double pitch_deg = 1.33;     // about 5 pixels of the prototype's cameras (0.26 deg/pixel)
  int window = 2;              // patch radius, coarse pixels (patch 5x5)
  double band_ratio = 2;       // band-pass of the matched gray levels (see "Cost"); 0 = none
  double noise_sigma = 0.005;  // sigma_n: gray-level noise of the band-pass for the texture weight
  double w0 = 0.2;             // evidence of the neutral cost
  double unknown_cost = 0.25;  // cap of an unknown candidate's cost above the pixel's best (see above)
  double neutral_cost = 0.5;   // cost where no pair of cameras gives evidence (see "Cost" above)
  double p1 = 0.2, p2 = 2.0;   // SGM penalties, cost units
  double edge_gray = 0.03;     // edge-aware P2 scale, gray levels
  int paths = 8;               // 4 or 8
  int median = 2;              // median filter radius on the winners (coarse pixels; 0 = none)
  double margin_scale = 0.05;  // confidence scale of the cost margin per path
  double fill_sigma = 8;       // fallback smoothing, coarse pixels
  double fill_lambda = 1e-3;   // weight of the prior in the fallback
  double prior_mm = 0;         // prior distance; 0 = median of the confident estimates
  double temporal_weight = 0;  // with a previous estimate (engine), see the file comment
  SearchOptions search;        // the observer q
  // -1: the sweep runs on the output projection's coarse grid (above). >= 0: on the pixel grid of
  // rig camera grid_camera (index into rig.cameras; see "Camera grid" above).
  int grid_camera = -1;
  bool IsValid(std::string* why = nullptr) const;
};

struct DepthEstimate {
  cv::Mat depth;              // CV_32FC1, output grid, mm from q
  cv::Mat confidence;         // CV_32FC1, output grid, [0, 1]
  cv::Mat coarse_inverse;     // CV_32FC1, coarse grid, 1/mm (final, after the fallback)
  cv::Mat coarse_confidence;  // CV_32FC1, coarse grid
  double prior_mm = 0;        // the prior distance used
  // Of the directions with confidence > 0.3: the fraction whose best candidate is the nearest /
  // the farthest (a sweep range that excludes the scene piles the estimate up at its ends).
  double at_near = 0, at_far = 0;
  long confident = 0;  // number of those directions
  // Wall time of estimate()'s phases, ms: gray levels and band-pass; the pair costs (remap of the
  // layers, ZNCC); final costs and aggregation; winners, fallback and upsampling.
  struct Timing {
    double gray_ms = 0, cost_ms = 0, aggregate_ms = 0, rest_ms = 0;
  } timing;
};

// The sweep's geometry for one rig, output grid and options, computed once (per camera and
// candidate: where the camera sees every coarse direction's surface point); estimate() then runs per
// frame set. Thread-safe for concurrent estimate() calls.
class DepthSweep {
 public:
  // Throws std::invalid_argument if the options are invalid (IsValid) or near_mm does not lie
  // outside every camera centre.
  DepthSweep(const Rig& rig, const PanoGrid& grid, const PlaneSweepOptions& opt);
  ~DepthSweep();
  DepthSweep(DepthSweep&&) noexcept;
  DepthSweep& operator=(DepthSweep&&) noexcept;

  // frames: one per camera (as stitch.h: 8U/16U/32F, 1 or 3 channels, checked). previous: an
  // earlier result's coarse_inverse (for temporal_weight > 0), or empty. upsample = false leaves
  // depth/confidence empty (the engine uses the coarse grid).
  DepthEstimate estimate(const std::vector<cv::Mat>& frames, const cv::Mat& previous = {},
                         bool upsample = true) const;

  const PanoGrid& coarse_grid() const;
  const PanoGrid& grid() const;
  const PlaneSweepOptions& options() const;
  // Candidate k's inverse depth (1/mm).
  double inverse_depth(int k) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

namespace detail {
// The semi-global aggregation of DepthSweep::estimate ("Aggregation" above): C is the cost volume,
// pixel-major (C[(y W + x) K + k], W x H coarse pixels, K candidates), guide the CV_32FC1 W x H gray
// levels G of the edge-aware P2; returns S(u, k) = sum over `paths` (4 or 8) directions of L_r(u, k),
// in the same layout. Throws std::invalid_argument on mismatched sizes.
std::vector<float> aggregate_sgm(const std::vector<float>& C, int W, int H, int K, const cv::Mat& guide,
                                 double p1, double p2, double edge_gray, int paths);
}  // namespace detail

// The pixel pitch of the rig's finest camera at its image centre, degrees: min over the cameras of
// atan(1 / max(fu, fv)). PlaneSweepOptions::pitch_deg = this runs the sweep at the cameras' own
// resolution (`omma stitch --depth-pitch camera`).
double camera_pitch_deg(const Rig& rig);

// A rectified stereo pair (rows equal in both images, disparity d = x_left - x_right > 0) as a
// two-camera rig: camera 0 (left) at the origin, camera 1 (right) at (baseline_mm, 0, 0), both
// pinhole without distortion, looking along +z with image right u = +x and image down v = +y
// (u x v = t), focal focal_px, principal point at the image centre, field = the image
// (Intrinsics::kImage). A point at depth Z (mm, along +z) then has d = focal_px baseline_mm / Z.
// Any focal and baseline describe the same pixels; they only set the depth scale. Throws
// std::invalid_argument if the rig is not valid (validate_camera).
Rig rectified_pair_rig(int width, int height, double focal_px, double baseline_mm);
// Sweep options for rectified_pair_rig's rig that cover the disparities d_min .. d_max (px) of every
// left pixel at steps of step_px on the optical axis (d = f B s / (w.t), s = 1/D, so the steps are
// step_px / (w.t) elsewhere: 2.6 % larger at the corners of Aloe's field): the camera grid of camera 0 at
// factor 1, q at its centre, near = f B / d_max, far = f B / (d_min min(w.t)), steps = the count that covers
// them (throws std::invalid_argument beyond kMaxSteps or for an invalid range). The other fields come from
// `base`.
PlaneSweepOptions rectified_sweep_options(const Rig& pair, double d_min, double d_max, double step_px = 1,
                                          PlaneSweepOptions base = {});
// The disparity (px, CV_32FC1, camera 0's image) of a depth map on camera 0's grid (depth along the
// ray from camera 0's centre, mm): d = f B / (D (w.t)); 0 where D is +infinity.
cv::Mat disparity_from_depth(const Rig& pair, const cv::Mat& depth_mm);

// The sweep's settings for a rectified pair on a camera grid at the cameras' own pixels, where the
// defaults above (made for a coarse grid of about 5 camera pixels) match too little texture and smooth
// too little: a (2 window + 1)^2 patch, the band-pass 4 times its blur (a ZNCC of detail 0.5 .. 2 px
// across), SGM penalties P1 = 0.8 and P2 = 4 window (a larger patch's cost varies less between
// candidates, so the same smoothness needs a larger P2) with the edge-aware scale 0.1 (a depth edge
// wherever the gray level steps by some 10 %). The patch should span the images' finest reliable
// texture: on the Middlebury Aloe pair (`omma real depth`) window 4 (9 x 9) at its full 1282 x 1110,
// window 2 at a half and a quarter of it (bad-2 measured over windows 1..5, P2 4..32, P1 0.4..1.6, edge
// scale 0.05..1, band-pass ratio 0, 2, 4; the final numbers: docs/results/real_images.md).
PlaneSweepOptions stereo_sweep_defaults(int window = 4);

// The disparity of a rectified pair by two sweeps and a left-right check (the consistency check of
// semi-global matching, Hirschmueller 2008, on the sweep's winners): the sweep on the left camera's grid
// (opt, as from rectified_sweep_options) gives d_L, the same sweep on the right camera's grid (q at its
// centre) d_R; a left pixel x is consistent where |d_L(x) - d_R(x - d_L(x))| <= lr_tolerance_px (d_R at
// the nearest pixel). The others are occluded in the right image or mismatched: each takes the smaller
// (farther) of the nearest consistent disparities to its left and right in its row, since what one
// camera sees and the other does not lies behind the occluding edge, i.e. is background (pixels with
// no consistent one in their row keep d_L). The sweep itself has no model of visibility: on the Aloe pair
// this check and fill take bad-2 from 17.0 % (d_L alone) to 14.0 %, at twice the time. Memory: each
// sweep holds 3 floats per pixel and candidate at its peak (num, den and C; then C, S and the second
// worker's paths), 3.0 GB for 1282 x 1110 pixels and 177 candidates; measured peak RSS 5.2 GB.
struct RectifiedDisparity {
  cv::Mat disparity;   // CV_32FC1 px, the left image, filled
  cv::Mat consistent;  // CV_8UC1, 255 where the left-right check passed
  cv::Mat left_only;   // CV_32FC1 px, the left sweep's own disparity (before the check)
};
RectifiedDisparity rectified_disparity(const Rig& pair, const cv::Mat& left, const cv::Mat& right,
                                       const PlaneSweepOptions& opt, double lr_tolerance_px = 1);

// One-shot: DepthSweep(rig, grid, opt).estimate(frames).
DepthEstimate estimate_depth(const Rig& rig, const std::vector<cv::Mat>& frames, const PanoGrid& grid,
                             const PlaneSweepOptions& opt = {});

}  // namespace omma::pano
