#include "omma/calib/subpixel.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

namespace omma::calib {

cv::Mat to_alignment_image(const cv::Mat& image) {
  cv::Mat gray = image;
  if (gray.channels() == 3) cv::cvtColor(gray, gray, cv::COLOR_BGR2GRAY);
  if (gray.channels() == 4) cv::cvtColor(gray, gray, cv::COLOR_BGRA2GRAY);
  cv::Mat out;
  const double scale = gray.depth() == CV_8U ? 1.0 / 255 : gray.depth() == CV_16U ? 1.0 / 65535 : 1.0;
  gray.convertTo(out, CV_32F, scale);
  return out;
}

std::optional<Vec2> align_patch(const cv::Mat& a, const Vec2& pa, const cv::Mat& b, const Eigen::Matrix3d& h,
                                const SubpixelOptions& opt, double* correlation) {
  const int half = opt.patch_px / 2;
  const int side = 2 * half + 1;
  // Template: the integer-aligned square of A whose centre pixel contains pa (no resampling of A).
  const int ca = static_cast<int>(std::floor(pa.x())), ra = static_cast<int>(std::floor(pa.y()));
  const cv::Rect ta(ca - half, ra - half, side, side);
  if (ta.x < 0 || ta.y < 0 || ta.x + side > a.cols || ta.y + side > a.rows) return std::nullopt;
  if (!h.allFinite()) return std::nullopt;
  // Crop of B: the box of the warped template plus a margin.
  double x0 = 1e30, y0 = 1e30, x1 = -1e30, y1 = -1e30;
  for (int k = 0; k < 4; ++k) {
    const Vec2 c = apply_homography(h, Vec2(ta.x + (k & 1 ? side : 0), ta.y + (k & 2 ? side : 0)));
    if (!c.allFinite()) return std::nullopt;
    x0 = std::min(x0, c.x()), y0 = std::min(y0, c.y()), x1 = std::max(x1, c.x()), y1 = std::max(y1, c.y());
  }
  if (x1 - x0 > 4 * side || y1 - y0 > 4 * side) return std::nullopt;  // degenerate map
  cv::Rect crop(static_cast<int>(std::floor(x0)) - opt.search_margin_px, static_cast<int>(std::floor(y0)) - opt.search_margin_px,
                static_cast<int>(std::ceil(x1 - x0)) + 2 * opt.search_margin_px + 1,
                static_cast<int>(std::ceil(y1 - y0)) + 2 * opt.search_margin_px + 1);
  crop &= cv::Rect(0, 0, b.cols, b.rows);
  if (crop.width < side || crop.height < side) return std::nullopt;
  // Warp in OpenCV coordinates (integer pixel centres) of the template and the crop:
  // w = S_crop^-1 h S_template, S_r(x) = x + r.origin + 0.5.
  auto shift = [](double dx, double dy) {
    Eigen::Matrix3d s = Eigen::Matrix3d::Identity();
    s(0, 2) = dx, s(1, 2) = dy;
    return s;
  };
  Eigen::Matrix3d w = shift(-crop.x - 0.5, -crop.y - 0.5) * h * shift(ta.x + 0.5, ta.y + 0.5);
  w /= w(2, 2);
  cv::Mat warp(3, 3, CV_32F);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) warp.at<float>(r, c) = static_cast<float>(w(r, c));
  // Coarse stage with ECC's Gaussian pre-filter (a wider basin of convergence), then a fine stage
  // without it: the two images are blurred in their own pixel frames, which differ by the map, and
  // the mismatched blur shifts the optimum by up to ~0.1 px on fine texture.
  double rho = 0;
  const cv::TermCriteria crit(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, opt.max_iterations, opt.epsilon);
  try {
    if (opt.gauss_px > 1)
      rho = cv::findTransformECC(a(ta), b(crop), warp, cv::MOTION_HOMOGRAPHY, crit, cv::noArray(), opt.gauss_px);
    rho = cv::findTransformECC(a(ta), b(crop), warp, cv::MOTION_HOMOGRAPHY, crit, cv::noArray(), 1);
  } catch (const cv::Exception&) {
    return std::nullopt;
  }
  if (correlation) *correlation = rho;
  if (!(rho >= opt.min_correlation)) return std::nullopt;
  Eigen::Matrix3d wr;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) wr(r, c) = warp.at<float>(r, c);
  const Vec2 pt(pa.x() - 0.5 - ta.x, pa.y() - 0.5 - ta.y);
  const Vec2 out = apply_homography(wr, pt) + Vec2(crop.x + 0.5, crop.y + 0.5);
  if (!out.allFinite() || (out - apply_homography(h, pa)).norm() > opt.max_shift_px) return std::nullopt;
  return out;
}

}  // namespace omma::calib
