#include "omma/sim/scene.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "omma/core/grid.h"
#include "omma/core/parse.h"
#include "omma/sim/room.h"
#include "omma/sim/usaf.h"

namespace omma::sim {

namespace {

// ---------------------------------------------------------------- photo (far field)
class PhotoScene final : public Scene {
 public:
  PhotoScene(const cv::Mat& image, std::string spec) : spec_(std::move(spec)) {
    if (image.empty()) throw SceneError("photo scene: empty image");
    if (image.depth() != CV_8U && image.depth() != CV_16U && !cv::checkRange(image))
      throw SceneError("photo scene: the image holds NaN or infinite values");
    cv::Mat bgr = image;
    if (bgr.channels() == 1) cv::cvtColor(bgr, bgr, cv::COLOR_GRAY2BGR);
    if (bgr.channels() == 4) cv::cvtColor(bgr, bgr, cv::COLOR_BGRA2BGR);
    if (bgr.depth() == CV_8U) {
      std::array<float, 256> lut;
      for (int i = 0; i < 256; ++i) lut[i] = srgb_to_linear(i / 255.0f);
      linear_.create(bgr.size(), CV_32FC3);
      for (int r = 0; r < bgr.rows; ++r) {
        const uchar* s = bgr.ptr<uchar>(r);
        float* d = linear_.ptr<float>(r);
        for (int i = 0; i < bgr.cols * 3; ++i) d[i] = lut[s[i]];
      }
    } else {
      cv::Mat f;
      const double scale = bgr.depth() == CV_16U ? 1.0 / 65535 : 1.0;
      bgr.convertTo(f, CV_32FC3, scale);
      linear_.create(f.size(), CV_32FC3);
      f.forEach<cv::Vec3f>([&](const cv::Vec3f& v, const int* pos) {
        linear_.at<cv::Vec3f>(pos[0], pos[1]) =
            cv::Vec3f(srgb_to_linear(v[0]), srgb_to_linear(v[1]), srgb_to_linear(v[2]));
      });
    }
  }

  cv::Vec3f radiance(const Vec3&, const Vec3& d, const Vec3&) const override {
    const int W = linear_.cols, H = linear_.rows;
    double phi = std::atan2(d.y(), d.x());
    if (phi < 0) phi += 2 * kPi;
    const double theta = std::acos(std::clamp(d.z(), -1.0, 1.0));
    // The photo is an equirect-full panorama (conventions.h (G1)): continuous photo coordinates
    // (pixel centres at +0.5) -> sample grid (centres at integers).
    const double x = equirect_x(phi, W) - 0.5;
    const double y = std::clamp(theta / kPi * H - 0.5, 0.0, H - 1.0);
    const double fx = std::floor(x), fy = std::floor(y);
    const double ax = x - fx, ay = y - fy;
    int x0 = static_cast<int>(fx) % W;
    if (x0 < 0) x0 += W;
    const int x1 = (x0 + 1) % W;
    const int y0 = static_cast<int>(fy), y1 = std::min(y0 + 1, H - 1);
    const cv::Vec3f* r0 = linear_.ptr<cv::Vec3f>(y0);
    const cv::Vec3f* r1 = linear_.ptr<cv::Vec3f>(y1);
    const float wx = static_cast<float>(ax), wy = static_cast<float>(ay);
    return (r0[x0] * (1 - wx) + r0[x1] * wx) * (1 - wy) + (r1[x0] * (1 - wx) + r1[x1] * wx) * wy;
  }
  std::string spec() const override { return spec_; }

 private:
  cv::Mat linear_;  // CV_32FC3 linear BGR
  std::string spec_;
};

// ---------------------------------------------------------------- checker sphere
unsigned hash_cell(int a, int b) {
  unsigned h = static_cast<unsigned>(a) * 73856093u ^ static_cast<unsigned>(b) * 19349663u;
  h ^= h >> 13;
  h *= 0x5bd1e995u;
  return h ^ (h >> 15);
}

class CheckerScene final : public Scene {
 public:
  explicit CheckerScene(double radius) : radius_(radius) {
    if (!(radius > 0 && radius <= kMaxSceneMm))
      throw SceneError(fmt::format("checker scene: radius must be a positive number of mm up to {}, got {}",
                                   kMaxSceneMm, radius));
  }
  cv::Vec3f radiance(const Vec3& o, const Vec3& d, const Vec3&) const override {
    // |o + s d| = R, s > 0 (origin inside the sphere).
    const double b = o.dot(d), c = o.squaredNorm() - radius_ * radius_;
    if (c > 0) return {0, 0, 0};
    const double s = -b + std::sqrt(std::max(0.0, b * b - c));
    const Vec3 p = o + s * d;
    const Spherical sp = spherical_from_direction(p);
    const double td = rad2deg(sp.theta), pd = rad2deg(sp.phi);
    const int it = static_cast<int>(std::floor(td / 10)), ip = static_cast<int>(std::floor(pd / 10));
    static const cv::Vec3f kColours[6] = {{0.60f, 0.15f, 0.10f}, {0.10f, 0.55f, 0.15f},
                                          {0.12f, 0.15f, 0.65f}, {0.55f, 0.55f, 0.10f},
                                          {0.55f, 0.10f, 0.50f}, {0.10f, 0.50f, 0.55f}};
    cv::Vec3f c0 = ((it + ip) % 2 == 0) ? cv::Vec3f(0.8f, 0.8f, 0.8f) : kColours[(hash_cell(it, ip)) % 6];
    // Fine dark lines every 2 degrees (detail for resolution / blur checks).
    const double ft = std::fmod(td, 2.0), fp = std::fmod(pd, 2.0);
    if (ft < 0.2 || fp < 0.2) c0 *= 0.25f;
    return c0;
  }
  double distance(const Vec3& o, const Vec3& d) const override {
    const double b = o.dot(d), c = o.squaredNorm() - radius_ * radius_;
    if (c > 0) return std::numeric_limits<double>::infinity();
    return -b + std::sqrt(std::max(0.0, b * b - c));
  }
  std::string spec() const override { return fmt::format("checker:{}", radius_); }

