#include "omma/calib/subpixel.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "omma/core/srgb.h"
#include "omma/core/valid.h"

namespace omma::calib {

bool SubpixelOptions::IsValid(std::string* why) const {
  if (patch_px < 3) return invalid(why, "patch_px must be >= 3");
  if (search_margin_px < 0) return invalid(why, "search_margin_px must be >= 0");
  if (gauss_px < 0 || (gauss_px > 1 && gauss_px % 2 == 0))
    return invalid(why, "gauss_px must be 0, 1 or odd (a Gaussian kernel size)");
  if (max_iterations < 1) return invalid(why, "max_iterations must be >= 1");
  if (!(epsilon > 0)) return invalid(why, "epsilon must be > 0");
  if (!(min_correlation >= -1 && min_correlation <= 1))
    return invalid(why, "min_correlation must be in [-1, 1]");
  if (!(max_shift_px > 0)) return invalid(why, "max_shift_px must be > 0");
  if (!(flatfield_sigma_px >= 0)) return invalid(why, "flatfield_sigma_px must be >= 0");
  return true;
}

cv::Mat to_alignment_image(const cv::Mat& image, double flatfield_sigma_px) {
  auto to_gray = [](cv::Mat m) {
    if (m.channels() == 3) cv::cvtColor(m, m, cv::COLOR_BGR2GRAY);
    if (m.channels() == 4) cv::cvtColor(m, m, cv::COLOR_BGRA2GRAY);
    return m;
  };
  const double scale = image.depth() == CV_8U ? 1.0 / 255 : image.depth() == CV_16U ? 1.0 / 65535 : 1.0;
  if (flatfield_sigma_px <= 0) {
    cv::Mat out;
    to_gray(image).convertTo(out, CV_32F, scale);
    return out;
  }
  cv::Mat lin;
  if (image.depth() == CV_8U) {  // a 256-entry table
    cv::Mat lut(1, 256, CV_32F);
    for (int i = 0; i < 256; ++i) lut.at<float>(i) = srgb_to_linear(i / 255.0f);
    cv::LUT(image, lut, lin);
  } else {
    image.convertTo(lin, CV_MAKETYPE(CV_32F, image.channels()), scale);
    cv::Mat flat = lin.reshape(1);
    flat.forEach<float>([](float& v, const int*) { v = srgb_to_linear(std::clamp(v, 0.0f, 1.0f)); });
  }
  const cv::Mat gray = to_gray(lin);
  cv::Mat mean;
  cv::GaussianBlur(gray, mean, cv::Size(), flatfield_sigma_px, flatfield_sigma_px, cv::BORDER_REFLECT);
  // The floor keeps black regions (the colon's lumen, the night sky) from amplifying noise.
  return gray / (mean + 1e-3f);
}

namespace {

// The translation x -> x + (dx, dy) as a homography.
Eigen::Matrix3d translation(double dx, double dy) {
  Eigen::Matrix3d s = Eigen::Matrix3d::Identity();
  s(0, 2) = dx, s(1, 2) = dy;
  return s;
}

// The crop of b to search: the box of the template ta (side x side px) mapped by h, plus the
// search margin, within b; nullopt if the map is degenerate or the crop smaller than the template.
std::optional<cv::Rect> search_crop(const cv::Mat& b, const cv::Rect& ta, int side, const Eigen::Matrix3d& h,
                                    const SubpixelOptions& opt) {
  double x0 = 1e30, y0 = 1e30, x1 = -1e30, y1 = -1e30;
  for (int k = 0; k < 4; ++k) {
    const Vec2 c = apply_homography(h, Vec2(ta.x + (k & 1 ? side : 0), ta.y + (k & 2 ? side : 0)));
    if (!c.allFinite()) return std::nullopt;
    x0 = std::min(x0, c.x()), y0 = std::min(y0, c.y()), x1 = std::max(x1, c.x()), y1 = std::max(y1, c.y());
  }
  if (x1 - x0 > 4 * side || y1 - y0 > 4 * side) return std::nullopt;  // degenerate map
  cv::Rect crop(static_cast<int>(std::floor(x0)) - opt.search_margin_px,
                static_cast<int>(std::floor(y0)) - opt.search_margin_px,
                static_cast<int>(std::ceil(x1 - x0)) + 2 * opt.search_margin_px + 1,
                static_cast<int>(std::ceil(y1 - y0)) + 2 * opt.search_margin_px + 1);
  crop &= cv::Rect(0, 0, b.cols, b.rows);
  if (crop.width < side || crop.height < side) return std::nullopt;
  return crop;
}

// The warp h (3 x 3, CV_32F) from the template ta to the crop in OpenCV coordinates.
cv::Mat crop_warp(const Eigen::Matrix3d& h, const cv::Rect& ta, const cv::Rect& crop) {
  // Warp in OpenCV coordinates (integer pixel centres) of the template and the crop:
  // w = S_crop^-1 h S_template, S_r(x) = x + r.origin + 0.5.
  Eigen::Matrix3d w = translation(-crop.x - 0.5, -crop.y - 0.5) * h * translation(ta.x + 0.5, ta.y + 0.5);
  w /= w(2, 2);
  cv::Mat warp(3, 3, CV_32F);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) warp.at<float>(r, c) = static_cast<float>(w(r, c));
  return warp;
}

// The ECC correlation of the template t with the crop bc after refining warp; nullopt if ECC
// fails.
std::optional<double> ecc_correlation(const cv::Mat& t, const cv::Mat& bc, cv::Mat& warp,
                                      const SubpixelOptions& opt) {
  // Coarse stage with ECC's Gaussian pre-filter (a wider basin of convergence), then a fine stage
  // without it: the two images are blurred in their own pixel frames, which differ by the map, and
  // the mismatched blur shifts the optimum by up to ~0.1 px on fine texture.
  double rho = 0;
  const cv::TermCriteria crit(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, opt.max_iterations,
                              opt.epsilon);
  try {
    if (opt.gauss_px > 1)
      rho = cv::findTransformECC(t, bc, warp, cv::MOTION_HOMOGRAPHY, crit, cv::noArray(), opt.gauss_px);
    rho = cv::findTransformECC(t, bc, warp, cv::MOTION_HOMOGRAPHY, crit, cv::noArray(), 1);
  } catch (const cv::Exception&) {
    return std::nullopt;
  }
  return rho;
}

// The gain g and offset o of a photometric fit t = g * bw + o.
struct GainOffset {
  double g, o;
};

// The least-squares photometric fit t = g * bw + o of two side x side patches.
GainOffset photometric_fit(const cv::Mat& t, const cv::Mat& bw, int side) {
  double sb = 0, st = 0, sbb = 0, sbt = 0;
  const int m = side * side;
  for (int r = 0; r < side; ++r)
    for (int c = 0; c < side; ++c) {
      const double x = bw.at<float>(r, c), y = t.at<float>(r, c);
      sb += x, st += y, sbb += x * x, sbt += x * y;
    }
  const double vb = sbb - sb * sb / m, cbt = sbt - sb * st / m;
  const double g = vb > 0 ? cbt / vb : 0, o = (st - g * sb) / m;
  return {g, o};
}

// The Fisher matrix of the affine warp about pt (template px), gradients averaged over t and
// g * bw, over the patch's interior; *ss_out: the sum of the squared residuals of the fit there.
Eigen::Matrix<double, 6, 6> affine_fisher(const cv::Mat& t, const cv::Mat& bw, const GainOffset& fit,
                                          const Vec2& pt, int side, double* ss_out) {
  const double g = fit.g, o = fit.o;
  // Fisher matrix of the affine warp about pa, gradients averaged over both images.
  Eigen::Matrix<double, 6, 6> f = Eigen::Matrix<double, 6, 6>::Zero();
  double ss = 0;
  for (int r = 1; r < side - 1; ++r)
    for (int c = 1; c < side - 1; ++c) {
      const double e = t.at<float>(r, c) - g * bw.at<float>(r, c) - o;
      ss += e * e;
      const double gx = 0.25 * (t.at<float>(r, c + 1) - t.at<float>(r, c - 1) +
                                g * (bw.at<float>(r, c + 1) - bw.at<float>(r, c - 1)));
      const double gy = 0.25 * (t.at<float>(r + 1, c) - t.at<float>(r - 1, c) +
                                g * (bw.at<float>(r + 1, c) - bw.at<float>(r - 1, c)));
      const double u = c + 0.5 - pt.x(), v = r + 0.5 - pt.y();
      Eigen::Matrix<double, 6, 1> j;
      j << gx, gy, gx * u, gx * v, gy * u, gy * v;
      f += j * j.transpose();
    }
  *ss_out = ss;
  return f;
}

// f less the noise's share of the gradients' energy (residual sigma sigma_r); false if f is then
// not positive definite.
bool subtract_gradient_noise(Eigen::Matrix<double, 6, 6>& f, const Vec2& pt, int side, double sigma_r) {
  // The noise of both images adds to the gradients' energy: E[g g^T] gains 0.125 sigma_r^2 per
  // axis for the averaged central differences above (sigma_r^2 = sigma_t^2 + gain^2 sigma_b^2),
  // which would make dark, noisy patches look precise. Subtract it.
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  for (int r = 1; r < side - 1; ++r)
    for (int c = 1; c < side - 1; ++c) {
      const Eigen::Vector3d b3(1, c + 0.5 - pt.x(), r + 0.5 - pt.y());
      m += b3 * b3.transpose();
    }
  m *= 0.125 * sigma_r * sigma_r;
  const int ix[3] = {0, 2, 3}, iy[3] = {1, 4, 5};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) f(ix[i], ix[j]) -= m(i, j), f(iy[i], iy[j]) -= m(i, j);
  return !(Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>>(f).eigenvalues()(0) <= 0);
}

