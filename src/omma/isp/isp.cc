#include "omma/isp/isp.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <opencv2/imgproc.hpp>
#include <tbb/parallel_for.h>

#include "omma/core/io.h"
#include "omma/core/srgb.h"
#include "omma/core/valid.h"

namespace omma::isp {

bool IspOptions::IsValid(std::string* why) const {
  if (bits < 8 || bits > 16) {  // output_table: 2^bits entries, the 8 most significant bits
    if (why)
      *why = bits < 8 ? "ISP needs raw values of at least 8 bits" : "ISP needs raw values of at most 16 bits";
    return false;
  }
  if (!flat_gain.empty() && flat_gain.type() != CV_16UC1)
    return invalid(why, "flat-field gain must be CV_16UC1 (Q12)");
  return true;
}

namespace {

// Flat-field correction when a gain map is given (returns the input otherwise).
cv::Mat vignetting(const cv::Mat& raw, const IspOptions& o) {
  if (o.flat_gain.empty()) return raw;
  cv::Mat r16;
  if (raw.depth() == CV_16U)
    r16 = raw;
  else
    raw.convertTo(r16, CV_16U);
  return apply_flat_field(r16, o.flat_gain, (1 << o.bits) - 1);
}

cv::Mat to_bgr8(const cv::Mat& bgr16, int bits, bool srgb) {
  const std::vector<uint8_t> lut = output_table(bits, srgb);
  cv::Mat out(bgr16.size(), CV_8UC3);
  for (int y = 0; y < bgr16.rows; ++y) {
    const uint16_t* p = bgr16.ptr<uint16_t>(y);
    uint8_t* o = out.ptr<uint8_t>(y);
    for (int i = 0; i < 3 * bgr16.cols; ++i) o[i] = lut[p[i]];
  }
  return out;
}

void gain_row_lut(const uint16_t* p, uint8_t* q, int n, uint32_t gain, uint32_t maxv, const uint8_t* lut) {
  for (int x = 0; x < n; ++x) {
    const uint32_t v = (uint32_t(p[x]) * gain + 2048u) >> 12;
    q[x] = lut[v < maxv ? v : maxv];
  }
}

// One row of: v' = min(maxv, (v * gain + 2048) >> 12), then the 8 MSBs (a compile-time shift for
// the 10-bit sensors, so that the loop vectorises).
template <int kShift>
void gain_row(const uint16_t* __restrict p, uint8_t* __restrict q, int n, uint32_t gain, uint32_t maxv) {
  if (gain == 4096u) {
    for (int x = 0; x < n; ++x) q[x] = uint8_t(p[x] >> kShift);
    return;
  }
  for (int x = 0; x < n; ++x) {
    const uint32_t v = (uint32_t(p[x]) * gain + 2048u) >> 12;
    q[x] = uint8_t((v < maxv ? v : maxv) >> kShift);
  }
}
void gain_row_any(const uint16_t* p, uint8_t* q, int n, uint32_t gain, uint32_t maxv, int shift) {
  for (int x = 0; x < n; ++x) {
    const uint32_t v = (uint32_t(p[x]) * gain + 2048u) >> 12;
    q[x] = uint8_t((v < maxv ? v : maxv) >> shift);
  }
}

void check_options(const cv::Mat& raw, const IspOptions& o) {
  check_bayer(raw, o.bits);
  std::string why;
  if (!o.IsValid(&why)) throw std::invalid_argument(why);
  if (!o.flat_gain.empty() && (o.flat_gain.size() != raw.size() || o.flat_gain.type() != CV_16UC1))
    throw std::invalid_argument("flat-field is " + std::to_string(o.flat_gain.cols) + "x" +
                                std::to_string(o.flat_gain.rows) + " but the raw frame is " +
                                std::to_string(raw.cols) + "x" + std::to_string(raw.rows));
}

}  // namespace

std::vector<uint8_t> output_table(int bits, bool srgb) {
  if (bits < 8 || bits > 16) throw std::invalid_argument("output_table: bits must be 8..16");
  const int n = 1 << bits;
  std::vector<uint8_t> t(static_cast<size_t>(n));
  for (int v = 0; v < n; ++v) {
    if (!srgb) {
      t[size_t(v)] = uint8_t(v >> (bits - 8));  // the 8 most significant bits (§5.2)
    } else {
      const double e = linear_to_srgb(float(double(v) / double(n - 1)));
      t[size_t(v)] = uint8_t(std::clamp(std::lround(255.0 * e), 0L, 255L));
    }
  }
  return t;
}

cv::Mat develop(const cv::Mat& raw_in, const IspOptions& o) {
  check_options(raw_in, o);
  const cv::Mat raw = vignetting(raw_in, o);
  const int maxv = (1 << o.bits) - 1;
  cv::Mat planes[3];  // B, G, R
  demosaic_planes(raw, o.demosaic, o.bits, planes);
  WbGains g;
  if (o.awb == Awb::kGrayWorld) {
    std::array<int64_t, 3> sums{};
    for (int c = 0; c < 3; ++c) sums[size_t(c)] = int64_t(cv::sum(planes[c])[0]);
    g = gray_world_gains(sums);
  } else if (o.awb == Awb::kWhitePatch) {
    g = white_patch_gains_planes(planes);
  }
  // Gains, clamp and the 8 MSBs, plane by plane (vectorisable loops), then interleave.
  const uint32_t gain[3] = {uint32_t(g.b_q12), 4096u, uint32_t(g.r_q12)};
  std::vector<uint8_t> lut;
  if (o.srgb) lut = output_table(o.bits, true);
  cv::Mat out8[3];
  for (int c = 0; c < 3; ++c) {
    out8[c].create(raw.size(), CV_8UC1);
    for (int y = 0; y < raw.rows; ++y) {
      const uint16_t* p = planes[c].ptr<uint16_t>(y);
      uint8_t* q = out8[c].ptr<uint8_t>(y);
      if (o.srgb)
        gain_row_lut(p, q, raw.cols, gain[c], uint32_t(maxv), lut.data());
      else if (o.bits == 10)
        gain_row<2>(p, q, raw.cols, gain[c], uint32_t(maxv));
      else
        gain_row_any(p, q, raw.cols, gain[c], uint32_t(maxv), o.bits - 8);
    }
  }
  cv::Mat out;
  cv::merge(out8, 3, out);
  return out;
}

cv::Mat develop_reference(const cv::Mat& raw_in, const IspOptions& o) {
  check_options(raw_in, o);
  const cv::Mat raw = vignetting(raw_in, o);
  cv::Mat rgb = demosaic_reference(raw, o.demosaic, o.bits);
  if (o.awb == Awb::kGrayWorld)
    apply_gains(rgb, gray_world_gains(rgb), (1 << o.bits) - 1);
  else if (o.awb == Awb::kWhitePatch)
    apply_gains(rgb, white_patch_gains_reference(rgb), (1 << o.bits) - 1);
  return to_bgr8(rgb, o.bits, o.srgb);
}

std::vector<cv::Mat> develop_all(const std::vector<cv::Mat>& raws, const IspOptions& o) {
  std::vector<cv::Mat> out(raws.size());
  tbb::parallel_for(size_t(0), raws.size(), [&](size_t i) { out[i] = develop(raws[i], o); });
  return out;
}

cv::Mat load_flat_field(const std::string& path) {
  const cv::Mat flat = read_image(path);
  if (flat.channels() != 1)
    throw std::invalid_argument("flat field '" + path + "' must be a raw single-channel RGGB frame");
  return flat_field_gain(flat);
}

ChannelPsnr psnr_per_channel(const cv::Mat& test, const cv::Mat& ref, int border) {
  if (test.type() != CV_8UC3 || ref.type() != CV_8UC3 || test.size() != ref.size())
    throw std::invalid_argument("psnr: expected two 8-bit BGR images of one size");
  if (test.cols <= 2 * border || test.rows <= 2 * border)
    throw std::invalid_argument("psnr: image too small for a border of " + std::to_string(border));
  const cv::Rect roi(border, border, test.cols - 2 * border, test.rows - 2 * border);
  double se[3] = {0, 0, 0};
  for (int y = roi.y; y < roi.y + roi.height; ++y) {
    const uint8_t* a = test.ptr<uint8_t>(y);
    const uint8_t* b = ref.ptr<uint8_t>(y);
    for (int x = roi.x; x < roi.x + roi.width; ++x)
      for (int c = 0; c < 3; ++c) {
        const double d = double(a[3 * x + c]) - double(b[3 * x + c]);
        se[c] += d * d;
      }
  }
  const double n = double(roi.area());
  auto psnr = [&](double s) {  // (A.39)-(A.40)
    const double mse = s / n;
    return mse <= 0 ? 99.0 : std::min(99.0, 10.0 * std::log10(255.0 * 255.0 / mse));
  };
  return {psnr(se[2]), psnr(se[1]), psnr(se[0])};
}

std::map<std::string, ChannelPsnr> evaluate_demosaic(const cv::Mat& photo, int border) {
  if (photo.type() != CV_8UC3) throw std::invalid_argument("evaluation needs an 8-bit colour photograph");
  const cv::Mat ref = photo(cv::Rect(0, 0, photo.cols & ~1, photo.rows & ~1)).clone();
  const cv::Mat raw = mosaic_rggb(ref);  // 8-bit values in CV_16UC1
  std::map<std::string, ChannelPsnr> res;
  for (Demosaic m :
       {Demosaic::kBilinear, Demosaic::kHybrid, Demosaic::kAdamsHamilton, Demosaic::kColourCorrelation}) {
    cv::Mat out8;
    demosaic(raw, m, 8).convertTo(out8, CV_8U);
    res[demosaic_name(m)] = psnr_per_channel(out8, ref, border);
  }
  cv::Mat raw8, cv_bl, cv_ea;
  raw.convertTo(raw8, CV_8U);
  cv::cvtColor(raw8, cv_bl, opencv_bayer_code_bilinear());
  cv::cvtColor(raw8, cv_ea, opencv_bayer_code_ea());
  res["opencv_bilinear"] = psnr_per_channel(cv_bl, ref, border);
  res["opencv_ea"] = psnr_per_channel(cv_ea, ref, border);
  return res;
}

LinkFrame to_link_frame(const cv::Mat& raw, int bits) {
  if (raw.empty() || raw.channels() != 1 || (raw.depth() != CV_16U && raw.depth() != CV_8U))
    throw std::invalid_argument("link frames must be single-channel 8- or 16-bit images (got " +
                                std::to_string(raw.channels()) + " channels, OpenCV depth " +
                                std::to_string(raw.depth()) + ")");
  cv::Mat r16;
  raw.convertTo(r16, CV_16U);
  double mx = 0;
  cv::minMaxLoc(r16, nullptr, &mx);
  if (mx >= double(1 << bits))
    throw std::invalid_argument("frame has values up to " + std::to_string(int(mx)) + ", more than " +
                                std::to_string(bits) + " bits allow: wrong bit depth?");
  LinkFrame f;
  f.width = r16.cols;
  f.height = r16.rows;
  f.pixels.resize(size_t(f.width) * f.height);
  for (int y = 0; y < f.height; ++y)
    std::copy_n(r16.ptr<uint16_t>(y), f.width, f.pixels.begin() + long(y) * f.width);
  f.row_ok.assign(size_t(f.height), 1);
  return f;
}

cv::Mat to_mat(const LinkFrame& f) {
  cv::Mat m(f.height, f.width, CV_16UC1);
  for (int y = 0; y < f.height; ++y)
    std::copy_n(f.pixels.begin() + long(y) * f.width, f.width, m.ptr<uint16_t>(y));
  return m;
}

}  // namespace omma::isp