 private:
  double radius_;
};

// ---------------------------------------------------------------- USAF chart
class UsafScene final : public Scene {
 public:
  explicit UsafScene(double distance) : distance_(distance) {
    if (!(distance > 0 && distance <= kMaxSceneMm))
      throw SceneError(fmt::format("usaf scene: distance must be a positive number of mm up to {}, got {}",
                                   kMaxSceneMm, distance));
  }
  cv::Vec3f radiance(const Vec3& o, const Vec3& d, const Vec3&) const override {
    if (d.z() <= 1e-9 || o.z() >= distance_) return {0.01f, 0.01f, 0.01f};
    const double s = (distance_ - o.z()) / d.z();
    const Vec2 p(o.x() + s * d.x(), o.y() + s * d.y());
    switch (usaf_paint(p)) {
      case UsafPaint::kOutside:
        return {0.18f, 0.18f, 0.18f};
      case UsafPaint::kWhite:
        return {0.80f, 0.80f, 0.80f};
      case UsafPaint::kBlack:
        return {0.03f, 0.03f, 0.03f};
    }
    return {0, 0, 0};
  }
  double distance(const Vec3& o, const Vec3& d) const override {
    if (d.z() <= 1e-9 || o.z() >= distance_) return std::numeric_limits<double>::infinity();
    return (distance_ - o.z()) / d.z();
  }
  std::string spec() const override { return fmt::format("usaf:{}", distance_); }

 private:
  double distance_;
};

double parse_number(const std::string& text, const std::string& spec) {
  if (const std::optional<double> v = parse_double(text)) return *v;  // core/parse.h
  throw SceneError(fmt::format("scene '{}': '{}' is not a number", spec, text));
}

}  // namespace

std::unique_ptr<Scene> make_photo_scene(const cv::Mat& equirect, const std::string& spec) {
  return std::make_unique<PhotoScene>(equirect, spec);
}

std::unique_ptr<Scene> make_photo_scene(const std::string& path) {
  if (path.empty()) throw SceneError("photo scene: no path given (use photo:PATH)");
  if (!std::filesystem::exists(path)) throw SceneError(fmt::format("photo scene: '{}' does not exist", path));
  cv::Mat img;
  try {
    img = cv::imread(path, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception&) {
  }
  if (img.empty()) throw SceneError(fmt::format("photo scene: cannot read '{}' as an image", path));
  if (img.cols < 8 || img.rows < 4)
    throw SceneError(fmt::format("photo scene: '{}' is only {}x{} pixels", path, img.cols, img.rows));
  return std::make_unique<PhotoScene>(img, "photo:" + path);
}

std::unique_ptr<Scene> make_usaf_scene(double distance_mm) {
  return std::make_unique<UsafScene>(distance_mm);
}

std::unique_ptr<Scene> make_checker_scene(double radius_mm) {
  return std::make_unique<CheckerScene>(radius_mm);
}

std::unique_ptr<Scene> make_scene(const std::string& spec) {
  const auto colon = spec.find(':');
  const std::string kind = spec.substr(0, colon);
  const bool has_arg = colon != std::string::npos;
  const std::string arg = has_arg ? spec.substr(colon + 1) : "";
  if (kind == "photo") {
    if (!has_arg || arg.empty()) throw SceneError("scene 'photo' needs a path: photo:PATH");
    return make_photo_scene(arg);
  }
  if (kind == "colon" && !has_arg) return make_colon_scene();
  if (kind == "usaf") return make_usaf_scene(has_arg ? parse_number(arg, spec) : 25.0);
  if (kind == "checker") return make_checker_scene(has_arg ? parse_number(arg, spec) : 100.0);
  if (kind == "tube") {
    TubeParams p;
    if (has_arg) p.diameter_mm = parse_number(arg, spec);
    return make_tube_scene(p);
  }
  if (kind == "flat") return make_flat_scene(has_arg ? parse_number(arg, spec) : 0.6);
  if (kind == "room") {
    if (has_arg && arg.empty())
      throw SceneError("scene 'room:' needs a path: room:PATH.json (or plain room)");
    return make_room_scene(arg);
  }
  throw SceneError(
      fmt::format("unknown scene '{}' (use photo:PATH, colon, usaf[:DISTANCE_MM], checker[:RADIUS_MM], "
                  "tube[:DIAMETER_MM], flat[:LEVEL], room or room:PATH.json)",
                  spec));
}

}  // namespace omma::sim