// Fills info's homography (a px -> b px), residual sigma and covariance (b px^2) of the alignment
// of template t (the square ta of a, pa at pt in it) with the crop bc of b, refined warp `warp`
// (wr); false if the covariance is unusable.
bool fill_align_info(const cv::Mat& t, const cv::Mat& bc, const cv::Rect& ta, const cv::Rect& crop,
                     const cv::Mat& warp, const Eigen::Matrix3d& wr, const Vec2& pa, const Vec2& pt, int side,
                     const SubpixelOptions& opt, AlignInfo* info) {
  const Eigen::Matrix3d hf =
      translation(crop.x + 0.5, crop.y + 0.5) * wr * translation(-ta.x - 0.5, -ta.y - 0.5);
  info->homography = hf / hf(2, 2);
  // b warped back onto the template grid, then the photometric fit t = g * bw + o.
  cv::Mat bw;
  cv::warpPerspective(bc, bw, warp, cv::Size(side, side), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                      cv::BORDER_REPLICATE);
  const GainOffset fit = photometric_fit(t, bw, side);
  double ss = 0;
  Eigen::Matrix<double, 6, 6> f = affine_fisher(t, bw, fit, pt, side, &ss);
  const int used = (side - 2) * (side - 2);
  info->residual_sigma = std::sqrt(ss / std::max(1, used - 8));
  if (opt.noise_corrected_covariance && !subtract_gradient_noise(f, pt, side, info->residual_sigma))
    return false;
  const Eigen::Matrix<double, 6, 6> fi = f.inverse();
  Eigen::Matrix2d cov_a = info->residual_sigma * info->residual_sigma * fi.topLeftCorner<2, 2>();
  // Jacobian of the final homography at pa (b pixels per a pixel).
  const Eigen::Vector3d q = info->homography * pa.homogeneous();
  Eigen::Matrix<double, 2, 3> dq;
  dq << 1 / q.z(), 0, -q.x() / (q.z() * q.z()), 0, 1 / q.z(), -q.y() / (q.z() * q.z());
  const Eigen::Matrix2d jac = dq * info->homography.topLeftCorner<3, 2>();
  info->covariance = jac * cov_a * jac.transpose();
  return info->covariance.allFinite();
}

}  // namespace

