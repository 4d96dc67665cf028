// Tests of the ISP pipeline (develop) and the Table A.1 ranking on real photographs.
#include "omma/isp/isp.h"

#include <cstdio>
#include <filesystem>
#include <random>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "omma/testing/expect.h"

namespace omma::isp {
namespace {

cv::Mat random_raw(int w, int h, int bits, unsigned seed) {
  cv::Mat m(h, w, CV_16UC1);
  cv::RNG rng(seed);
  rng.fill(m, cv::RNG::UNIFORM, 0, 1 << bits);
  return m;
}

cv::Mat photo_crop(const std::string& name, cv::Rect roi) {
  const std::string path = std::string(OMMA_DATA_DIR) + "/" + name;
  const cv::Mat im = cv::imread(path, cv::IMREAD_COLOR);
  if (im.empty()) return {};
  return im(roi & cv::Rect(0, 0, im.cols, im.rows)).clone();
}

// A raw 10-bit frame from a real photograph: mosaicked, scaled 8 -> 10 bits, with a colour cast.
cv::Mat raw_from_photo(const cv::Mat& bgr8, double cast_r, double cast_b) {
  cv::Mat f;
  bgr8.convertTo(f, CV_32FC3, 4.0);
  std::vector<cv::Mat> ch;
  cv::split(f, ch);
  ch[0] *= cast_b;
  ch[2] *= cast_r;
  cv::merge(ch, f);
  cv::Mat u16;
  f.convertTo(u16, CV_16UC3);
  cv::min(u16, cv::Scalar::all(1023), u16);
  return mosaic_rggb(u16);
}

TEST(Isp, DevelopFastEqualsReferenceAllOptions) {
  const cv::Mat raw = random_raw(40, 26, 10, 3);
  cv::Mat flat = random_raw(40, 26, 10, 4) / 4 + 700;  // a noisy flat field
  for (Demosaic m :
       {Demosaic::kBilinear, Demosaic::kHybrid, Demosaic::kAdamsHamilton, Demosaic::kColourCorrelation})
    for (Awb a : {Awb::kNone, Awb::kGrayWorld, Awb::kWhitePatch})
      for (bool with_flat : {false, true}) {
        IspOptions o;
        o.srgb = with_flat;  // both output encodings
        o.demosaic = m;
        o.awb = a;
        if (with_flat) o.flat_gain = flat_field_gain(flat);
        const cv::Mat fast = develop(raw, o), ref = develop_reference(raw, o);
        ASSERT_EQ(fast.type(), CV_8UC3);
        EXPECT_EQ(cv::norm(fast, ref, cv::NORM_INF), 0.0)
            << demosaic_name(m) << " " << awb_name(a) << " flat " << with_flat;
      }
}

TEST(Isp, DevelopRemovesColourCastOnRealPhoto) {
  const cv::Mat photo = photo_crop("louvre.jpg", {1024, 768, 250, 250});
  if (photo.empty()) GTEST_SKIP() << "no photo in " << OMMA_DATA_DIR;
  // Gray world of the original photo, to know its true R/G and B/G balance.
  const cv::Scalar m0 = cv::mean(photo);
  const cv::Mat raw = raw_from_photo(photo(cv::Rect(0, 0, 250, 250)), 1.6, 0.6);  // warm cast
  IspOptions o;
  o.awb = Awb::kNone;
  const cv::Scalar cast = cv::mean(develop(raw, o));
  o.awb = Awb::kGrayWorld;
  const cv::Scalar gw = cv::mean(develop(raw, o));
  // Without white balance the cast is there: R/G up, B/G down.
  EXPECT_GT(cast[2] / cast[1], 1.3 * m0[2] / m0[1]);
  EXPECT_LT(cast[0] / cast[1], 0.8 * m0[0] / m0[1]);
  // Gray world (A.26)-(A.30): equal channel means within 2 %.
  EXPECT_NEAR(gw[2] / gw[1], 1.0, 0.02);
  EXPECT_NEAR(gw[0] / gw[1], 1.0, 0.02);
}

TEST(Isp, VignettingCorrectionFlattensAFlatField) {
  // A white target seen through a lens with cos^4-like falloff, 10-bit, with noise.
  const int W = 250, H = 250;
  cv::Mat flat(H, W, CV_16UC1), scene(H, W, CV_16UC1);
  cv::RNG rng(5);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const double r2 = (std::pow(x + 0.5 - W / 2.0, 2) + std::pow(y + 0.5 - H / 2.0, 2)) / (W * W / 4.0);
      const double fall = 1.0 / std::pow(1.0 + 0.35 * r2, 2);
      flat.at<uint16_t>(y, x) = uint16_t(std::clamp(900 * fall + rng.gaussian(6), 0.0, 1023.0));
      scene.at<uint16_t>(y, x) = uint16_t(std::clamp(600 * fall + rng.gaussian(6), 0.0, 1023.0));
    }
  IspOptions o;
  o.demosaic = Demosaic::kBilinear;
  o.awb = Awb::kNone;
  const cv::Mat before = develop(scene, o);
  o.flat_gain = flat_field_gain(flat);
  const cv::Mat after = develop(scene, o);
  auto corner_to_centre = [](const cv::Mat& im) {
    const double c = cv::mean(im(cv::Rect(105, 105, 40, 40)))[1];
    const double k = cv::mean(im(cv::Rect(2, 2, 30, 30)))[1];
    return k / c;
  };
  EXPECT_LT(corner_to_centre(before), 0.75);
  EXPECT_NEAR(corner_to_centre(after), 1.0, 0.03);
}

TEST(Isp, BadInputGivesClearErrors) {
  IspOptions o;
  EXPECT_THROW(develop(cv::Mat(), o), std::invalid_argument);
  EXPECT_THROW(develop(cv::Mat(250, 251, CV_16UC1, cv::Scalar(10)), o), std::invalid_argument);
  EXPECT_THROW(develop(cv::Mat(251, 250, CV_16UC1, cv::Scalar(10)), o), std::invalid_argument);
  EXPECT_THROW(develop(cv::Mat(2, 2, CV_16UC1, cv::Scalar(10)), o), std::invalid_argument);
  EXPECT_THROW(develop(cv::Mat(8, 8, CV_16UC3, cv::Scalar::all(10)), o), std::invalid_argument);
  EXPECT_THROW(develop(cv::Mat(8, 8, CV_32FC1, cv::Scalar(10)), o), std::invalid_argument);
  try {
    develop(cv::Mat(8, 8, CV_16UC1, cv::Scalar(4000)), o);  // 12-bit values in a 10-bit pipeline
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("bits"), std::string::npos) << e.what();
  }
  o.flat_gain = cv::Mat(10, 10, CV_16UC1, cv::Scalar(4096));
  EXPECT_THROW(develop(cv::Mat(8, 8, CV_16UC1, cv::Scalar(10)), o), std::invalid_argument);
}

