// Subpixel patch alignment (subpixel.h) on a textured image warped by a known affine map.
#include "omma/calib/subpixel.h"

#include <cmath>
#include <cstdio>
#include <random>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "omma/calib/calibrate.h"
#include "omma/testing/expect.h"

namespace omma::calib {
namespace {

// Smooth random texture (blurred noise), 250 x 250, values in [0, 1].
cv::Mat texture(unsigned seed) {
  cv::Mat img(250, 250, CV_32F);
  cv::RNG rng(seed);
  rng.fill(img, cv::RNG::UNIFORM, 0.0, 1.0);
  cv::GaussianBlur(img, img, cv::Size(), 1.5);
  cv::normalize(img, img, 0, 1, cv::NORM_MINMAX);
  return img;
}

TEST(Subpixel, RecoversKnownAffineCorrespondence) {
  const cv::Mat a = texture(3);
  // b(x) = a(M^-1 x): the point at pa in a lies at M pa in b (continuous coordinates, centres +0.5).
  Eigen::Matrix2d l;
  l << 0.9, 0.25, -0.1, 1.1;
  const Vec2 shift(7.3, -4.6);
  auto map = [&](const Vec2& p) -> Vec2 { return l * (p - Vec2(125, 125)) + Vec2(125, 125) + shift; };
  // warpAffine with WARP_INVERSE_MAP takes dst (OpenCV coords) -> src coords.
  const Eigen::Matrix2d li = l.inverse();
  const Vec2 o = Vec2(125, 125) - 0.5 * Vec2::Ones();  // OpenCV coords of the continuous centre
  const Vec2 t = -li * (o + shift) + o;                // src_cv = li (dst_cv - o - shift) + o
  cv::Mat inv = (cv::Mat_<double>(2, 3) << li(0, 0), li(0, 1), t.x(), li(1, 0), li(1, 1), t.y());
  cv::Mat b;
  cv::warpAffine(a, b, inv, a.size(), cv::INTER_CUBIC | cv::WARP_INVERSE_MAP, cv::BORDER_REFLECT);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(60, 190);
  std::normal_distribution<double> g(0, 0.5);
  double sum2 = 0, worst = 0;
  int ok = 0;
  for (int k = 0; k < 50; ++k) {
    const Vec2 pa(u(rng), u(rng));
    const Vec2 truth = map(pa);
    Eigen::Matrix3d h = Eigen::Matrix3d::Identity();  // a rough initial map, started ~0.7 px away
    h.topLeftCorner<2, 2>() = l;
    h(0, 1) += 0.1;
    h.topRightCorner<2, 1>() = truth + Vec2(g(rng), g(rng)) - h.topLeftCorner<2, 2>() * pa;
    const auto pb = align_patch(a, pa, b, h);
    if (!pb) continue;
    ++ok;
    sum2 += (*pb - truth).squaredNorm();
    worst = std::max(worst, (*pb - truth).norm());
  }
  std::printf("aligned %d of 50, error rms %.4f max %.4f px\n", ok, std::sqrt(sum2 / std::max(ok, 1)), worst);
  EXPECT_GE(ok, 45);
  EXPECT_LT(std::sqrt(sum2 / std::max(ok, 1)), 0.015);
  EXPECT_LT(worst, 0.04);
}

TEST(Subpixel, PatchOutsideTheImageGivesNothing) {
  const cv::Mat a = texture(3);
  EXPECT_FALSE(align_patch(a, Vec2(3, 125), a, Eigen::Matrix3d::Identity()).has_value());
  Eigen::Matrix3d h = Eigen::Matrix3d::Identity();
  h(0, 2) = -170;  // start at (-45, 125)
  EXPECT_FALSE(align_patch(a, Vec2(125, 125), a, h).has_value());
}

using testing::refusal;

TEST(Options, SubpixelOptionsRefuseBadValues) {
  SubpixelOptions o;
  EXPECT_TRUE(o.IsValid());
  EXPECT_TRUE(dense_subpixel_defaults().IsValid());
  o.gauss_px = 4;  // ECC's Gaussian kernel must be odd
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("gauss_px"), std::string::npos);
  const cv::Mat img(64, 64, CV_32FC1, cv::Scalar(0.5));
  EXPECT_NE(
      refusal([&] { align_patch(img, Vec2(32, 32), img, Eigen::Matrix3d::Identity(), o); }).find("gauss_px"),
      std::string::npos);
}

}  // namespace
}  // namespace omma::calib