std::optional<Vec2> align_patch(const cv::Mat& a, const Vec2& pa, const cv::Mat& b, const Eigen::Matrix3d& h,
                                const SubpixelOptions& opt, AlignInfo* info) {
  std::string why;
  if (!opt.IsValid(&why)) throw std::invalid_argument("align_patch: " + why);
  const int half = opt.patch_px / 2;
  const int side = 2 * half + 1;
  // Template: the integer-aligned square of A whose centre pixel contains pa (no resampling of A).
  const int ca = static_cast<int>(std::floor(pa.x())), ra = static_cast<int>(std::floor(pa.y()));
  const cv::Rect ta(ca - half, ra - half, side, side);
  if (ta.x < 0 || ta.y < 0 || ta.x + side > a.cols || ta.y + side > a.rows) return std::nullopt;
  if (!h.allFinite()) return std::nullopt;
  // Crop of B: the box of the warped template plus a margin.
  const std::optional<cv::Rect> crop_or = search_crop(b, ta, side, h, opt);
  if (!crop_or) return std::nullopt;
  const cv::Rect crop = *crop_or;
  cv::Mat warp = crop_warp(h, ta, crop);
  const std::optional<double> rho = ecc_correlation(a(ta), b(crop), warp, opt);
  if (!rho) return std::nullopt;
  if (info) info->correlation = *rho;
  if (!(*rho >= opt.min_correlation)) return std::nullopt;
  Eigen::Matrix3d wr;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) wr(r, c) = warp.at<float>(r, c);
  const Vec2 pt(pa.x() - 0.5 - ta.x, pa.y() - 0.5 - ta.y);
  const Vec2 out = apply_homography(wr, pt) + Vec2(crop.x + 0.5, crop.y + 0.5);
  if (!out.allFinite() || (out - apply_homography(h, pa)).norm() > opt.max_shift_px) return std::nullopt;
  if (info && !fill_align_info(a(ta), b(crop), ta, crop, warp, wr, pa, pt, side, opt, info))
    return std::nullopt;
  return out;
}

}  // namespace omma::calib
