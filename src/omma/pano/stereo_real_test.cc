// The depth sweep on real photographs with a truth no simulator made: the rectified Middlebury Aloe pair
// (OpenCV's samples, testing/real_data.h) at a quarter of its size, as a two-camera rig on the left
// camera's own pixels (rectified_disparity), against its true disparity and beside OpenCV's StereoSGBM
// on the same images. The full-size measurement is `omma real depth` (bench/real_depth.cc).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "omma/pano/plane_sweep.h"
#include "omma/testing/real_data.h"

namespace omma::pano {
namespace {

struct Measured {
  double omma_bad2 = 0, omma_median = 0, sgbm_bad2 = 0, sgbm_median = 0;
};

// bad-2 (%: no estimate, or |d - truth| > 2 px) and the median |error| (px, where an estimate exists)
// over the pixels with a known truth right of the left border band where SGBM computes nothing.
void score(const cv::Mat& d, const cv::Mat& valid, const cv::Mat& truth, int border, double& bad2,
           double& med) {
  long n = 0, bad = 0;
  std::vector<float> err;
  for (int r = 0; r < truth.rows; ++r)
    for (int c = border; c < truth.cols; ++c) {
      if (!(truth.at<float>(r, c) > 0)) continue;
      ++n;
      if (!valid.at<uint8_t>(r, c)) {
        ++bad;
        continue;
      }
      const float e = std::abs(d.at<float>(r, c) - truth.at<float>(r, c));
      err.push_back(e);
      bad += e > 2;
    }
  ASSERT_GT(n, 1000);
  bad2 = 100.0 * bad / n;
  std::nth_element(err.begin(), err.begin() + err.size() / 2, err.end());
  med = err[err.size() / 2];
}

// The pair at 1/down of its size (cv::INTER_AREA; the truth averaged over blocks whose pixels are all
// known, scaled by the width ratio), cropped to `crop` (fractions of the image), as bench/real_depth.cc.
Measured measure(const std::filesystem::path& dir, int down, cv::Rect2d crop) {
  cv::Mat left = cv::imread((dir / "aloeL.jpg").string(), cv::IMREAD_COLOR);
  cv::Mat right = cv::imread((dir / "aloeR.jpg").string(), cv::IMREAD_COLOR);
  const cv::Mat gt = cv::imread((dir / "aloeGT.png").string(), cv::IMREAD_GRAYSCALE);
  EXPECT_FALSE(left.empty() || right.empty() || gt.empty()) << dir;
  const cv::Size small((left.cols + down / 2) / down, (left.rows + down / 2) / down);
  const double scale = double(small.width) / left.cols;
  cv::Mat truth_full, known, sum, frac;
  gt.convertTo(truth_full, CV_32F);
  cv::Mat(gt > 0).convertTo(known, CV_32F, 1 / 255.0);
  cv::resize(left, left, small, 0, 0, cv::INTER_AREA);
  cv::resize(right, right, small, 0, 0, cv::INTER_AREA);
  cv::resize(truth_full, sum, small, 0, 0, cv::INTER_AREA);
  cv::resize(known, frac, small, 0, 0, cv::INTER_AREA);
  cv::Mat truth(small, CV_32FC1, cv::Scalar(0));
  truth.setTo(0);
  sum.convertTo(sum, CV_32F, scale);
  sum.copyTo(truth, frac > 0.999f);
  const cv::Rect roi(int(crop.x * small.width), int(crop.y * small.height), int(crop.width * small.width),
                     int(crop.height * small.height));
  left = left(roi).clone();
  right = right(roi).clone();
  truth = truth(roi).clone();
  // The range: the truth's extremes widened by 3 px, SGBM's numDisparities a multiple of 16.
  double t_min = 0, t_max = 0;
  cv::minMaxLoc(truth, nullptr, &t_max);
  cv::Mat t = truth.clone();
  t.setTo(1e9, truth <= 0);
  cv::minMaxLoc(t, &t_min);
  const int d_lo = std::max(1, int(std::floor(t_min)) - 3);
  const int n_d = 16 * int(std::ceil((std::ceil(t_max) + 3 - d_lo + 1) / 16.0));
  const int border = d_lo + n_d;

  Measured m;
  const Rig rig = rectified_pair_rig(left.cols, left.rows, 3740 * scale, 160);
  const PlaneSweepOptions so =
      rectified_sweep_options(rig, d_lo, d_lo + n_d - 1, 1, stereo_sweep_defaults(down >= 2 ? 2 : 4));
  const RectifiedDisparity rd = rectified_disparity(rig, left, right, so);
  const cv::Mat all(left.size(), CV_8UC1, cv::Scalar(255));
  score(rd.disparity, all, truth, border, m.omma_bad2, m.omma_median);
  // StereoSGBM as OpenCV's stereo_match.cpp sets it up; the best of block 3 / 5 and the modes.
  m.sgbm_bad2 = 101;
  const int cn = 3;
  for (auto [mode, b] :
       {std::pair{cv::StereoSGBM::MODE_SGBM, 3}, std::pair{cv::StereoSGBM::MODE_SGBM, 5},
        std::pair{cv::StereoSGBM::MODE_HH, 3}, std::pair{cv::StereoSGBM::MODE_SGBM_3WAY, 3}}) {
    auto sgbm =
        cv::StereoSGBM::create(d_lo, n_d, b, 8 * cn * b * b, 32 * cn * b * b, 1, 63, 10, 100, 32, mode);
    cv::Mat raw, d;
    sgbm->compute(left, right, raw);
    raw.convertTo(d, CV_32F, 1 / 16.0);
    double bad2 = 0, med = 0;
    score(d, raw >= 16 * d_lo, truth, border, bad2, med);
    if (bad2 < m.sgbm_bad2) {
      m.sgbm_bad2 = bad2;
      m.sgbm_median = med;
    }
  }
  std::printf(
      "Aloe 1/%d crop (%.2f %.2f %.2f %.2f) %dx%d: omma bad-2 %.2f %% median %.3f px, SGBM bad-2 %.2f %% "
      "median %.3f px\n",
      down, crop.x, crop.y, crop.width, crop.height, left.cols, left.rows, m.omma_bad2, m.omma_median,
      m.sgbm_bad2, m.sgbm_median);
  return m;
}

TEST(PanoStereoReal, AloeQuarterSizeNotWorseThanSgbm) {
  const std::filesystem::path dir = testing::opencv_samples_dir();
  if (dir.empty()) GTEST_SKIP() << "OpenCV's sample images (opencv-doc) are not installed";
  const Measured m = measure(dir, 4, {0, 0, 1, 1});
  // Measured (OMMA_STEREO_VARIANTS=1): the whole image at 1/3, 1/4, 1/5: omma bad-2 11.07 / 11.89 / 11.80 %
  // against SGBM's 13.63 / 14.31 / 14.30 % (2.4 .. 2.6 points better every time; median |error| 0.25 ..
  // 0.27 px against 0.16 .. 0.17); on 9 crops (top or bottom 60 %, right 80 %) omma - SGBM = -4.8 .. +0.7
  // points (SGBM ahead on the bottom crops only: the pot and the floor, little occlusion). Full size
  // (`omma real depth`): 14.0 % against 14.25 %. The margin 0 on the whole image leaves the measured
  // 2.4 points; the bounds on omma's own numbers leave 1.6 points and 0.08 px.
  EXPECT_LE(m.omma_bad2, m.sgbm_bad2);
  EXPECT_LT(m.omma_bad2, 13.5);
  EXPECT_LT(m.omma_median, 0.35);
  if (std::getenv("OMMA_STEREO_VARIANTS")) {  // the measurement behind the bounds above
    for (int down : {3, 4, 5})
      for (cv::Rect2d crop : {cv::Rect2d(0, 0, 1, 1), cv::Rect2d(0, 0, 1, 0.6), cv::Rect2d(0, 0.4, 1, 0.6),
                              cv::Rect2d(0.2, 0, 0.8, 1)})
        measure(dir, down, crop);
  }
}

}  // namespace
}  // namespace omma::pano
