// Photometric correction (photometric.h): the engine's table path against the double-precision
// reference, the correction inverting the model exactly, and the model as the ISP's flat gain.
#include "omma/isp/photometric.h"

#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "omma/core/srgb.h"
#include "omma/isp/isp.h"

namespace omma::isp {
namespace {

Photometric test_model() {
  Photometric p;
  p.vignetting = {-0.55, 0.12, -0.03};
  p.center_px = Vec2(3.5, -2);
  p.gains = {0.91, 1.04, 1.09};
  return p;
}

TEST(PhotometricCorrection, TableMatchesReferenceWithinOneStep) {
  const int W = 97, H = 64;
  cv::Mat frame(H, W, CV_8UC3);
  cv::RNG rng(5);
  rng.fill(frame, cv::RNG::UNIFORM, 0, 256);
  const Photometric p = test_model();
  const cv::Mat ref = correct_photometric_reference(frame, p);
  cv::Mat fast;
  PhotometricTable(p, W, H).apply(frame, fast);
  cv::Mat diff;
  cv::absdiff(ref, fast, diff);
  double mx = 0;
  cv::minMaxLoc(diff.reshape(1), nullptr, &mx);
  EXPECT_LE(mx, 1.0);
  EXPECT_LT(cv::mean(diff.reshape(1))[0], 0.05);  // off by one only at rounding ties
  // In place gives the same.
  cv::Mat inplace = frame.clone();
  PhotometricTable(p, W, H).apply(inplace, inplace);
  EXPECT_EQ(cv::norm(inplace, fast, cv::NORM_INF), 0);
}

TEST(PhotometricCorrection, InvertsTheModelInLinearLight) {
  // A frame made by the model from a known linear radiance: the correction gives the radiance back.
  const int W = 80, H = 60;
  const Photometric p = test_model();
  cv::Mat radiance(H, W, CV_32FC3), frame16(H, W, CV_16UC3), truth16(H, W, CV_16UC3);
  cv::RNG rng(9);
  for (int r = 0; r < H; ++r)
    for (int c = 0; c < W; ++c)
      for (int k = 0; k < 3; ++k) {
        const double l = rng.uniform(0.02, 0.8);
        const double v = vignetting_falloff(p, W, H, c + 0.5, r + 0.5);
        frame16.at<cv::Vec3w>(r, c)[k] =
            uint16_t(std::lround(65535 * linear_to_srgb(float(l * p.gains[k] * v))));
        truth16.at<cv::Vec3w>(r, c)[k] = uint16_t(std::lround(65535 * linear_to_srgb(float(l))));
      }
  const cv::Mat back = correct_photometric_reference(frame16, p);
  EXPECT_LE(cv::norm(back, truth16, cv::NORM_INF), 40.0);  // float sRGB round trip in 16 bits
}

TEST(PhotometricCorrection, FramesWithoutModelUntouchedAndBadInput) {
  Rig rig;
  RigCamera a, b;
  a.id = 0, b.id = 1;
  a.in.width = b.in.width = 50;
  a.in.height = b.in.height = 40;
  a.photometric = test_model();
  rig.cameras = {a, b};
  cv::Mat f0(40, 50, CV_8UC3, cv::Scalar(100, 120, 140)), f1 = f0.clone();
  const auto out = correct_frames(rig, {f0, f1});
  EXPECT_EQ(out[1].data, f1.data);  // shared, unchanged
  EXPECT_GT(cv::norm(out[0], f0, cv::NORM_INF), 0);
  EXPECT_THROW(correct_frames(rig, {f0}), std::invalid_argument);
  cv::Mat wrong(41, 50, CV_8UC3);
  cv::Mat o;
  EXPECT_THROW(PhotometricTable(test_model(), 50, 40).apply(wrong, o), std::invalid_argument);
  Photometric bad = test_model();
  bad.gains[0] = 0;
  EXPECT_THROW(PhotometricTable(bad, 50, 40), std::invalid_argument);
}

TEST(PhotometricCorrection, ModelAsIspFlatGainUndoesVignettingAndGains) {
  // A raw mosaic of a uniform grey seen through the model: developed with the model's flat gain
  // and no white balance it is uniform and neutral again.
  const int W = 64, H = 48, bits = 10;
  const Photometric p = test_model();
  cv::Mat raw(H, W, CV_16UC1);
  const double level = 500;
  for (int r = 0; r < H; ++r)
    for (int c = 0; c < W; ++c) {
      const int k = (r % 2 == 0) ? (c % 2 == 0 ? 2 : 1) : (c % 2 == 0 ? 1 : 0);
      raw.at<uint16_t>(r, c) =
          uint16_t(std::lround(level * p.gains[k] * vignetting_falloff(p, W, H, c + 0.5, r + 0.5)));
    }
  IspOptions o;
  o.bits = bits;
  o.awb = Awb::kNone;
  o.demosaic = Demosaic::kBilinear;
  o.flat_gain = flat_gain_from_model(p, W, H);
  const cv::Mat out = develop(raw, o);  // linear MSBs: 500 >> 2 = 125
  cv::Mat inner = out(cv::Rect(2, 2, W - 4, H - 4));
  double lo = 0, hi = 0;
  cv::minMaxLoc(inner.reshape(1), &lo, &hi);
  EXPECT_GE(lo, 123);
  EXPECT_LE(hi, 126);
}

}  // namespace
}  // namespace omma::isp
