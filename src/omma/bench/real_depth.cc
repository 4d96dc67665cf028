// `omma real depth`: the depth sweep (pano/plane_sweep.h) on the rectified Middlebury Aloe pair as a
// two-camera rig (rectified_pair_rig), on the left camera's own pixel grid with the observer at its
// centre, and the same on the right camera's for the left-right check (rectified_disparity), against the
// pair's true disparity, beside OpenCV's StereoSGBM in the same run. omma.left_only_*: the left sweep
// alone; omma.consistent_pct: the evaluated pixels that pass the left-right check.
//
// Truth. aloeGT.png is 8-bit gray, 0 = unknown (3.5 % of the pixels), else the disparity in pixels of
// these 1282 x 1110 images (43 .. 211): checked against StereoSGBM, whose valid disparities agree with it
// at scale 1 (median |error| 0.25 px), while scales 1/3, 1/2 and 2 leave over 99 % of them off by > 2 px.
//
// Evaluation. Pixels with a known truth, outside the left border band x < d_lo + n_d (StereoSGBM's
// minDisparity + numDisparities: SGBM computes nothing there, and for most of it the right image holds
// no match for part of the range). bad-2: the share of them whose estimate is missing or off by more
// than 2 px (the Middlebury measure at full size); median: of |error| where an estimate exists;
// coverage: the share with an estimate. omma's sweep always gives one (the fallback, plane_sweep.h);
// SGBM marks pixels invalid (uniqueness, left-right check, speckle filter); its bad-2 over its valid
// pixels only is reported beside.
//
// Quick (RealOptions::quick): both images and the truth at a quarter of the size (cv::INTER_AREA; the
// truth averaged over blocks whose pixels are all known, disparities scaled by the width ratio).
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <tbb/global_control.h>

#include "omma/bench/real.h"
#include "omma/core/io.h"
#include "omma/pano/plane_sweep.h"

