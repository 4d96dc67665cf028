#include "omma/pano/quality.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "omma/core/frames.h"

namespace omma::pano {
namespace {

std::pair<cv::Mat, cv::Mat> as_float_pair(const cv::Mat& a, const cv::Mat& b) {
  if (a.empty() || b.empty()) throw std::invalid_argument("empty image");
  if (a.size() != b.size())
    throw std::invalid_argument("image sizes differ: " + std::to_string(a.cols) + "x" +
                                std::to_string(a.rows) + " vs " + std::to_string(b.cols) + "x" +
                                std::to_string(b.rows));
  cv::Mat fa = to_float01(a), fb = to_float01(b);
  if (fa.channels() == 1 && fb.channels() == 3) cv::cvtColor(fa, fa, cv::COLOR_GRAY2BGR);
  if (fb.channels() == 1 && fa.channels() == 3) cv::cvtColor(fb, fb, cv::COLOR_GRAY2BGR);
  if (fa.channels() != fb.channels()) throw std::invalid_argument("images have different channel counts");
  return {fa, fb};
}

}  // namespace

double psnr_db(const cv::Mat& image, const cv::Mat& truth, const cv::Mat& mask) {
  auto [a, b] = as_float_pair(image, truth);
  cv::Mat diff;
  cv::subtract(a, b, diff);
  diff = diff.mul(diff);
  if (!mask.empty()) {
    if (mask.size() != a.size() || mask.type() != CV_8UC1)
      throw std::invalid_argument("mask must be an 8-bit one-channel image of the panorama's size");
    if (cv::countNonZero(mask) == 0) throw std::invalid_argument("the mask selects no pixel");
  }
  const cv::Scalar m = mask.empty() ? cv::mean(diff) : cv::mean(diff, mask);
  double sum = 0;
  for (int c = 0; c < diff.channels(); ++c) sum += m[c];
  const double mse = sum / diff.channels();
  if (mse <= 0) return std::numeric_limits<double>::infinity();
  return -10 * std::log10(mse);
}

double ssim(const cv::Mat& image, const cv::Mat& truth) {
  auto [a, b] = as_float_pair(image, truth);
  std::vector<cv::Mat> xs, ys;
  cv::split(a, xs);
  cv::split(b, ys);
  const double c1 = 0.01 * 0.01, c2 = 0.03 * 0.03;
  auto blur = [](const cv::Mat& m) {
    cv::Mat out;
    cv::GaussianBlur(m, out, cv::Size(11, 11), 1.5, 1.5, cv::BORDER_REFLECT);
    return out;
  };
  double s = 0;
  for (size_t ch = 0; ch < xs.size(); ++ch) {  // one channel at a time (Wang et al. 2004, eq. 13)
    const cv::Mat& x = xs[ch];
    const cv::Mat& y = ys[ch];
    const cv::Mat mx = blur(x), my = blur(y);
    const cv::Mat mx2 = mx.mul(mx), my2 = my.mul(my), mxy = mx.mul(my);
    const cv::Mat sx2 = blur(x.mul(x)) - mx2, sy2 = blur(y.mul(y)) - my2, sxy = blur(x.mul(y)) - mxy;
    const cv::Mat num = (2 * mxy + c1).mul(2 * sxy + c2);
    const cv::Mat den = (mx2 + my2 + c1).mul(sx2 + sy2 + c2);
    cv::Mat map;
    cv::divide(num, den, map);
    s += cv::mean(map)[0];
  }
  return s / static_cast<double>(xs.size());
}

EvalSummary evaluate(const cv::Mat& image, const cv::Mat& truth, const cv::Mat& seam) {
  EvalSummary r;
  r.psnr_db = psnr_db(image, truth);
  r.ssim = ssim(image, truth);
  r.seam_psnr_db = seam.empty() ? std::numeric_limits<double>::quiet_NaN() : psnr_db(image, truth, seam);
  return r;
}

}  // namespace omma::pano
