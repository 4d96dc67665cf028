// Tests of white balance (eq. A.23-A.38), flat-field gains and RGB565 (§5.2).
#include "omma/isp/color.h"

#include <gtest/gtest.h>

namespace omma::isp {
namespace {

TEST(WhiteBalance, GrayWorldGainsAreMeanRatios) {
  cv::Mat img(10, 10, CV_16UC3, cv::Scalar(200, 400, 800));  // B, G, R
  const WbGains g = gray_world_gains(img);
  EXPECT_EQ(g.r_q12, 2048);  // alpha = 400 / 800 (A.26)
  EXPECT_EQ(g.b_q12, 8192);  // beta = 400 / 200 (A.27)
  apply_gains(img, g, 1023);
  EXPECT_EQ(img.at<cv::Vec3w>(3, 3), cv::Vec3w(400, 400, 400));
}

TEST(WhiteBalance, WhitePatchIgnoresSinglePixelOutliers) {
  // A scene with a bluish-white patch of 6x6 and one hot red pixel: the 4x4 low-pass keeps the
  // hot pixel from setting Rmax (A.31).
  cv::Mat img(40, 40, CV_16UC3, cv::Scalar(100, 100, 100));
  img(cv::Rect(20, 20, 6, 6)).setTo(cv::Scalar(800, 640, 500));
  img.at<cv::Vec3w>(5, 5) = {100, 100, 1023};
  const WbGains g = white_patch_gains(img);
  EXPECT_NEAR(g.r(), 640.0 / 500.0, 1e-3);  // (A.34)
  EXPECT_NEAR(g.b(), 640.0 / 800.0, 1e-3);  // (A.35)
  const WbGains ref = white_patch_gains_reference(img);
  EXPECT_EQ(g.r_q12, ref.r_q12);
  EXPECT_EQ(g.b_q12, ref.b_q12);
}

TEST(WhiteBalance, WhitePatchFastEqualsReferenceOnRandom) {
  cv::Mat img(23, 31, CV_16UC3);
  cv::RNG(9).fill(img, cv::RNG::UNIFORM, 0, 1024);
  const WbGains a = white_patch_gains(img), b = white_patch_gains_reference(img);
  EXPECT_EQ(a.r_q12, b.r_q12);
  EXPECT_EQ(a.b_q12, b.b_q12);
}

TEST(WhiteBalance, ZeroChannelsGiveUnitGains) {
  const cv::Mat black(8, 8, CV_16UC3, cv::Scalar::all(0));
  EXPECT_EQ(gray_world_gains(black).r_q12, 4096);
  EXPECT_EQ(white_patch_gains(black).b_q12, 4096);
  EXPECT_THROW(parse_awb("auto"), std::invalid_argument);
  EXPECT_EQ(parse_awb("whitepatch"), Awb::kWhitePatch);
}

TEST(FlatField, GainInvertsAFalloff) {
  cv::Mat flat(40, 40, CV_16UC1);
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 40; ++x) flat.at<uint16_t>(y, x) = uint16_t(x < 20 ? 800 : 400);
  const cv::Mat g = flat_field_gain(flat);
  EXPECT_NEAR(g.at<uint16_t>(20, 36) / 4096.0, 2.0, 0.01);
  EXPECT_NEAR(g.at<uint16_t>(20, 2) / 4096.0, 1.0, 0.01);
  const cv::Mat out = apply_flat_field(flat, g, 1023);
  EXPECT_NEAR(out.at<uint16_t>(7, 37), 800, 8);
  EXPECT_THROW(flat_field_gain(cv::Mat(5, 6, CV_16UC1)), std::invalid_argument);
  EXPECT_THROW(apply_flat_field(flat, cv::Mat(4, 4, CV_16UC1), 1023), std::invalid_argument);
}

TEST(Rgb565, PackLayoutAndRoundTripError) {
  cv::Mat px(1, 1, CV_8UC3, cv::Scalar(0x12, 0x34, 0xF8));  // B, G, R
  const cv::Mat p = pack_rgb565(px);
  EXPECT_EQ(p.at<uint16_t>(0, 0), (0xF8 >> 3) << 11 | (0x34 >> 2) << 5 | (0x12 >> 3));
  cv::Mat all(256, 256, CV_8UC3);
  for (int y = 0; y < 256; ++y)
    for (int x = 0; x < 256; ++x) all.at<cv::Vec3b>(y, x) = {uint8_t(x), uint8_t(y), uint8_t(255 - x)};
  const cv::Mat back = unpack_rgb565(pack_rgb565(all));
  int max_rb = 0, max_g = 0;
  for (int y = 0; y < 256; ++y)
    for (int x = 0; x < 256; ++x) {
      const cv::Vec3b a = all.at<cv::Vec3b>(y, x), b = back.at<cv::Vec3b>(y, x);
      max_rb = std::max({max_rb, std::abs(a[0] - b[0]), std::abs(a[2] - b[2])});
      max_g = std::max(max_g, std::abs(a[1] - b[1]));
    }
  EXPECT_LE(max_rb, 7);
  EXPECT_LE(max_g, 3);
  EXPECT_EQ(unpack_rgb565(pack_rgb565(cv::Mat(1, 1, CV_8UC3, cv::Scalar::all(255)))).at<cv::Vec3b>(0, 0),
            cv::Vec3b(255, 255, 255));
  EXPECT_THROW(pack_rgb565(cv::Mat(2, 2, CV_16UC3)), std::invalid_argument);
}

}  // namespace
}  // namespace omma::isp
