#include "omma/isp/photometric.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "omma/core/srgb.h"

namespace omma::isp {
namespace {

void check_frame(const cv::Mat& f, int width, int height, bool allow16) {
  const bool ok = f.type() == CV_8UC3 || (allow16 && f.type() == CV_16UC3);
  if (!ok)
    throw std::invalid_argument(fmt::format("photometric correction needs a {}3-channel sRGB frame",
                                            allow16 ? "8- or 16-bit " : "8-bit "));
  if (f.cols != width || f.rows != height)
    throw std::invalid_argument(fmt::format("photometric correction: frame is {}x{}, the camera is {}x{}",
                                            f.cols, f.rows, width, height));
}

}  // namespace

cv::Mat correct_photometric_reference(const cv::Mat& frame, const Photometric& p) {
  if (frame.empty()) throw std::invalid_argument("photometric correction: empty frame");
  const int W = frame.cols, H = frame.rows;
  check_frame(frame, W, H, true);
  const double full = frame.depth() == CV_8U ? 255.0 : 65535.0;
  cv::Mat out(frame.size(), frame.type());
  for (int r = 0; r < H; ++r)
    for (int c = 0; c < W; ++c) {
      const double v = vignetting_falloff(p, W, H, c + 0.5, r + 0.5);
      for (int k = 0; k < 3; ++k) {
        const double in =
            frame.depth() == CV_8U ? frame.at<cv::Vec3b>(r, c)[k] : frame.at<cv::Vec3w>(r, c)[k];
        const double lin = srgb_to_linear(float(in / full)) / (p.gains[k] * v);
        const double e = std::round(full * linear_to_srgb(float(std::min(lin, 1.0))));
        if (frame.depth() == CV_8U)
          out.at<cv::Vec3b>(r, c)[k] = cv::saturate_cast<uint8_t>(e);
        else
          out.at<cv::Vec3w>(r, c)[k] = cv::saturate_cast<uint16_t>(e);
      }
    }
  return out;
}

PhotometricTable::PhotometricTable(const Photometric& p, int width, int height)
    : width_(width), height_(height) {
  if (width <= 0 || height <= 0) throw std::invalid_argument("PhotometricTable: image size must be positive");
  validate_photometric(p, width, height, "PhotometricTable");
  gain_q12_.resize(size_t(width) * height);
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c) {
      const double g = 4096.0 / vignetting_falloff(p, width, height, c + 0.5, r + 0.5);  // Q4.12
      gain_q12_[size_t(r) * width + c] = uint16_t(std::min(65535.0, std::round(g)));
    }
  for (int k = 0; k < 3; ++k) {
    decode_[k].resize(256);
    for (int i = 0; i < 256; ++i)  // Q16.16
      decode_[k][i] =
          uint32_t(std::min(4294967295.0, std::round(65536.0 * srgb_to_linear(i / 255.0f) / p.gains[k])));
  }
  const int n = 1 << kEncodeBits;
  encode_.resize(n + 1);
  for (int i = 0; i <= n; ++i)
    encode_[i] = uint8_t(std::lround(255.0 * linear_to_srgb(float(double(i) / n))));
}

void PhotometricTable::apply_row(const uint8_t* src, uint8_t* dst, int row) const {
  const uint16_t* g = gain_q12_.data() + size_t(row) * width_;
  const uint32_t* d0 = decode_[0].data();
  const uint32_t* d1 = decode_[1].data();
  const uint32_t* d2 = decode_[2].data();
  const uint8_t* enc = encode_.data();
  constexpr uint64_t kMax = uint64_t(1) << kEncodeBits;
  for (int c = 0; c < width_; ++c, src += 3, dst += 3) {
    const uint64_t gg = g[c];
    // Q16.16 * Q4.12 = Q.28; + half and >> 14: Q0.14, rounded to nearest.
    const uint64_t b = std::min((d0[src[0]] * gg + 8192) >> 14, kMax);
    const uint64_t gr = std::min((d1[src[1]] * gg + 8192) >> 14, kMax);
    const uint64_t rr = std::min((d2[src[2]] * gg + 8192) >> 14, kMax);
    dst[0] = enc[b];
    dst[1] = enc[gr];
    dst[2] = enc[rr];
  }
}

