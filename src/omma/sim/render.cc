#include "omma/sim/render.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace omma::sim {
namespace {

uint64_t splitmix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

uint64_t mix(uint64_t a, uint64_t b, uint64_t c = 0) { return splitmix(splitmix(splitmix(a) ^ b) ^ c); }

void check_effects(const CameraEffects& e) {
  if (e.supersample < 1 || e.supersample > 16)
    throw std::invalid_argument(fmt::format("supersample must be 1..16, got {}", e.supersample));
  if (!(e.vignetting >= 0 && e.vignetting <= 1))
    throw std::invalid_argument(fmt::format("vignetting strength must be in [0, 1], got {}", e.vignetting));
  if (!(e.color_gain >= 0 && e.color_gain < 1))
    throw std::invalid_argument(fmt::format("colour gain spread must be in [0, 1), got {}", e.color_gain));
  if (!(e.full_scale_electrons >= 0) || !(e.read_noise_dn >= 0) || !(e.exposure > 0))
    throw std::invalid_argument("full-scale electrons and read noise must be >= 0, exposure > 0");
  if (e.shot < 0) throw std::invalid_argument(fmt::format("shot index must be >= 0, got {}", e.shot));
  if (e.bits != 0 && (e.bits < 8 || e.bits > 16))
    throw std::invalid_argument(fmt::format("bits must be 8..16 (or 0 for none), got {}", e.bits));
}

}  // namespace

CameraEffects CameraEffects::ideal(int supersample) {
  CameraEffects e;
  e.supersample = supersample;
  e.vignetting = 0;
  e.color_gain = 0;
  e.full_scale_electrons = 0;
  e.read_noise_dn = 0;
  e.bits = 0;
  return e;
}

cv::Vec3d camera_gains(const CameraEffects& e, int camera_id) {
  if (e.color_gain == 0) return {1, 1, 1};
  std::mt19937_64 rng(mix(e.seed, 0x6761696e73ull, static_cast<uint64_t>(camera_id)));
  std::uniform_real_distribution<double> u(1 - e.color_gain, 1 + e.color_gain);
  cv::Vec3d g;
  for (int c = 0; c < 3; ++c) g[c] = u(rng);
  return g;
}

double true_falloff(const RigCamera& camera, const CameraEffects& e, const Vec2& px) {
  if (e.vignetting <= 0) return 1;
  const double ca = camera.model().unproject(px).dot(camera.frame.t);
  return 1 - e.vignetting * (1 - ca * ca * ca * ca);
}

Photometric true_photometric(const RigCamera& camera, const CameraEffects& e, double* max_error) {
  Photometric p;
  const cv::Vec3d g = camera_gains(e, camera.id);
  p.gains = {g[0], g[1], g[2]};
  const int W = camera.in.width, H = camera.in.height;
  // V = 1 + b s + c s^2 + d s^3 (s = r^2): the minimax fit over a grid of pixel centres.
  const int step = std::max(1, std::min(W, H) / 64);
  std::vector<double> ss, vs;
  for (int r = 0; r < H; r += step)
    for (int c = 0; c < W; c += step) {
      const double rad = vignetting_radius(p, W, H, c + 0.5, r + 0.5);
      ss.push_back(rad * rad);
      vs.push_back(true_falloff(camera, e, Vec2(c + 0.5, r + 0.5)));
    }
  // The grid misses the image's outermost pixels: add the corners and edge midpoints.
  for (double c : {0.5, W / 2.0, W - 0.5})
    for (double r : {0.5, H / 2.0, H - 0.5}) {
      const double rad = vignetting_radius(p, W, H, c, r);
      ss.push_back(rad * rad);
      vs.push_back(true_falloff(camera, e, Vec2(c, r)));
    }
  p.vignetting = fit_vignetting(ss, vs);
  if (max_error) {
    double mx = 0;
    for (int r = 0; r < H; ++r)
      for (int c = 0; c < W; ++c)
        mx = std::max(mx, std::abs(vignetting_falloff(p, W, H, c + 0.5, r + 0.5) /
                                       true_falloff(camera, e, Vec2(c + 0.5, r + 0.5)) -
                                   1));
    *max_error = mx;
  }
  return p;
}

