// Tests of the demosaicing methods (eq. 5.1-5.10, A.1-A.22).
#include "omma/isp/demosaic.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

namespace omma::isp {
namespace {

const Demosaic kAll[] = {Demosaic::kBilinear, Demosaic::kHybrid, Demosaic::kAdamsHamilton,
                         Demosaic::kColourCorrelation};

cv::Mat random_raw(int w, int h, int bits, unsigned seed) {
  cv::Mat m(h, w, CV_16UC1);
  cv::RNG rng(seed);
  rng.fill(m, cv::RNG::UNIFORM, 0, 1 << bits);
  return m;
}

// A smooth-ish textured colour image (sum of sinusoids), 10-bit.
cv::Mat texture_bgr16(int w, int h) {
  cv::Mat m(h, w, CV_16UC3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double base = 500 + 300 * std::sin(0.21 * x + 0.13 * y) + 150 * std::cos(0.05 * x * y / 10.0);
      m.at<cv::Vec3w>(y, x) = {uint16_t(std::clamp(base * 0.7, 0.0, 1023.0)),
                               uint16_t(std::clamp(base, 0.0, 1023.0)),
                               uint16_t(std::clamp(base * 0.9 + 40, 0.0, 1023.0))};
    }
  return m;
}

TEST(Demosaic, ParseNames) {
  for (Demosaic m : kAll) EXPECT_EQ(parse_demosaic(demosaic_name(m)), m);
  EXPECT_THROW(parse_demosaic("nearest"), std::invalid_argument);
}

TEST(Demosaic, FastEqualsReferenceOnRandomAndTexture) {
  const cv::Mat rnd = random_raw(36, 28, 10, 1);
  const cv::Mat tex = mosaic_rggb(texture_bgr16(64, 50));
  for (Demosaic m : kAll)
    for (const cv::Mat* raw : {&rnd, &tex}) {
      const cv::Mat fast = demosaic(*raw, m, 10), ref = demosaic_reference(*raw, m, 10);
      ASSERT_EQ(fast.type(), CV_16UC3);
      EXPECT_EQ(cv::norm(fast, ref, cv::NORM_INF), 0.0) << demosaic_name(m);
      // the interleaved integer path, and the 12-bit case (no int16 planar kernel)
      EXPECT_EQ(cv::norm(demosaic_interleaved(*raw, m, 10), ref, cv::NORM_INF), 0.0) << demosaic_name(m);
      const cv::Mat raw12 = *raw * 4;
      EXPECT_EQ(cv::norm(demosaic(raw12, m, 12), demosaic_reference(raw12, m, 12), cv::NORM_INF), 0.0)
          << demosaic_name(m);
    }
  // also at the smallest size (4x4: every pixel is a border pixel)
  const cv::Mat tiny = random_raw(4, 4, 10, 2);
  for (Demosaic m : kAll)
    EXPECT_EQ(cv::norm(demosaic(tiny, m, 10), demosaic_reference(tiny, m, 10), cv::NORM_INF), 0.0);
}

TEST(Demosaic, UniformColourIsReconstructedExactly) {
  const cv::Mat img(20, 24, CV_16UC3, cv::Scalar(100, 700, 333));  // B, G, R
  const cv::Mat raw = mosaic_rggb(img);
  for (Demosaic m : kAll)
    EXPECT_EQ(cv::norm(demosaic(raw, m, 10), img, cv::NORM_INF), 0.0) << demosaic_name(m);
}

TEST(Demosaic, BilinearFollowsEquations51To510) {
  const cv::Mat raw = random_raw(12, 12, 10, 7);
  const cv::Mat out = demosaic(raw, Demosaic::kBilinear, 10);
  auto v = [&](int y, int x) { return int(raw.at<uint16_t>(y, x)); };
  auto px = [&](int y, int x) { return out.at<cv::Vec3w>(y, x); };
  // B site (5,5): R = mean of the 4 diagonals (5.1), G = mean of the cross (5.5), B itself (5.7)
  EXPECT_EQ(px(5, 5)[2], (v(4, 4) + v(4, 6) + v(6, 4) + v(6, 6) + 2) / 4);
  EXPECT_EQ(px(5, 5)[1], (v(4, 5) + v(6, 5) + v(5, 4) + v(5, 6) + 2) / 4);
  EXPECT_EQ(px(5, 5)[0], v(5, 5));
  // G on a red row (4,5): R from left/right (5.3), B from up/down (5.9)
  EXPECT_EQ(px(4, 5)[2], (v(4, 4) + v(4, 6) + 1) / 2);
  EXPECT_EQ(px(4, 5)[0], (v(3, 5) + v(5, 5) + 1) / 2);
  // G on a blue row (5,4): R from up/down (5.4), B from left/right (5.10)
  EXPECT_EQ(px(5, 4)[2], (v(4, 4) + v(6, 4) + 1) / 2);
  EXPECT_EQ(px(5, 4)[0], (v(5, 3) + v(5, 5) + 1) / 2);
  // R site (4,4): B = mean of diagonals (5.8)
  EXPECT_EQ(px(4, 4)[0], (v(3, 3) + v(3, 5) + v(5, 3) + v(5, 5) + 2) / 4);
  // Mirrored border at (0,0): the R site's "up" neighbour is row 1 (reflect-101, no wrap-around)
  EXPECT_EQ(px(0, 0)[1], (2 * v(1, 0) + 2 * v(0, 1) + 2) / 4);
  EXPECT_EQ(px(0, 0)[0], (4 * v(1, 1) + 2) / 4);
}

TEST(Demosaic, HybridGainsAreAlphaBetaGamma) {
  // A raw frame that is zero except one centre sample: the responses are the filter taps x 16.
  for (int cy : {8, 9})
    for (int cx : {8, 9}) {
      cv::Mat raw(18, 18, CV_16UC1, cv::Scalar(0));
      raw.at<uint16_t>(cy, cx) = 256;
      const cv::Mat out = demosaic(raw, Demosaic::kHybrid, 10);
      const auto c = out.at<cv::Vec3w>(cy, cx);
      const bool r_site = cy % 2 == 0 && cx % 2 == 0, b_site = cy % 2 && cx % 2;
      if (r_site || b_site) {
        // (A.19)-(A.20): G = alpha * 256 = 128 (alpha = 1/2); (A.22): other chroma = gamma * 256 = 192
        EXPECT_EQ(c[1], 128);
        EXPECT_EQ(r_site ? c[0] : c[2], 192);
      } else {
        // (A.21): R and B at a green site = beta * 256 = 160 (beta = 5/8)
        EXPECT_EQ(c[0], 160);
        EXPECT_EQ(c[2], 160);
      }
    }
}

TEST(Demosaic, NoWrapAroundAtBorders) {
  // Left half dark, right half bright: the left column must not see the right edge.
  cv::Mat img(16, 16, CV_16UC3, cv::Scalar::all(50));
  img(cv::Rect(8, 0, 8, 16)).setTo(cv::Scalar::all(1000));
  const cv::Mat raw = mosaic_rggb(img);
  for (Demosaic m : kAll) {
    const cv::Mat out = demosaic(raw, m, 10);
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 3; ++x)
        for (int c = 0; c < 3; ++c) EXPECT_EQ(out.at<cv::Vec3w>(y, x)[c], 50) << demosaic_name(m);
  }
}

TEST(Demosaic, GradientMethodsBeatBilinearOnEdges) {
  // A sharp diagonal-free step pattern (vertical stripes of period 6): AH and CC interpolate along
  // the stripes and should be far more accurate than bilinear.
  cv::Mat img(64, 64, CV_16UC3);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x)
      img.at<cv::Vec3w>(y, x) = ((x / 3) % 2) ? cv::Vec3w(800, 900, 850) : cv::Vec3w(100, 150, 120);
  const cv::Mat raw = mosaic_rggb(img);
  auto err = [&](Demosaic m) {
    cv::Mat d;
    cv::absdiff(demosaic(raw, m, 10)(cv::Rect(4, 4, 56, 56)), img(cv::Rect(4, 4, 56, 56)), d);
    return cv::sum(d)[1] / (56.0 * 56.0);  // mean abs error on green
  };
  EXPECT_LT(err(Demosaic::kAdamsHamilton), 0.3 * err(Demosaic::kBilinear));
  EXPECT_LE(err(Demosaic::kColourCorrelation), err(Demosaic::kAdamsHamilton));
}