TEST(Isp, DevelopAllMatchesDevelop) {
  std::vector<cv::Mat> raws;
  for (unsigned i = 0; i < 6; ++i) raws.push_back(random_raw(32, 24, 10, 10 + i));
  IspOptions o;
  o.demosaic = Demosaic::kColourCorrelation;
  const auto all = develop_all(raws, o);
  ASSERT_EQ(all.size(), raws.size());
  for (size_t i = 0; i < raws.size(); ++i)
    EXPECT_EQ(cv::norm(all[i], develop(raws[i], o), cv::NORM_INF), 0.0);
}

TEST(Isp, OutputTables) {
  const auto lin = output_table(10, false), srgb = output_table(10, true);
  ASSERT_EQ(lin.size(), 1024u);
  EXPECT_EQ(lin[1023], 255);
  EXPECT_EQ(lin[4], 1);
  EXPECT_EQ(srgb[0], 0);
  EXPECT_EQ(srgb[1023], 255);
  EXPECT_EQ(srgb[220], 128);  // linear 0.215 -> sRGB 0.5
}

TEST(Isp, PsnrOfKnownError) {
  cv::Mat a(40, 40, CV_8UC3, cv::Scalar(100, 100, 100)), b = a.clone();
  b.setTo(cv::Scalar(100, 110, 101));  // G off by 10, R off by 1
  const ChannelPsnr p = psnr_per_channel(b, a, 8);
  EXPECT_NEAR(p.g, 10 * std::log10(255.0 * 255.0 / 100.0), 1e-9);  // 28.13 dB
  EXPECT_NEAR(p.r, 10 * std::log10(255.0 * 255.0), 1e-9);          // 48.13 dB
  EXPECT_EQ(p.b, 99.0);
}

