// CLI tests for `omma isp` and `omma link` (thesis §5.1, appendix A).
#include <filesystem>
#include <fstream>
#include <random>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {
namespace fs = std::filesystem;

// A 10-bit RGGB raw frame (16-bit PNG) mosaicked from a crop of a real photo (or a gradient).
cv::Mat make_raw(int w, int h) {
  cv::Mat photo = cv::imread(data_dir() + "/louvre.jpg", cv::IMREAD_COLOR);
  cv::Mat crop;
  if (photo.empty()) {
    crop.create(h, w, CV_8UC3);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) crop.at<cv::Vec3b>(y, x) = {uint8_t(x), uint8_t(y), uint8_t(x + y)};
  } else {
    crop = photo(cv::Rect(1200, 800, w, h)).clone();
  }
  cv::Mat raw(h, w, CV_16UC1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int ch = (y % 2 == 0 && x % 2 == 0) ? 2 : (y % 2 && x % 2) ? 0 : 1;
      raw.at<uint16_t>(y, x) = uint16_t(crop.at<cv::Vec3b>(y, x)[ch] * 4);
    }
  return raw;
}

TEST(IspCli, DevelopsRawFrameAndMatchesMethodsOptions) {
  const fs::path dir = temp_dir("ispcli");
  const cv::Mat raw = make_raw(250, 250);
  cv::imwrite((dir / "cam_00_raw.png").string(), raw);
  for (const char* m : {"bilinear", "hybrid", "ah", "cc"}) {
    const fs::path out = dir / (std::string(m) + ".png");
    const RunResult r = run_omma("isp --in " + (dir / "cam_00_raw.png").string() + " --demosaic " + m +
                                 " --awb grayworld --out " + out.string() + " --json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.json()["demosaic"], m);
    const cv::Mat rgb = cv::imread(out.string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(rgb.type(), CV_8UC3);
    ASSERT_EQ(rgb.size(), cv::Size(250, 250));
    // gray world: equal channel means (within 2 %)
    const cv::Scalar mean = cv::mean(rgb);
    EXPECT_NEAR(mean[2] / mean[1], 1.0, 0.02) << m;
    EXPECT_NEAR(mean[0] / mean[1], 1.0, 0.02) << m;
  }
  fs::remove_all(dir);
}

// The simulator's raw frames (linear 10-bit RGGB) developed with --srgb match its own sRGB frames
// (cam_XX.png, rendered from the same signal without a mosaic) up to the demosaicing error.
TEST(IspCli, DevelopsSimulatorRawFrames) {
  const fs::path dir = temp_dir("ispsim");
  RunResult r = run_omma("design --method max-volume --cam-size 1x1x2 --out " + (dir / "rig.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_omma("simulate --rig " + (dir / "rig.json").string() + " --scene photo:" + data_dir() +
               "/louvre.jpg --out " + (dir / "sim").string() + " --raw --no-truth --supersample 2 --seed 3");
  if (r.exit_code != 0 && !fs::exists(data_dir() + "/louvre.jpg")) GTEST_SKIP();
  ASSERT_EQ(r.exit_code, 0) << r.err;
  double worst_cc = 99, worst_bl = 99, sum_cc = 0, sum_bl = 0;
  const int cams[] = {0, 5, 14, 20};
  for (int cam : cams) {
    char name[32];
    std::snprintf(name, sizeof name, "cam_%02d", cam);
    const fs::path raw = dir / "sim" / (std::string(name) + "_raw.png");
    const cv::Mat ref = cv::imread((dir / "sim" / (std::string(name) + ".png")).string(), cv::IMREAD_COLOR);
    ASSERT_FALSE(ref.empty());
    for (const char* m : {"bilinear", "cc"}) {
      const fs::path out = dir / (std::string(name) + "_" + m + ".png");
      r = run_omma("isp --in " + raw.string() + " --demosaic " + m + " --awb none --srgb --out " +
                   out.string());
      ASSERT_EQ(r.exit_code, 0) << r.err;
      const cv::Mat got = cv::imread(out.string(), cv::IMREAD_COLOR);
      const cv::Rect roi(8, 8, ref.cols - 16, ref.rows - 16);
      const double p = cv::PSNR(got(roi), ref(roi));
      if (std::string(m) == "cc") {
        worst_cc = std::min(worst_cc, p);
        sum_cc += p;
      } else {
        worst_bl = std::min(worst_bl, p);
        sum_bl += p;
      }
    }
  }
  std::printf(
      "simulator raw -> sRGB vs cam_XX.png: bilinear mean %.2f dB (worst %.2f), cc mean %.2f dB (worst "
      "%.2f)\n",
      sum_bl / 4, worst_bl, sum_cc / 4, worst_cc);
  EXPECT_GT(worst_cc, 29.5);
  EXPECT_GT(sum_cc, sum_bl);
  fs::remove_all(dir);
}

TEST(IspCli, FlatFieldRemovesVignetting) {
  const fs::path dir = temp_dir("ispflat");
  const int W = 250, H = 250;
  cv::Mat flat(H, W, CV_16UC1), scene(H, W, CV_16UC1);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const double r2 = (std::pow(x + 0.5 - W / 2.0, 2) + std::pow(y + 0.5 - H / 2.0, 2)) / (W * W / 4.0);
      const double fall = 1.0 / std::pow(1.0 + 0.4 * r2, 2);
      flat.at<uint16_t>(y, x) = uint16_t(950 * fall);
      scene.at<uint16_t>(y, x) = uint16_t(500 * fall);
    }
  cv::imwrite((dir / "flat.png").string(), flat);
  cv::imwrite((dir / "scene.png").string(), scene);
  auto ratio = [&](const std::string& extra) {
    const fs::path out = dir / "out.png";
    const RunResult r = run_omma("isp --in " + (dir / "scene.png").string() + " --awb none --out " +
                                 out.string() + " " + extra);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    const cv::Mat im = cv::imread(out.string(), cv::IMREAD_COLOR);
    fs::remove(out);
    return cv::mean(im(cv::Rect(4, 4, 30, 30)))[1] / cv::mean(im(cv::Rect(105, 105, 40, 40)))[1];
  };
  EXPECT_LT(ratio(""), 0.7);
  EXPECT_NEAR(ratio("--flat " + (dir / "flat.png").string()), 1.0, 0.03);
  cv::imwrite((dir / "small.png").string(), cv::Mat(100, 100, CV_16UC1, cv::Scalar(900)));
  const RunResult bad = run_omma("isp --in " + (dir / "scene.png").string() + " --flat " +
                                 (dir / "small.png").string() + " --out " + (dir / "o.png").string());
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("flat"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(dir / "o.png"));
  fs::remove_all(dir);
}

TEST(IspCli, EvalPrintsTableA1Json) {
  const fs::path dir = temp_dir("ispeval");
  cv::Mat photo = cv::imread(data_dir() + "/lake.jpg", cv::IMREAD_COLOR);
  if (photo.empty()) GTEST_SKIP();
  cv::imwrite((dir / "crop.png").string(), photo(cv::Rect(1500, 700, 400, 300)));
  const RunResult r = run_omma("isp --eval " + (dir / "crop.png").string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = r.json();
  EXPECT_EQ(j["image"], (dir / "crop.png").string());
  ASSERT_EQ(j["methods"].size(), 6u);
  for (const char* k : {"bilinear", "hybrid", "ah", "cc", "opencv_bilinear", "opencv_ea"})
    for (const char* c : {"r", "g", "b"}) {
      ASSERT_TRUE(j["methods"][k].contains(c)) << k << c;
      EXPECT_GT(j["methods"][k][c].get<double>(), 15.0);
      EXPECT_LT(j["methods"][k][c].get<double>(), 80.0);
    }
  // our bilinear is OpenCV's bilinear; the gradient methods beat it
  EXPECT_NEAR(j["methods"]["bilinear"]["r"].get<double>(), j["methods"]["opencv_bilinear"]["r"].get<double>(),
              0.011);
  EXPECT_GT(j["methods"]["cc"]["r"].get<double>(), j["methods"]["bilinear"]["r"].get<double>() + 2.0);
  fs::remove_all(dir);
}

TEST(IspCli, BadInputsFailClearlyWithoutOutput) {
  const fs::path dir = temp_dir("ispbad");
  cv::imwrite((dir / "odd.png").string(), cv::Mat(251, 250, CV_16UC1, cv::Scalar(100)));
  cv::imwrite((dir / "rgb8.png").string(), cv::Mat(250, 250, CV_8UC3, cv::Scalar::all(100)));
  cv::imwrite((dir / "deep.png").string(), cv::Mat(250, 250, CV_16UC1, cv::Scalar(4000)));
  std::ofstream(dir / "junk.png") << "not a png";
  const fs::path out = dir / "out.png";
  struct Case {
    std::string in, expect;
  };
  for (const Case& c :
       {Case{"odd.png", "even"}, Case{"rgb8.png", "16-bit single-channel"}, Case{"deep.png", "bits"},
        Case{"junk.png", "cannot read"}, Case{"missing.png", "does not exist"}}) {
    const RunResult r = run_omma("isp --in " + (dir / c.in).string() + " --out " + out.string());
    EXPECT_EQ(r.exit_code, 1) << c.in;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.in << ": " << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.in;
  }
  const RunResult m =
      run_omma("isp --in " + (dir / "odd.png").string() + " --demosaic nearest --out " + out.string());
  EXPECT_NE(m.exit_code, 0);
  EXPECT_FALSE(fs::exists(out));
  fs::remove_all(dir);
}

TEST(LinkCli, EncodeDecodeRoundTripAndDamage) {
  const fs::path dir = temp_dir("linkcli");
  const cv::Mat raw = make_raw(250, 250);
  cv::imwrite((dir / "raw.png").string(), raw);
  // clean, 2 frames
  RunResult e =
      run_omma("link encode " + (dir / "raw.png").string() + " " + (dir / "s.bin").string() + " --frames 2");
  ASSERT_EQ(e.exit_code, 0) << e.err;
  RunResult d = run_omma("link decode " + (dir / "s.bin").string() + " " + (dir / "f").string() + " --json");
  ASSERT_EQ(d.exit_code, 0) << d.err;
  auto j = d.json();
  EXPECT_EQ(j["frames"], 2);
  EXPECT_EQ(j["rows_ok"], 500);
  EXPECT_EQ(j["rows_damaged"], 0);
  EXPECT_EQ(j["bytes"].get<long>(), long(fs::file_size(dir / "s.bin")));
  EXPECT_EQ(j.size(), 5u);  // and the omma_version of every --json summary
  EXPECT_TRUE(j.contains("omma_version"));
  const cv::Mat back = cv::imread((dir / "f_001.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(back.type(), CV_16UC1);
  EXPECT_EQ(cv::norm(back, raw, cv::NORM_INF), 0.0);
  // impaired channel: damage is counted, frames survive
  e = run_omma("link encode " + (dir / "raw.png").string() + " " + (dir / "bad.bin").string() +
               " --frames 3 --flip-rate 3e-6 --drop-rate 3e-6 --seed 7");
  ASSERT_EQ(e.exit_code, 0) << e.err;
  d = run_omma("link decode " + (dir / "bad.bin").string() + " " + (dir / "g").string() + " --json");
  ASSERT_EQ(d.exit_code, 0) << d.err;
  j = d.json();
  EXPECT_EQ(j["frames"], 3);
  EXPECT_GT(j["rows_damaged"].get<long>(), 0);
  EXPECT_LT(j["rows_damaged"].get<long>(), 60);
  EXPECT_EQ(j["rows_ok"].get<long>() + j["rows_damaged"].get<long>(), 750);
  // concealed frame is close to the original (damaged rows copied from 2 rows away)
  const cv::Mat g0 = cv::imread((dir / "g_000.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(g0.empty());
  cv::Mat diff;
  cv::absdiff(g0, raw, diff);
  EXPECT_LT(cv::mean(diff)[0], 5.0);
  fs::remove_all(dir);
}

TEST(LinkCli, GarbageAndTruncatedFiles) {
  const fs::path dir = temp_dir("linkbad");
  {
    std::ofstream g(dir / "garbage.bin", std::ios::binary);
    std::mt19937 rng(1);
    for (int i = 0; i < 300000; ++i) g.put(char(rng()));
  }
  std::ofstream(dir / "empty.bin").close();
  RunResult r =
      run_omma("link decode " + (dir / "garbage.bin").string() + " " + (dir / "x").string() + " --json", 60);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no frame found"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "x_000.png"));
  r = run_omma("link decode " + (dir / "empty.bin").string() + " " + (dir / "x").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("empty"), std::string::npos) << r.err;
  r = run_omma("link decode " + (dir / "none.bin").string() + " " + (dir / "x").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("does not exist"), std::string::npos) << r.err;
  // truncated stream: the rows that arrived are kept, the rest counted as damaged
  cv::imwrite((dir / "raw.png").string(), make_raw(250, 250));
  ASSERT_EQ(run_omma("link encode " + (dir / "raw.png").string() + " " + (dir / "s.bin").string()).exit_code,
            0);
  fs::resize_file(dir / "s.bin", 100000);
  r = run_omma("link decode " + (dir / "s.bin").string() + " " + (dir / "t").string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = r.json();
  EXPECT_EQ(j["frames"], 1);
  EXPECT_EQ(j["rows_ok"].get<long>(), 100000 * 8 / 6072);  // whole rows in 100000 bytes
  EXPECT_EQ(j["rows_ok"].get<long>() + j["rows_damaged"].get<long>(), 250);
  // wrong inputs to encode
  cv::imwrite((dir / "small.png").string(), cv::Mat(10, 10, CV_16UC1, cv::Scalar(5)));
  cv::imwrite((dir / "deep.png").string(), cv::Mat(250, 250, CV_16UC1, cv::Scalar(2000)));
  cv::imwrite((dir / "rgb.png").string(), cv::Mat(250, 250, CV_8UC3, cv::Scalar::all(5)));
  for (const auto& [in, expect] : std::vector<std::pair<std::string, std::string>>{
           {"small.png", "250x250"}, {"deep.png", "bits"}, {"rgb.png", "16-bit single-channel"}}) {
    r = run_omma("link encode " + (dir / in).string() + " " + (dir / "o.bin").string());
    EXPECT_EQ(r.exit_code, 1) << in;
    EXPECT_NE(r.err.find(expect), std::string::npos) << in << ": " << r.err;
    EXPECT_FALSE(fs::exists(dir / "o.bin"));
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace omma::test
