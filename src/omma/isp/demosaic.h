// Bayer demosaicing of RGGB raw frames (thesis §5.1.2, eq. 5.1-5.10, appendix A eq. A.1-A.22).
//
// CFA layout (the dome's sensors and the simulator's cam_XX_raw.png): (row 0, col 0) = R,
// (0, 1) = G, (1, 0) = G, (1, 1) = B, repeating every 2x2. Raw frames are CV_16UC1 with values in
// [0, 2^bits - 1] (10-bit on the camera; 8-bit when a photograph is mosaicked for evaluation).
// Outputs are CV_16UC3 in OpenCV's BGR channel order with the same value scale, clamped to
// [0, 2^bits - 1]. Borders are mirrored without repeating the edge pixel (OpenCV's
// BORDER_REFLECT_101: index -1 -> 1, -2 -> 2), which keeps the CFA phase; there is no
// wrap-around. Width and height must be even and at least 4.
//
// All methods use integer arithmetic with round-half-up divisions, written twice: a plain
// per-pixel reference that reads the 5x5 window through a mirroring accessor and spells out the
// equations (names as in Fig. 5.6b: centre 13, R7/R9/R17/R19 the diagonals, G8/G12/G14/G18 the
// crosses, B3/B11/B15/B23 the +-2 samples), and a fast path (padded copy, row pointers, 2x2 sites
// without per-pixel branches) that the tests check gives identical output.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

namespace omma::isp {

enum class Demosaic {
  kBilinear,           // eq. 5.1-5.10 (3x3)
  kHybrid,             // linear with gradient correction, eq. A.19-A.22, alpha 1/2, beta 5/8, gamma 3/4
  kAdamsHamilton,      // gradient-directed, eq. A.1-A.12
  kColourCorrelation,  // Adams-Hamilton with colour-correlation gradients, eq. A.13-A.18
};

// "bilinear", "hybrid", "ah", "cc" (throws std::invalid_argument listing the valid names).
Demosaic parse_demosaic(const std::string& name);
std::string demosaic_name(Demosaic m);

// Throws std::invalid_argument with a clear message unless `raw` is a CV_16UC1 (or CV_8UC1)
// Bayer frame with even width and height >= 4 and no value above 2^bits - 1.
void check_bayer(const cv::Mat& raw, int bits);

// Samples a colour image (CV_8UC3 or CV_16UC3, BGR) through the RGGB filter: CV_16UC1 with the
// value of the filter's channel at each pixel (same scale).
cv::Mat mosaic_rggb(const cv::Mat& bgr);

// Fast path (the one to use). `sums`, when given, receives the per-channel sums (B, G, R) of the
// output (for gray-world white balance without another pass).
cv::Mat demosaic(const cv::Mat& raw, Demosaic method, int bits, std::array<int64_t, 3>* sums = nullptr);

// Fast path with planar output: planes[0..2] = B, G, R as CV_16UC1 (what develop() uses).
void demosaic_planes(const cv::Mat& raw, Demosaic method, int bits, cv::Mat planes[3]);
// The interleaved integer path for every method and bit depth (demosaic() uses the planar one for
// every method at <= 10 bits); exposed so that the tests can compare both with the reference.
cv::Mat demosaic_interleaved(const cv::Mat& raw, Demosaic method, int bits,
                             std::array<int64_t, 3>* sums = nullptr);

// Plain per-pixel reference (slow, readable): identical output to demosaic().
cv::Mat demosaic_reference(const cv::Mat& raw, Demosaic method, int bits);

// OpenCV's Bayer conversion codes for our RGGB layout ((0,0) = R). OpenCV names a pattern after
// the second row's second and third pixels, so RGGB is its "BG" pattern: COLOR_BayerBG2BGR and
// COLOR_BayerBG2BGR_EA (checked by a test on a coloured mosaic).
int opencv_bayer_code_bilinear();
int opencv_bayer_code_ea();

}  // namespace omma::isp
