#include "omma/isp/color.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <opencv2/imgproc.hpp>

namespace omma::isp {

Awb parse_awb(const std::string& name) {
  if (name == "none") return Awb::kNone;
  if (name == "grayworld") return Awb::kGrayWorld;
  if (name == "whitepatch") return Awb::kWhitePatch;
  throw std::invalid_argument("unknown white balance '" + name + "' (use none, grayworld or whitepatch)");
}

std::string awb_name(Awb a) {
  switch (a) {
    case Awb::kNone:
      return "none";
    case Awb::kGrayWorld:
      return "grayworld";
    case Awb::kWhitePatch:
      return "whitepatch";
  }
  return "?";
}

int gain_q12(double num, double den) {
  if (!(den > 0)) return 4096;
  const double g = std::round(4096.0 * num / den);
  return int(std::clamp(g, 0.0, 65535.0));
}

WbGains gray_world_gains(const std::array<int64_t, 3>& s) {
  // (A.26)-(A.27): alpha = Gavg / Ravg, beta = Gavg / Bavg (the pixel counts cancel)
  return {gain_q12(double(s[1]), double(s[2])), gain_q12(double(s[1]), double(s[0]))};
}

static void check_bgr16(const cv::Mat& m, const char* who) {
  if (m.type() != CV_16UC3) throw std::invalid_argument(std::string(who) + ": expected CV_16UC3 BGR");
}

WbGains gray_world_gains(const cv::Mat& bgr16) {
  check_bgr16(bgr16, "gray_world_gains");
  std::array<int64_t, 3> s{};
  for (int y = 0; y < bgr16.rows; ++y) {
    const uint16_t* p = bgr16.ptr<uint16_t>(y);
    for (int x = 0; x < bgr16.cols; ++x)
      for (int c = 0; c < 3; ++c) s[c] += p[3 * x + c];
  }
  return gray_world_gains(s);
}

WbGains white_patch_gains_reference(const cv::Mat& bgr16) {
  check_bgr16(bgr16, "white_patch_gains");
  // 4x4 box sums (16 x the low-passed value) and their maxima (A.31)-(A.33)
  std::array<int64_t, 3> mx{};
  for (int y = 0; y + 4 <= bgr16.rows; ++y)
    for (int x = 0; x + 4 <= bgr16.cols; ++x)
      for (int c = 0; c < 3; ++c) {
        int64_t s = 0;
        for (int dy = 0; dy < 4; ++dy)
          for (int dx = 0; dx < 4; ++dx) s += bgr16.at<cv::Vec3w>(y + dy, x + dx)[c];
        mx[c] = std::max(mx[c], s);
      }
  return {gain_q12(double(mx[1]), double(mx[2])), gain_q12(double(mx[1]), double(mx[0]))};  // (A.34)-(A.35)
}

WbGains white_patch_gains_planes(const cv::Mat planes[3]) {
  const int W = planes[0].cols, H = planes[0].rows;
  std::array<int64_t, 3> mx{};
  if (W < 4 || H < 4) return {};
  std::vector<int32_t> col(static_cast<size_t>(W));
  for (int c = 0; c < 3; ++c) {
    if (planes[c].type() != CV_16UC1 || planes[c].size() != planes[0].size())
      throw std::invalid_argument("white_patch_gains: planes must be CV_16UC1 of one size");
    // Column sums over the last 4 rows (vectorisable), then a 4-wide running sum along the row.
    std::fill(col.begin(), col.end(), 0);
    int32_t* __restrict cs = col.data();
    for (int y = 0; y < H; ++y) {
      const uint16_t* __restrict add = planes[c].ptr<uint16_t>(y);
      if (y >= 4) {
        const uint16_t* __restrict sub = planes[c].ptr<uint16_t>(y - 4);
#pragma GCC ivdep
        for (int x = 0; x < W; ++x) cs[x] += int32_t(add[x]) - int32_t(sub[x]);
      } else {
#pragma GCC ivdep
        for (int x = 0; x < W; ++x) cs[x] += add[x];
      }
      if (y < 3) continue;
      int64_t s = int64_t(cs[0]) + cs[1] + cs[2] + cs[3];
      int64_t m = s;
      for (int x = 4; x < W; ++x) {
        s += cs[x] - cs[x - 4];
        m = std::max(m, s);
      }
      mx[size_t(c)] = std::max(mx[size_t(c)], m);
    }
  }
  return {gain_q12(double(mx[1]), double(mx[2])), gain_q12(double(mx[1]), double(mx[0]))};
}

WbGains white_patch_gains(const cv::Mat& bgr16) {
  check_bgr16(bgr16, "white_patch_gains");
  std::vector<cv::Mat> ch;
  cv::split(bgr16, ch);
  const cv::Mat planes[3] = {ch[0], ch[1], ch[2]};
  return white_patch_gains_planes(planes);
}

void apply_gains(cv::Mat& bgr16, const WbGains& g, int maxv) {
  check_bgr16(bgr16, "apply_gains");
  for (int y = 0; y < bgr16.rows; ++y) {
    uint16_t* p = bgr16.ptr<uint16_t>(y);
    for (int x = 0; x < bgr16.cols; ++x) {
      p[3 * x + 0] = uint16_t(std::min<int64_t>(maxv, (int64_t(p[3 * x + 0]) * g.b_q12 + 2048) >> 12));
      p[3 * x + 2] = uint16_t(std::min<int64_t>(maxv, (int64_t(p[3 * x + 2]) * g.r_q12 + 2048) >> 12));
    }
  }
}

cv::Mat flat_field_gain(const cv::Mat& flat_raw) {
  if (flat_raw.empty() || flat_raw.channels() != 1 ||
      (flat_raw.depth() != CV_16U && flat_raw.depth() != CV_8U))
    throw std::invalid_argument("flat field must be a raw single-channel 8- or 16-bit RGGB frame");
  if (flat_raw.cols % 2 || flat_raw.rows % 2 || flat_raw.cols < 4 || flat_raw.rows < 4)
    throw std::invalid_argument("flat field must have even width and height of at least 4");
  cv::Mat f;
  flat_raw.convertTo(f, CV_32F);
  const int w2 = f.cols / 2, h2 = f.rows / 2;
  cv::Mat gain(f.size(), CV_16UC1);
  for (int py = 0; py < 2; ++py)
    for (int px = 0; px < 2; ++px) {
      cv::Mat plane(h2, w2, CV_32F);
      for (int y = 0; y < h2; ++y)
        for (int x = 0; x < w2; ++x) plane.at<float>(y, x) = f.at<float>(2 * y + py, 2 * x + px);
      cv::GaussianBlur(plane, plane, cv::Size(0, 0), 2.0, 2.0, cv::BORDER_REFLECT_101);
      double peak = 0;
      cv::minMaxLoc(plane, nullptr, &peak);
      if (!(peak > 0)) throw std::invalid_argument("flat field is black in one colour plane");
      for (int y = 0; y < h2; ++y)
        for (int x = 0; x < w2; ++x) {
          const double v = std::max(1e-3, double(plane.at<float>(y, x)));
          gain.at<uint16_t>(2 * y + py, 2 * x + px) =
              uint16_t(std::clamp(std::round(4096.0 * peak / v), 1.0, 65535.0));
        }
    }
  return gain;
}

cv::Mat apply_flat_field(const cv::Mat& raw16, const cv::Mat& gain, int maxv) {
  if (raw16.type() != CV_16UC1 || gain.type() != CV_16UC1 || raw16.size() != gain.size())
    throw std::invalid_argument("flat-field gain is " + std::to_string(gain.cols) + "x" +
                                std::to_string(gain.rows) + ", the raw frame " + std::to_string(raw16.cols) +
                                "x" + std::to_string(raw16.rows) +
                                " (both must be 16-bit single-channel of one size)");
  cv::Mat out(raw16.size(), CV_16UC1);
  for (int y = 0; y < raw16.rows; ++y) {
    const uint16_t* r = raw16.ptr<uint16_t>(y);
    const uint16_t* g = gain.ptr<uint16_t>(y);
    uint16_t* o = out.ptr<uint16_t>(y);
    for (int x = 0; x < raw16.cols; ++x)
      o[x] = uint16_t(std::min<uint32_t>(uint32_t(maxv), (uint32_t(r[x]) * g[x] + 2048u) >> 12));
  }
  return out;
}

cv::Mat pack_rgb565(const cv::Mat& bgr8) {
  if (bgr8.type() != CV_8UC3) throw std::invalid_argument("pack_rgb565: expected CV_8UC3 BGR");
  cv::Mat out(bgr8.size(), CV_16UC1);
  for (int y = 0; y < bgr8.rows; ++y) {
    const uint8_t* p = bgr8.ptr<uint8_t>(y);
    uint16_t* o = out.ptr<uint16_t>(y);
    for (int x = 0; x < bgr8.cols; ++x)
      o[x] = uint16_t(((p[3 * x + 2] >> 3) << 11) | ((p[3 * x + 1] >> 2) << 5) | (p[3 * x + 0] >> 3));
  }
  return out;
}

cv::Mat unpack_rgb565(const cv::Mat& packed) {
  if (packed.type() != CV_16UC1) throw std::invalid_argument("unpack_rgb565: expected CV_16UC1");
  cv::Mat out(packed.size(), CV_8UC3);
  for (int y = 0; y < packed.rows; ++y) {
    const uint16_t* p = packed.ptr<uint16_t>(y);
    uint8_t* o = out.ptr<uint8_t>(y);
    for (int x = 0; x < packed.cols; ++x) {
      const int r5 = p[x] >> 11, g6 = (p[x] >> 5) & 63, b5 = p[x] & 31;
      o[3 * x + 2] = uint8_t((r5 << 3) | (r5 >> 2));
      o[3 * x + 1] = uint8_t((g6 << 2) | (g6 >> 4));
      o[3 * x + 0] = uint8_t((b5 << 3) | (b5 >> 2));
    }
  }
  return out;
}

}  // namespace omma::isp