cv::Mat render_radiance(const Scene& scene, const RigCamera& camera, const DomePose& pose, int n) {
  if (n < 1 || n > 16) throw std::invalid_argument(fmt::format("supersample must be 1..16, got {}", n));
  const CameraModel model = camera.model();
  const int W = camera.in.width, H = camera.in.height;
  cv::Mat out(H, W, CV_32FC3);
  const Vec3 origin = pose.rotation * camera.position_mm + pose.translation_mm;
  const Vec3 light = pose.translation_mm;
  const float inv = 1.0f / (n * n);
  tbb::parallel_for(tbb::blocked_range<int>(0, H, 4), [&](const tbb::blocked_range<int>& rows) {
    for (int r = rows.begin(); r < rows.end(); ++r) {
      cv::Vec3f* dst = out.ptr<cv::Vec3f>(r);
      for (int c = 0; c < W; ++c) {
        cv::Vec3f sum(0, 0, 0);
        for (int j = 0; j < n; ++j)
          for (int i = 0; i < n; ++i) {
            const Vec2 px(c + (i + 0.5) / n, r + (j + 0.5) / n);
            const Vec3 dir = pose.rotation * model.unproject(px);
            sum += scene.radiance(origin, dir, light);
          }
        dst[c] = sum * inv;
      }
    }
  });
  return out;
}

cv::Mat bayer_rggb(const cv::Mat& bgr) {
  if (bgr.channels() != 3) throw std::invalid_argument("bayer_rggb needs a 3-channel image");
  cv::Mat ch[3];
  cv::split(bgr, ch);
  cv::Mat out(bgr.size(), ch[0].type());
  for (int r = 0; r < bgr.rows; ++r)
    for (int c = 0; c < bgr.cols; ++c) {
      // BGR channel index: R = 2, G = 1, B = 0.
      const int k = (r % 2 == 0) ? (c % 2 == 0 ? 2 : 1) : (c % 2 == 0 ? 1 : 0);
      switch (out.depth()) {
        case CV_8U:
          out.at<uchar>(r, c) = ch[k].at<uchar>(r, c);
          break;
        case CV_16U:
          out.at<uint16_t>(r, c) = ch[k].at<uint16_t>(r, c);
          break;
        case CV_32F:
          out.at<float>(r, c) = ch[k].at<float>(r, c);
          break;
        default:
          throw std::invalid_argument("bayer_rggb: unsupported depth");
      }
    }
  return out;
}

cv::Mat encode_srgb8(const cv::Mat& linear) {
  CV_Assert(linear.type() == CV_32FC3);
  // 4096-entry table over [0, 1] plus linear interpolation: error far below one 8-bit step.
  static const std::vector<float> lut = [] {
    std::vector<float> t(4097);
    for (int i = 0; i <= 4096; ++i) t[i] = linear_to_srgb(i / 4096.0f) * 255.0f;
    return t;
  }();
  cv::Mat out(linear.size(), CV_8UC3);
  tbb::parallel_for(tbb::blocked_range<int>(0, linear.rows, 16), [&](const tbb::blocked_range<int>& rows) {
    for (int r = rows.begin(); r < rows.end(); ++r) {
      const float* s = linear.ptr<float>(r);
      uchar* d = out.ptr<uchar>(r);
      for (int i = 0; i < linear.cols * 3; ++i) {
        // NaN -> 0 and +inf -> 1 (std::clamp passes NaN through, and NaN would index the table).
        const float v = s[i] > 0 ? std::min(s[i], 1.0f) : 0.0f;
        float x = v <= 0.0031308f ? 12.92f * v * 255.0f : -1.0f;
        if (x < 0) {
          const float f = v * 4096.0f;
          const int k = std::min(static_cast<int>(f), 4095);
          x = lut[k] + (lut[k + 1] - lut[k]) * (f - k);
        }
        d[i] = static_cast<uchar>(std::lround(std::clamp(x, 0.0f, 255.0f)));
      }
    }
  });
  return out;
}

CameraFrame apply_sensor(const cv::Mat& radiance, const RigCamera& camera, const CameraEffects& e,
                         bool want_raw) {
  check_effects(e);
  CV_Assert(radiance.type() == CV_32FC3);
  if (want_raw && e.bits == 0) throw std::invalid_argument("raw frames need quantisation (bits 8..16)");
  const int W = radiance.cols, H = radiance.rows;
  CameraFrame f;
  f.gains = camera_gains(e, camera.id);
  f.signal.create(H, W, CV_32FC3);
  const double levels = e.bits > 0 ? std::ldexp(1.0, e.bits) - 1 : 0;
  cv::Mat dn;
  if (e.bits > 0) dn.create(H, W, CV_16UC3);
  tbb::parallel_for(tbb::blocked_range<int>(0, H, 4), [&](const tbb::blocked_range<int>& rows) {
    for (int r = rows.begin(); r < rows.end(); ++r) {
      // Shot 0 keeps the single-exposure noise of earlier versions; later shots mix their index in.
      const uint64_t noise_seed =
          e.shot == 0 ? e.seed : mix(e.seed, 0x73686f74ull, static_cast<uint64_t>(e.shot));
      std::mt19937_64 rng(mix(noise_seed, static_cast<uint64_t>(camera.id) + 1, static_cast<uint64_t>(r)));
      std::normal_distribution<double> normal(0.0, 1.0);
      const cv::Vec3f* src = radiance.ptr<cv::Vec3f>(r);
      cv::Vec3f* dst = f.signal.ptr<cv::Vec3f>(r);
      for (int c = 0; c < W; ++c) {
        const double v = true_falloff(camera, e, Vec2(c + 0.5, r + 0.5));
        for (int k = 0; k < 3; ++k) {
          double s = e.exposure * f.gains[k] * v * src[c][k];
          if (e.full_scale_electrons > 0 && s > 0) s += std::sqrt(s / e.full_scale_electrons) * normal(rng);
          if (e.read_noise_dn > 0 && levels > 0) s += e.read_noise_dn / levels * normal(rng);
          s = std::clamp(s, 0.0, 1.0);
          if (levels > 0) {
            const double q = std::round(s * levels);
            dn.ptr<uint16_t>(r)[3 * c + k] = static_cast<uint16_t>(q);
            s = q / levels;
          }
          dst[c][k] = static_cast<float>(s);
        }
      }
    }
  });
  f.image = encode_srgb8(f.signal);
  if (want_raw) f.raw = bayer_rggb(dn);
  return f;
}