namespace omma::bench {
namespace {

namespace fs = std::filesystem;

// Middlebury 2006's published geometry of its full-size images (focal 3740 px, baseline 160 mm). Only
// the depth scale depends on them: any focal and baseline describe the same disparities.
constexpr double kFocalPx = 3740, kBaselineMm = 160;
constexpr double kBadPx = 2;  // bad-2

struct AloePair {
  cv::Mat left, right;  // BGR 8-bit
  cv::Mat truth;        // CV_32FC1 disparity px, 0 = unknown
  double scale = 1;     // of the full-size images (width ratio)
};

AloePair load_aloe(const fs::path& dir, bool quick) {
  AloePair p;
  p.left = read_image(dir / "aloeL.jpg", cv::IMREAD_COLOR);
  p.right = read_image(dir / "aloeR.jpg", cv::IMREAD_COLOR);
  const cv::Mat gt = read_image(dir / "aloeGT.png", cv::IMREAD_GRAYSCALE);
  if (p.left.size() != p.right.size() || p.left.size() != gt.size())
    throw std::runtime_error(
        fmt::format("{}: aloeL.jpg, aloeR.jpg and aloeGT.png differ in size", dir.string()));
  gt.convertTo(p.truth, CV_32F);
  if (!quick) return p;
  const cv::Size small((p.left.cols + 2) / 4, (p.left.rows + 2) / 4);
  p.scale = double(small.width) / p.left.cols;
  cv::resize(p.left, p.left, small, 0, 0, cv::INTER_AREA);
  cv::resize(p.right, p.right, small, 0, 0, cv::INTER_AREA);
  cv::Mat known = p.truth > 0, known_f, sum, frac;
  known.convertTo(known_f, CV_32F, 1 / 255.0);
  cv::resize(p.truth, sum, small, 0, 0, cv::INTER_AREA);
  cv::resize(known_f, frac, small, 0, 0, cv::INTER_AREA);
  p.truth = cv::Mat(small, CV_32FC1, cv::Scalar(0));
  for (int r = 0; r < small.height; ++r)
    for (int c = 0; c < small.width; ++c)
      if (frac.at<float>(r, c) > 0.999f) p.truth.at<float>(r, c) = float(sum.at<float>(r, c) * p.scale);
  return p;
}

struct Score {
  double bad2_pct = 0, median_px = 0, coverage_pct = 0, bad2_valid_pct = 0;
};

// disparity: CV_32FC1 px, valid: CV_8UC1 (non-zero = an estimate), mask: the evaluated pixels.
Score score(const cv::Mat& disparity, const cv::Mat& valid, const cv::Mat& truth, const cv::Mat& mask) {
  long n = 0, bad = 0, nvalid = 0, bad_valid = 0;
  std::vector<float> err;
  for (int r = 0; r < truth.rows; ++r)
    for (int c = 0; c < truth.cols; ++c) {
      if (!mask.at<uint8_t>(r, c)) continue;
      ++n;
      if (!valid.at<uint8_t>(r, c)) {
        ++bad;
        continue;
      }
      const float e = std::abs(disparity.at<float>(r, c) - truth.at<float>(r, c));
      err.push_back(e);
      ++nvalid;
      if (e > kBadPx) {
        ++bad;
        ++bad_valid;
      }
    }
  Score s;
  if (n == 0) throw std::runtime_error("real depth: no pixel to evaluate");
  s.bad2_pct = 100.0 * bad / n;
  s.coverage_pct = 100.0 * nvalid / n;
  s.bad2_valid_pct = nvalid ? 100.0 * bad_valid / nvalid : 100;
  if (!err.empty()) {
    std::nth_element(err.begin(), err.begin() + err.size() / 2, err.end());
    s.median_px = err[err.size() / 2];
  }
  return s;
}

// A legend bar (turbo from lo to hi, labelled in px) under `img`, with a title above it.
cv::Mat with_legend(const cv::Mat& img, double lo, double hi, const std::string& title, bool colour_bar) {
  const int bar = 18, pad = 6, text_h = 22, width = img.cols;
  const double font = std::max(0.4, width / 1600.0);
  cv::Mat out(img.rows + bar + 2 * text_h + 2 * pad, width, CV_8UC3, cv::Scalar(255, 255, 255));
  img.copyTo(out(cv::Rect(0, 0, width, img.rows)));
  const int y0 = img.rows + pad;
  if (colour_bar) {
    cv::Mat ramp(1, width, CV_8UC1);
    for (int c = 0; c < width; ++c) ramp.at<uint8_t>(0, c) = uint8_t(std::lround(255.0 * c / (width - 1)));
    cv::Mat colour;
    cv::applyColorMap(ramp, colour, cv::COLORMAP_TURBO);
    cv::resize(colour, out(cv::Rect(0, y0, width, bar)), cv::Size(width, bar), 0, 0, cv::INTER_NEAREST);
    for (int t = 0; t <= 4; ++t) {
      const double v = lo + (hi - lo) * t / 4;
      const int x = std::clamp(int(std::lround((width - 1) * t / 4.0)), 0, width - 1);
      cv::line(out, {x, y0}, {x, y0 + bar}, cv::Scalar(0, 0, 0), 1);
      const std::string label = fmt::format("{:.0f} px", v);
      int base = 0;
      const cv::Size ts = cv::getTextSize(label, cv::FONT_HERSHEY_SIMPLEX, font, 1, &base);
      const int tx = std::clamp(x - ts.width / 2, 0, width - ts.width);
      cv::putText(out, label, {tx, y0 + bar + text_h - 4}, cv::FONT_HERSHEY_SIMPLEX, font,
                  cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    }
  }
  cv::putText(out, title, {4, out.rows - pad}, cv::FONT_HERSHEY_SIMPLEX, font, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  return out;
}

// Disparity in turbo over [lo, hi] (near = red), black where there is no value.
cv::Mat disparity_picture(const cv::Mat& d, const cv::Mat& valid, double lo, double hi,
                          const std::string& title) {
  cv::Mat g(d.size(), CV_8UC1);
  for (int r = 0; r < d.rows; ++r)
    for (int c = 0; c < d.cols; ++c)
      g.at<uint8_t>(r, c) = cv::saturate_cast<uint8_t>(255.0 * (d.at<float>(r, c) - lo) / (hi - lo));
  cv::Mat colour;
  cv::applyColorMap(g, colour, cv::COLORMAP_TURBO);
  colour.setTo(cv::Scalar(0, 0, 0), valid == 0);
  return with_legend(colour, lo, hi, title, true);
}

// The left image, dimmed, with the evaluated pixels off by more than 2 px in red and those without an
// estimate in yellow; black: not evaluated (truth unknown, or the left border band).
cv::Mat error_picture(const cv::Mat& left, const cv::Mat& d, const cv::Mat& valid, const cv::Mat& truth,
                      const cv::Mat& mask, const std::string& title) {
  cv::Mat gray, out;
  cv::cvtColor(left, gray, cv::COLOR_BGR2GRAY);
  cv::cvtColor(gray, out, cv::COLOR_GRAY2BGR);
  out *= 0.6;
  for (int r = 0; r < d.rows; ++r)
    for (int c = 0; c < d.cols; ++c) {
      cv::Vec3b& p = out.at<cv::Vec3b>(r, c);
      if (!mask.at<uint8_t>(r, c))
        p = cv::Vec3b(0, 0, 0);
      else if (!valid.at<uint8_t>(r, c))
        p = cv::Vec3b(0, 220, 255);
      else if (std::abs(d.at<float>(r, c) - truth.at<float>(r, c)) > kBadPx)
        p = cv::Vec3b(0, 0, 255);
    }
  return with_legend(out, 0, 0, title + "  red: error > 2 px, yellow: none, black: not evaluated", false);
}

struct SgbmSetting {
  std::string name;
  int mode, block;
};

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

nlohmann::json real_depth(const RealOptions& opt) {
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::max(1, opt.threads));
  const int cv_threads = cv::getNumThreads();
  cv::setNumThreads(std::max(1, opt.threads));
  fs::path out_dir = opt.out_dir;
  if (out_dir.empty()) out_dir = fs::temp_directory_path() / fmt::format("omma_real_depth_{}", ::getpid());
  fs::create_directories(out_dir);

  const AloePair p = load_aloe(opt.data_dir, opt.quick);
  const int W = p.left.cols, H = p.left.rows;
  // The scene's range (the truth's extremes), widened by 3 px and rounded to SGBM's multiple of 16:
  // both methods search the same disparities d_lo .. d_lo + n_d - 1.
  double t_min = 0, t_max = 0;
  cv::minMaxLoc(p.truth, nullptr, &t_max);
  {
    cv::Mat t = p.truth.clone();
    t.setTo(1e9, p.truth <= 0);
    cv::minMaxLoc(t, &t_min);
  }
  const int d_lo = std::max(1, int(std::floor(t_min)) - 3);
  const int n_d = 16 * int(std::ceil((std::ceil(t_max) + 3 - d_lo + 1) / 16.0));
  const int border = d_lo + n_d;  // the left border band left out of the evaluation
  cv::Mat mask = p.truth > 0;
  mask(cv::Rect(0, 0, std::min(border, W), H)).setTo(0);
  const long known = cv::countNonZero(p.truth > 0), evaluated = cv::countNonZero(mask);

  // omma: the sweep on the left camera's pixel grid (factor 1), 1 px steps on the axis.
  const double f = kFocalPx * p.scale;
  const Rig rig = pano::rectified_pair_rig(W, H, f, kBaselineMm);
  // The patch spans about 9 pixels of the full-size images (plane_sweep.h, stereo_sweep_defaults).
  pano::PlaneSweepOptions base = pano::stereo_sweep_defaults(opt.quick ? 2 : 4);
  const pano::PlaneSweepOptions so = pano::rectified_sweep_options(rig, d_lo, d_lo + n_d - 1, 1.0, base);
  auto t0 = std::chrono::steady_clock::now();
  const pano::RectifiedDisparity rd = pano::rectified_disparity(rig, p.left, p.right, so);
  const double omma_s = seconds_since(t0);
  const cv::Mat& omma_d = rd.disparity;
  const cv::Mat omma_valid(H, W, CV_8UC1, cv::Scalar(255));
  const Score os = score(omma_d, omma_valid, p.truth, mask);
  const Score os_left = score(rd.left_only, omma_valid, p.truth, mask);
  const Score os_cons = score(rd.left_only, rd.consistent, p.truth, mask);
  long confident = 0;
  for (int r = 0; r < H; ++r)
    for (int c = 0; c < W; ++c) confident += mask.at<uint8_t>(r, c) && rd.consistent.at<uint8_t>(r, c);

  nlohmann::json j;
  j["pair"] = "Middlebury Aloe (OpenCV samples aloeL.jpg, aloeR.jpg, aloeGT.png)";
  j["quick"] = opt.quick;
  j["size"] = {W, H};
  j["scale"] = p.scale;
  j["truth"] = {{"units", "disparity px of these images, 0 = unknown"},
                {"min_px", t_min},
                {"max_px", t_max},
                {"known_pct", 100.0 * known / (double(W) * H)}};
  j["range_px"] = {d_lo, d_lo + n_d - 1};
  j["border_px"] = border;
  j["evaluated_pct"] = 100.0 * evaluated / known;
  j["omma"] = {{"bad2_pct", os.bad2_pct},
               {"median_err_px", os.median_px},
               {"coverage_pct", os.coverage_pct},
               {"consistent_pct", 100.0 * confident / evaluated},
               {"consistent_bad2_valid_pct", os_cons.bad2_valid_pct},
               {"left_only_bad2_pct", os_left.bad2_pct},
               {"left_only_median_err_px", os_left.median_px},
               {"time_s", omma_s},
               {"params",
                {{"grid", "left / right camera's pixels (factor 1), left-right check 1 px"},
                 {"focal_px", f},
                 {"baseline_mm", kBaselineMm},
                 {"near_mm", so.near_mm},
                 {"far_mm", so.far_mm},
                 {"steps", so.steps},
                 {"window", so.window},
                 {"band_ratio", so.band_ratio},
                 {"p1", so.p1},
                 {"p2", so.p2},
                 {"edge_gray", so.edge_gray},
                 {"paths", so.paths},
                 {"median", so.median}}}};

  const cv::Mat truth_valid = p.truth > 0;
  const double lo = d_lo, hi = d_lo + n_d - 1;
  nlohmann::json pictures;
  auto write = [&](const std::string& name, const cv::Mat& img) {
    write_image(out_dir / name, img);
    pictures[name.substr(0, name.find('.'))] = name;
  };
  write("disparity_truth.png", disparity_picture(p.truth, truth_valid, lo, hi, "truth (aloeGT.png)"));
  write("disparity_omma.png", disparity_picture(omma_d, omma_valid, lo, hi, "omma depth sweep"));
  write("error_omma.png", error_picture(p.left, omma_d, omma_valid, p.truth, mask,
                                        fmt::format("omma: bad-2 {:.1f} %", os.bad2_pct)));

  if (opt.peers) {
    // StereoSGBM as OpenCV's stereo_match.cpp sets it up: P1 = 8 cn b^2, P2 = 32 cn b^2, preFilterCap 63,
    // uniquenessRatio 10, speckleWindowSize 100, speckleRange 32, disp12MaxDiff 1; the best (by bad-2)
    // of its block sizes 3 and 5 and its modes SGBM, HH and SGBM_3WAY is compared.
    const std::vector<SgbmSetting> settings = {{"SGBM", cv::StereoSGBM::MODE_SGBM, 3},
                                               {"SGBM", cv::StereoSGBM::MODE_SGBM, 5},
                                               {"HH", cv::StereoSGBM::MODE_HH, 3},
                                               {"SGBM_3WAY", cv::StereoSGBM::MODE_SGBM_3WAY, 3}};
    const int cn = p.left.channels();
    nlohmann::json all = nlohmann::json::array();
    int best = -1;
    Score best_score;
    double best_s = 0;
    cv::Mat best_d, best_valid;
    for (size_t i = 0; i < settings.size(); ++i) {
      const SgbmSetting& st = settings[i];
      const int b = st.block;
      auto sgbm =
          cv::StereoSGBM::create(d_lo, n_d, b, 8 * cn * b * b, 32 * cn * b * b, 1, 63, 10, 100, 32, st.mode);
      cv::Mat raw, d;
      t0 = std::chrono::steady_clock::now();
      sgbm->compute(p.left, p.right, raw);
      const double s = seconds_since(t0);
      raw.convertTo(d, CV_32F, 1 / 16.0);      // fixed point, 4 fractional bits
      const cv::Mat valid = raw >= 16 * d_lo;  // invalid: (minDisparity - 1) * 16
      const Score sc = score(d, valid, p.truth, mask);
      all.push_back({{"mode", st.name},
                     {"block_size", b},
                     {"bad2_pct", sc.bad2_pct},
                     {"median_err_px", sc.median_px},
                     {"coverage_pct", sc.coverage_pct},
                     {"time_s", s}});
      if (best < 0 || sc.bad2_pct < best_score.bad2_pct) {
        best = int(i);
        best_score = sc;
        best_s = s;
        best_d = d;
        best_valid = valid;
      }
    }
    const SgbmSetting& st = settings[best];
    const int b = st.block;
    j["sgbm"] = {{"bad2_pct", best_score.bad2_pct},
                 {"bad2_valid_pct", best_score.bad2_valid_pct},
                 {"median_err_px", best_score.median_px},
                 {"coverage_pct", best_score.coverage_pct},
                 {"time_s", best_s},
                 {"params",
                  {{"mode", st.name},
                   {"block_size", b},
                   {"min_disparity", d_lo},
                   {"num_disparities", n_d},
                   {"p1", 8 * cn * b * b},
                   {"p2", 32 * cn * b * b},
                   {"pre_filter_cap", 63},
                   {"uniqueness_ratio", 10},
                   {"speckle_window_size", 100},
                   {"speckle_range", 32},
                   {"disp12_max_diff", 1}}},
                 {"settings", all}};
    write("disparity_sgbm.png",
          disparity_picture(best_d, best_valid, lo, hi, "OpenCV StereoSGBM " + st.name));
    write("error_sgbm.png", error_picture(p.left, best_d, best_valid, p.truth, mask,
                                          fmt::format("SGBM: bad-2 {:.1f} %", best_score.bad2_pct)));
  }
  j["pictures"] = pictures;
  j["out_dir"] = out_dir.string();
  cv::setNumThreads(cv_threads);
  return j;
}

}  // namespace omma::bench
