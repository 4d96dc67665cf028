// The single-camera ISP (thesis §5.1.2, appendix A): raw RGGB Bayer frame -> 8-bit BGR image.
//
//   raw (CV_16UC1, `bits`-bit values, (0,0) = R)
//     -> vignetting correction (optional flat-field gain, color.h)
//     -> demosaicing (demosaic.h: bilinear, hybrid, ah, cc)
//     -> white balance (none, gray world, white patch; color.h)
//     -> 8 most significant bits (§5.2)  -> CV_8UC3 BGR
//
// This is the API the stitcher and the engine call for `--raw` frames (frames.h:
// DIR/cam_XX_raw.png): develop() for one camera, develop_all() for a set (parallel over frames).
#pragma once

#include <map>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/isp/color.h"
#include "omma/isp/demosaic.h"
#include "omma/isp/link.h"

namespace omma::isp {

struct IspOptions {
  Demosaic demosaic = Demosaic::kHybrid;
  Awb awb = Awb::kGrayWorld;
  int bits = 10;      // bit depth of the raw values (10 on the dome's sensors)
  cv::Mat flat_gain;  // optional Q12 vignetting gain per raw pixel, from flat_field_gain()
  // Output encoding. false: the 8 most significant bits of the linear values (the thesis'
  // hardware, §5.2). true: sRGB-encoded 8-bit (IEC 61966-2-1 curve through a 2^bits-entry table),
  // to match sRGB images such as the simulator's cam_XX.png and truth.png (its raw is linear).
  bool srgb = false;

  // False (with the reason in *why) when a value lies outside the range the code relies on.
  bool IsValid(std::string* why = nullptr) const;
};

// The output table of develop(): 2^bits entries, value -> 8-bit (linear MSBs or sRGB).
std::vector<uint8_t> output_table(int bits, bool srgb);

// Raw frame -> CV_8UC3 BGR. Throws std::invalid_argument (clear message) on a frame that is not
// single-channel 8/16-bit, has odd or tiny sizes, values beyond `bits`, or a flat-gain size
// mismatch. Fast path (integer, row pointers); identical to develop_reference().
cv::Mat develop(const cv::Mat& raw16, const IspOptions& options);
// The plain reference pipeline (demosaic_reference, the reference white balance).
cv::Mat develop_reference(const cv::Mat& raw16, const IspOptions& options);
// develop() over a set of frames, in parallel (oneTBB) over the frames.
std::vector<cv::Mat> develop_all(const std::vector<cv::Mat>& raws, const IspOptions& options);

// Reads a flat-field raw frame (16-bit single-channel PNG) and returns its Q12 gain map.
cv::Mat load_flat_field(const std::string& path);

// ---- Evaluation (Table A.1) ----------------------------------------------------------------

struct ChannelPsnr {
  double r = 0, g = 0, b = 0;
};
// Per-channel PSNR in dB for 8-bit images (eq. A.39-A.40), leaving out `border` pixels on every
// side. Identical channels give 99 dB (capped).
ChannelPsnr psnr_per_channel(const cv::Mat& test_bgr8, const cv::Mat& ref_bgr8, int border = 8);

// Mosaics an 8-bit BGR photograph through the RGGB filter (8-bit values), demosaics it with each
// of our four methods and with OpenCV's cvtColor bilinear and edge-aware conversions, and returns
// PSNR against the photograph for each, keyed "bilinear", "hybrid", "ah", "cc",
// "opencv_bilinear", "opencv_ea". The photo is cropped to even width and height first.
std::map<std::string, ChannelPsnr> evaluate_demosaic(const cv::Mat& photo_bgr8, int border = 8);

// ---- Link frames <-> images --------------------------------------------------------------------

// CV_16UC1 (or CV_8UC1) frame -> LinkFrame (values must fit in `bits`; throws otherwise).
LinkFrame to_link_frame(const cv::Mat& raw, int bits);
// LinkFrame -> CV_16UC1.
cv::Mat to_mat(const LinkFrame& frame);

}  // namespace omma::isp
