// Image quality against a ground truth (the simulator's ideal panorama): PSNR, SSIM and the PSNR
// over the seam band (directions seen by two or more cameras, maps.h seam_mask).
// Images: 8U, 16U or 32F ([0,1]), 1 or 3 channels; compared in [0,1] (MAX = 1), all channels.
#pragma once

#include <opencv2/core.hpp>

namespace omma::pano {

// PSNR in dB = 10 log10(1 / MSE), MSE over all channels of the pixels where `mask` (CV_8UC1,
// optional) is non-zero. +infinity for identical images. Throws std::invalid_argument if sizes or
// channel counts differ, or the mask selects no pixel.
double psnr_db(const cv::Mat& image, const cv::Mat& truth, const cv::Mat& mask = {});

// Mean SSIM (Wang et al. 2004: 11x11 Gaussian window, sigma 1.5, K1 = 0.01, K2 = 0.03, L = 1),
// averaged over the channels and the whole image.
double ssim(const cv::Mat& image, const cv::Mat& truth);

struct EvalSummary {
  double psnr_db = 0;
  double ssim = 0;
  double seam_psnr_db = 0;  // NaN when no seam mask was given
};
// All three; `seam` is the seam-band mask (CV_8UC1, non-zero inside), or empty.
EvalSummary evaluate(const cv::Mat& image, const cv::Mat& truth, const cv::Mat& seam = {});

}  // namespace omma::pano