TEST(Demosaic, OpenCvCodeMatchesOurRggbLayout) {
  // A pure red image mosaicked as RGGB: with the right OpenCV code the interior comes back red.
  const cv::Mat img(32, 32, CV_8UC3, cv::Scalar(10, 60, 230));  // B, G, R
  const cv::Mat raw16 = mosaic_rggb(img);
  EXPECT_EQ(raw16.at<uint16_t>(0, 0), 230);  // (0,0) = R
  EXPECT_EQ(raw16.at<uint16_t>(0, 1), 60);
  EXPECT_EQ(raw16.at<uint16_t>(1, 0), 60);
  EXPECT_EQ(raw16.at<uint16_t>(1, 1), 10);  // (1,1) = B
  cv::Mat raw8;
  raw16.convertTo(raw8, CV_8U);
  for (int code : {opencv_bayer_code_bilinear(), opencv_bayer_code_ea()}) {
    cv::Mat out;
    cv::cvtColor(raw8, out, code);
    const cv::Vec3b c = out.at<cv::Vec3b>(16, 16);
    EXPECT_EQ(c, cv::Vec3b(10, 60, 230)) << code;
  }
  // The other naming (RG) swaps red and blue: the check above can fail.
  cv::Mat wrong;
  cv::cvtColor(raw8, wrong, cv::COLOR_BayerRG2BGR);
  EXPECT_EQ(wrong.at<cv::Vec3b>(16, 16), cv::Vec3b(230, 60, 10));
}

TEST(Demosaic, RejectsBadFrames) {
  EXPECT_THROW(demosaic(cv::Mat(10, 11, CV_16UC1, cv::Scalar(0)), Demosaic::kHybrid, 10),
               std::invalid_argument);
  EXPECT_THROW(demosaic(cv::Mat(2, 10, CV_16UC1, cv::Scalar(0)), Demosaic::kHybrid, 10),
               std::invalid_argument);
  EXPECT_THROW(demosaic(cv::Mat(10, 10, CV_16UC3, cv::Scalar::all(0)), Demosaic::kHybrid, 10),
               std::invalid_argument);
  EXPECT_THROW(demosaic(cv::Mat(10, 10, CV_16UC1, cv::Scalar(1024)), Demosaic::kAdamsHamilton, 10),
               std::invalid_argument);
  EXPECT_THROW(demosaic_reference(cv::Mat(9, 10, CV_16UC1, cv::Scalar(0)), Demosaic::kBilinear, 10),
               std::invalid_argument);
}

}  // namespace
}  // namespace omma::isp
