// Maps that use the overlap of neighbouring cameras (thesis §4.3): coverage count, the directions
// seen by a single camera, the object boundary map (eq. 4.12-4.16) and the inter-camera PSNR
// (eq. 4.19-4.21). Each takes an optional projection surface `depth` (surface.h; empty = the scene
// at infinity, the thesis's model): the contributors of a direction are then those of its surface
// point (contributors.h). Frames: as in stitch.h (any depth; checked with check_frames). Intensities are
// the gray level Y (BT.601 luma) in [0,1], as in §4.3.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "omma/core/grid.h"
#include "omma/core/rig.h"
#include "omma/pano/contributors.h"

namespace omma::pano {

// Number of cameras seeing each direction (eq. 2.3, and the projection inside the image),
// CV_8UC1, saturated at 255.
cv::Mat coverage_map(const Rig& rig, const PanoGrid& grid, const SearchOptions& search = {},
                     const cv::Mat& depth = {});

// Values of the single-camera map (Fig. 4.6c).
inline constexpr unsigned char kSingleCamera = 255;  // seen by exactly one camera
inline constexpr unsigned char kMultiCamera = 0;     // seen by two or more (the seam band)
inline constexpr unsigned char kNoCamera = 64;       // seen by no camera
// CV_8UC1 from a coverage map: kSingleCamera / kMultiCamera / kNoCamera.
cv::Mat single_camera_map(const cv::Mat& coverage);
// The seam band (directions seen by >= 2 cameras) as a CV_8UC1 mask (255 inside), from either a
// coverage map (values >= 2) or a single-camera map (values == kMultiCamera); `is_single_camera_map`
// says which one it is given.
cv::Mat seam_mask(const cv::Mat& map, bool is_single_camera_map);

// eq. 4.12-4.15: L_ob = |Y(nearest camera j) - Y(farthest camera k)| with j = argmin |r_i|,
// k = argmax |r_i| among the contributors of each direction. CV_32FC1 in [0,1]; 0 where fewer
// than two cameras see the direction.
cv::Mat boundary_map(const Rig& rig, const std::vector<cv::Mat>& frames, const PanoGrid& grid,
                     const SearchOptions& search = {}, const cv::Mat& depth = {});
// eq. 4.16: the panorama with the directions where L_ob > threshold painted pure green
// (Fig. 4.6d, 4.7). Same type as `pano` (8U or 32F, 3 channels).
cv::Mat boundary_overlay(const cv::Mat& pano, const cv::Mat& boundary, double threshold);
// eq. 4.16: binary decision image, CV_8UC1, 255 where L_ob > threshold.
cv::Mat boundary_binary(const cv::Mat& boundary, double threshold);

// eq. 4.19-4.21 with MAX_I = 1: MSE_w = (1/N) sum_j sum_{i>j} (I_i - I_j)^2 over the N contributors
// of each direction (0 where N <= 1), MSE_pan = mean over all m x n panorama pixels,
// PSNR = -10 log10(MSE_pan) in dB. +infinity if every direction agrees exactly.
double inter_camera_psnr(const Rig& rig, const std::vector<cv::Mat>& frames, const PanoGrid& grid,
                         const SearchOptions& search = {}, const cv::Mat& depth = {});

}  // namespace omma::pano