void PhotometricTable::apply(const cv::Mat& in, cv::Mat& out) const {
  check_frame(in, width_, height_, false);
  if (out.data != in.data) out.create(in.size(), CV_8UC3);
  for (int r = 0; r < height_; ++r) apply_row(in.ptr<uint8_t>(r), out.ptr<uint8_t>(r), r);
}

std::vector<PhotometricTable> photometric_tables(const Rig& rig, bool enabled) {
  std::vector<PhotometricTable> t(rig.cameras.size());
  if (!enabled) return t;
  tbb::parallel_for(size_t{0}, rig.cameras.size(), [&](size_t i) {
    const RigCamera& c = rig.cameras[i];
    if (c.photometric) t[i] = PhotometricTable(*c.photometric, c.in.width, c.in.height);
  });
  return t;
}

std::vector<cv::Mat> correct_frames(const Rig& rig, const std::vector<cv::Mat>& frames) {
  if (frames.size() != rig.cameras.size())
    throw std::invalid_argument(
        fmt::format("correct_frames: {} frames for {} cameras", frames.size(), rig.cameras.size()));
  std::vector<cv::Mat> out(frames);
  tbb::parallel_for(size_t{0}, frames.size(), [&](size_t i) {
    const RigCamera& c = rig.cameras[i];
    if (!c.photometric) return;
    if (frames[i].type() == CV_8UC3) {
      cv::Mat o;
      PhotometricTable(*c.photometric, c.in.width, c.in.height).apply(frames[i], o);
      out[i] = o;
    } else {
      out[i] = correct_photometric_reference(frames[i], *c.photometric);
    }
  });
  return out;
}

cv::Mat flat_gain_from_model(const Photometric& p, int width, int height) {
  validate_photometric(p, width, height, "flat_gain_from_model");
  cv::Mat g(height, width, CV_16UC1);
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c) {
      // RGGB: (even, even) = R, (odd, odd) = B, else G; gains are B, G, R.
      const int k = (r % 2 == 0) ? (c % 2 == 0 ? 2 : 1) : (c % 2 == 0 ? 1 : 0);
      const double q = 4096.0 / (p.gains[k] * vignetting_falloff(p, width, height, c + 0.5, r + 0.5));
      g.at<uint16_t>(r, c) = uint16_t(std::clamp(std::round(q), 0.0, 65535.0));
    }
  return g;
}

std::vector<cv::Mat> flat_gains_from_rig(const Rig& rig) {
  std::vector<cv::Mat> gains(rig.cameras.size());
  tbb::parallel_for(size_t{0}, gains.size(), [&](size_t i) {
    const RigCamera& c = rig.cameras[i];
    if (c.photometric) gains[i] = flat_gain_from_model(*c.photometric, c.in.width, c.in.height);
  });
  return gains;
}

std::vector<cv::Mat> develop_with_model(const std::vector<cv::Mat>& raws, const IspOptions& options,
                                        const std::vector<cv::Mat>& gains) {
  if (!gains.empty() && gains.size() != raws.size())
    throw std::invalid_argument("develop_with_model: " + std::to_string(gains.size()) + " gain maps for " +
                                std::to_string(raws.size()) + " frames");
  std::vector<cv::Mat> out(raws.size());
  tbb::parallel_for(size_t{0}, raws.size(), [&](size_t i) {
    if (raws[i].empty()) return;
    IspOptions o = options;
    if (!gains.empty() && !gains[i].empty()) {
      o.flat_gain = gains[i];
      o.awb = Awb::kNone;
    }
    out[i] = develop(raws[i], o);
  });
  return out;
}

}  // namespace omma::isp
