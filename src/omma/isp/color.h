// Colour stages after demosaicing (thesis appendix A.3-A.6, §5.2): automatic white balance by the
// gray-world (eq. A.23-A.30) and white-patch (eq. A.31-A.38, after a 4x4 low-pass) assumptions,
// vignetting correction from a flat-field frame, and RGB565 packing for the frame memories.
//
// Gains are fixed-point Q12 (4096 = 1.0), as a hardware gain multiplier would hold them; applying
// one is v' = min(maxv, (v * gain + 2048) >> 12). Green is the fixed channel: only R and B change.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

namespace omma::isp {

enum class Awb { kNone, kGrayWorld, kWhitePatch };
Awb parse_awb(const std::string& name);  // "none", "grayworld", "whitepatch"
std::string awb_name(Awb a);

struct WbGains {
  int r_q12 = 4096;  // alpha-hat, Q12
  int b_q12 = 4096;  // beta-hat, Q12
  double r() const { return r_q12 / 4096.0; }
  double b() const { return b_q12 / 4096.0; }
};

// Q12 gain num/den, rounded, clamped to [0, 65535] (just under 16x); 1.0 when den is 0.
int gain_q12(double num, double den);

// Gray world (A.23-A.27) from per-channel sums (B, G, R) over the same number of pixels.
WbGains gray_world_gains(const std::array<int64_t, 3>& sums_bgr);
// Gray world from an image (CV_16UC3 BGR): the means of (A.23)-(A.25).
WbGains gray_world_gains(const cv::Mat& bgr16);
// White patch (A.31-A.35): each channel low-passed by the 4x4 box mean over every position where
// the 4x4 window fits (no border padding), then the maxima; gains Gmax/Rmax and Gmax/Bmax.
WbGains white_patch_gains(const cv::Mat& bgr16);
// The same from B, G, R planes (CV_16UC1 each), as develop() holds them.
WbGains white_patch_gains_planes(const cv::Mat planes[3]);
// Plain reference of white_patch_gains (nested loops over every 4x4 window).
WbGains white_patch_gains_reference(const cv::Mat& bgr16);

// Applies (A.28)-(A.30) / (A.36)-(A.38) to a CV_16UC3 BGR image, in place, clamping at maxv.
void apply_gains(cv::Mat& bgr16, const WbGains& g, int maxv);

// Vignetting (flat-field) correction. `flat_raw` is a raw RGGB frame (CV_16UC1) of a uniformly lit
// white target taken through the same lens. Each CFA colour plane (quarter resolution) is smoothed
// with a Gaussian of sigma 2 plane pixels (against noise), and the gain is that plane's maximum
// divided by the smoothed value: 1 at the brightest (usually central) part, > 1 towards the
// corners. Returns a CV_16UC1 Q12 gain per raw pixel (clamped to [1, 65535]).
cv::Mat flat_field_gain(const cv::Mat& flat_raw);
// Multiplies a raw frame by a Q12 gain map (same size), clamping at maxv. Returns a new frame.
cv::Mat apply_flat_field(const cv::Mat& raw16, const cv::Mat& gain_q12, int maxv);

// RGB565 (§5.2): 16 bits per pixel, R in bits 15-11, G in 10-5, B in 4-0, the most significant
// bits of the 8-bit values. pack: CV_8UC3 BGR -> CV_16UC1; unpack: CV_16UC1 -> CV_8UC3 BGR with
// the high bits replicated into the low ones (31 -> 255), so errors are at most 7 (R, B) and 3 (G).
cv::Mat pack_rgb565(const cv::Mat& bgr8);
cv::Mat unpack_rgb565(const cv::Mat& packed);

}  // namespace omma::isp