CameraFrame render_camera(const Scene& scene, const RigCamera& camera, const DomePose& pose,
                          const CameraEffects& effects, bool want_raw) {
  check_effects(effects);
  return apply_sensor(render_radiance(scene, camera, pose, effects.supersample), camera, effects, want_raw);
}

std::vector<CameraFrame> render_rig(const Scene& scene, const Rig& rig, const DomePose& pose,
                                    const CameraEffects& effects, bool want_raw) {
  check_effects(effects);
  std::vector<CameraFrame> frames(rig.cameras.size());
  tbb::parallel_for(size_t{0}, rig.cameras.size(), [&](size_t i) {
    frames[i] = render_camera(scene, rig.cameras[i], pose, effects, want_raw);
  });
  return frames;
}

int auto_truth_supersample(const PanoGrid& grid) {
  double deg_per_px = 0;
  switch (grid.projection) {
    case Projection::kEquirect:
      deg_per_px = std::max(360.0 / grid.width, 90.0 / grid.height);
      break;
    case Projection::kVr180:
      deg_per_px = std::max(180.0 / grid.width, 180.0 / grid.height);
      break;
    case Projection::kEquirectFull:
      deg_per_px = std::max(360.0 / grid.width, 180.0 / grid.height);
      break;
    case Projection::kEquirect100:
      deg_per_px = std::max(360.0 / grid.width, 100.0 / grid.height);
      break;
  }
  return std::clamp(static_cast<int>(std::ceil(deg_per_px / 0.09 - 1e-9)), 1, 4);
}

cv::Mat render_truth_linear(const Scene& scene, const PanoGrid& grid, const DomePose& pose, int n,
                            double exposure, Progress* progress) {
  if (n < 1 || n > 16) throw std::invalid_argument(fmt::format("truth supersample must be 1..16, got {}", n));
  if (grid.width <= 0 || grid.height <= 0) throw std::invalid_argument("truth grid size must be positive");
  cv::Mat out(grid.height, grid.width, CV_32FC3);
  const Vec3 origin = pose.translation_mm;
  const float scale = static_cast<float>(exposure / (n * n));
  tbb::parallel_for(tbb::blocked_range<int>(0, grid.height, 2), [&](const tbb::blocked_range<int>& rows) {
    for (int r = rows.begin(); r < rows.end(); ++r) {
      cv::Vec3f* dst = out.ptr<cv::Vec3f>(r);
      for (int c = 0; c < grid.width; ++c) {
        cv::Vec3f sum(0, 0, 0);
        for (int j = 0; j < n; ++j)
          for (int i = 0; i < n; ++i) {
            const Vec3 dir = pose.rotation * grid.direction(c + (i + 0.5) / n, r + (j + 0.5) / n);
            sum += scene.radiance(origin, dir, origin);
          }
        dst[c] = sum * scale;
      }
      if (progress) progress->step();
    }
  });
  return out;
}

cv::Mat render_truth_depth(const Scene& scene, const PanoGrid& grid, const DomePose& pose) {
  if (grid.width <= 0 || grid.height <= 0) throw std::invalid_argument("truth grid size must be positive");
  cv::Mat out(grid.height, grid.width, CV_32FC1);
  tbb::parallel_for(0, grid.height, [&](int r) {
    float* dst = out.ptr<float>(r);
    for (int c = 0; c < grid.width; ++c)
      dst[c] =
          static_cast<float>(scene.distance(pose.translation_mm, pose.rotation * grid.pixel_direction(c, r)));
  });
  return out;
}

cv::Mat render_truth(const Scene& scene, const PanoGrid& grid, const DomePose& pose, int n, double exposure,
                     Progress* progress) {
  return encode_srgb8(render_truth_linear(scene, grid, pose, n, exposure, progress));
}

}  // namespace omma::sim
