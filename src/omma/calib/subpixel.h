// Subpixel refinement of a feature correspondence by patch alignment (OpenCV's ECC, Evangelidis &
// Psarakis 2008, cv::findTransformECC with an affine warp).
//
// SIFT locates a keypoint at the extremum of a difference-of-Gaussians blob; it is not affine
// invariant, so when two cameras see a surface at different obliquity (the colon wall) the two
// keypoints of a match are biased by a few tenths of a pixel against each other. Here the match is
// redefined as "the point of image B that corresponds to the FIXED pixel p_a of image A": a square
// patch of A around p_a is aligned to B by a homography (8 parameters, initialised with the map of
// the local scene plane predicted by the current rig model), maximising the enhanced correlation
// coefficient, which is invariant to gain and offset (vignetting, colour gains). The refined
// position is the warp of p_a. A homography, not an affine map: between two cameras 30-60 deg apart
// the perspective (quadratic) terms across a patch are not affine, and an affine fit absorbs their
// mean into its translation, a bias (measured: docs/results/tuning-calibration.md).
//
// Pixel coordinates: continuous, centres at integer + 0.5 (conventions.h).
#pragma once

#include <optional>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "omma/core/geometry.h"

namespace omma::calib {

struct SubpixelOptions {
  int patch_px = 21;              // template side (pixels of image A, odd)
  int search_margin_px = 10;      // image B is cropped to the warped template's box plus this
  int gauss_px = 5;               // ECC's Gaussian pre-filter size of the coarse stage (odd; 0 or 1:
                                  // no coarse stage); the fine stage runs unfiltered
  int max_iterations = 12;        // ECC iterations per stage
  double epsilon = 1e-5;          // ECC convergence threshold (parameter increment)
  double min_correlation = 0.8;   // reject alignments with a lower ECC correlation coefficient
  double max_shift_px = 2.5;      // reject if the refined position moved more than this from the start
  double flatfield_sigma_px = 0;  // to_alignment_image: divide by the local mean (Gaussian of this
                                  // sigma, pixels); 0 = the plain grey image (see below)
  bool noise_corrected_covariance = true;  // AlignInfo::covariance without the noise's share of
                                           // the gradient energy (alignments where nothing is left fail)

  // False (with the reason in *why) when a value lies outside the range the code relies on.
  bool IsValid(std::string* why = nullptr) const;
};

// A grey image prepared for alignment: CV_32F, one channel (accepts 8U/16U/32F, 1, 3 or 4
// channels). With flatfield_sigma_px > 0 the frame is taken as sRGB-encoded (the simulator's and
// most cameras' output), linearised, converted to grey, and divided by its local mean (a
// Gaussian of that sigma): I_flat = I / (G_sigma * I). Vignetting (a brightness falloff of ~10 %
// across a 21 px patch near the image edges, in opposite directions in the two cameras of an
// overlap) and slow shading are multiplicative, so the division removes them; ECC itself is only
// invariant to a constant gain and offset per patch. Used in the near field
// (CalibrationOptions::dense_subpixel); the far field keeps the plain grey image (the division
// amplifies the noise of dark regions such as a night sky). Measured effect:
// docs/results/tuning-calibration.md.
cv::Mat to_alignment_image(const cv::Mat& image, double flatfield_sigma_px = 0);

// What an alignment measured besides the position.
struct AlignInfo {
  double correlation = 0;     // ECC's enhanced correlation coefficient
  double residual_sigma = 0;  // RMS of template - (gain * warped b + offset), template units
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Identity();  // of the position in b, pixels^2
  Eigen::Matrix3d homography = Eigen::Matrix3d::Identity();  // final map, continuous pixels a -> b
};

// The position in image b (CV_32F) of the point that is at pixel pa in image a, starting from the
// homography h (continuous pixels of a -> continuous pixels of b, h(pa) is the start). Returns
// nothing when the patch leaves an image, ECC fails or the result is rejected by the options.
// `info` (optional) gets the correlation and the position's covariance: the Gauss-Newton
// (Cramer-Rao) estimate sigma_r^2 [F^-1]_tt of the least-squares alignment, F the Fisher matrix of
// an affine warp about pa (translation + 4 linear terms; the translation block after eliminating
// the linear terms, so a patch with one-directional texture, e.g. a single vessel, is uncertain
// along it), sigma_r the fit residual (both images' noise and any mismatch), mapped into b by the
// final homography's Jacobian at pa.
std::optional<Vec2> align_patch(const cv::Mat& a, const Vec2& pa, const cv::Mat& b, const Eigen::Matrix3d& h,
                                const SubpixelOptions& opt = {}, AlignInfo* info = nullptr);

// Applies a homography to a point (continuous pixels).
inline Vec2 apply_homography(const Eigen::Matrix3d& h, const Vec2& p) {
  const Eigen::Vector3d q = h * p.homogeneous();
  return q.hnormalized();
}

}  // namespace omma::calib