// Table A.1 on real photographs: crops of the shared 360-degree photos (and, when installed, a
// photograph from Debian's hugin-data). Averages over the crops, per channel.
TEST(IspTableA1, RankingOnRealPhotos) {
  std::vector<cv::Mat> crops;
  for (const char* name : {"louvre.jpg", "lake.jpg"})
    for (cv::Rect r : {cv::Rect(512, 640, 512, 512), cv::Rect(1536, 700, 512, 512),
                       cv::Rect(2560, 760, 512, 512), cv::Rect(3400, 900, 512, 512)}) {
      cv::Mat c = photo_crop(name, r);
      if (!c.empty()) crops.push_back(c);
    }
  const std::string hugin = "/usr/share/hugin/xrc/data/help_en_EN/800px-C_Marchi-GrandCentral-adj.jpg";
  if (std::filesystem::exists(hugin)) crops.push_back(cv::imread(hugin, cv::IMREAD_COLOR));
  if (crops.size() < 4) GTEST_SKIP() << "no photos in " << OMMA_DATA_DIR;
  std::map<std::string, ChannelPsnr> avg;
  for (const cv::Mat& c : crops) {
    const auto res = evaluate_demosaic(c, 8);
    for (const auto& [k, v] : res) {
      avg[k].r += v.r / double(crops.size());
      avg[k].g += v.g / double(crops.size());
      avg[k].b += v.b / double(crops.size());
    }
  }
  std::printf("Table A.1 on %zu real crops (mean PSNR dB, 8-px border left out)\n", crops.size());
  for (const char* k : {"bilinear", "hybrid", "ah", "cc", "opencv_bilinear", "opencv_ea"})
    std::printf("  %-16s R %6.2f  G %6.2f  B %6.2f\n", k, avg[k].r, avg[k].g, avg[k].b);
  const ChannelPsnr bl = avg["bilinear"], hy = avg["hybrid"], ah = avg["ah"], cc = avg["cc"];
  const ChannelPsnr cvbl = avg["opencv_bilinear"];
  // cc >= ah > hybrid > bilinear on red and blue
  EXPECT_GE(cc.r, ah.r);
  EXPECT_GE(cc.b, ah.b);
  EXPECT_GT(ah.r, hy.r);
  EXPECT_GT(ah.b, hy.b);
  EXPECT_GT(hy.r, bl.r);
  EXPECT_GT(hy.b, bl.b);
  // and on green (on these crops ah beats hybrid on green by only ~0.15 dB; on the whole louvre
  // photo and the hugin photo alone the hybrid wins on green, see `omma isp --eval`)
  EXPECT_GE(cc.g, ah.g);
  EXPECT_GT(ah.g, hy.g);
  EXPECT_GT(hy.g, bl.g);
  // ah and cc at least 2 dB above OpenCV's bilinear on red and blue
  EXPECT_GE(ah.r, cvbl.r + 2.0);
  EXPECT_GE(ah.b, cvbl.b + 2.0);
  EXPECT_GE(cc.r, cvbl.r + 2.0);
  EXPECT_GE(cc.b, cvbl.b + 2.0);
  // Our bilinear is eq. 5.1-5.10, the same filter as OpenCV's: equal PSNR to 0.01 dB.
  EXPECT_NEAR(bl.r, cvbl.r, 0.01);
  EXPECT_NEAR(bl.g, cvbl.g, 0.01);
  EXPECT_NEAR(bl.b, cvbl.b, 0.01);
}

using testing::refusal;

TEST(Isp, OptionsRefuseBadValues) {
  IspOptions o;
  EXPECT_TRUE(o.IsValid());
  o.bits = 17;
  EXPECT_FALSE(o.IsValid());
  o.bits = 7;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(refusal([&] { develop(cv::Mat(8, 8, CV_16UC1, cv::Scalar(10)), o); }), why);
  o = {};
  o.flat_gain = cv::Mat(8, 8, CV_32FC1, cv::Scalar(1));
  EXPECT_FALSE(o.IsValid());
}

}  // namespace
}  // namespace omma::isp
