// Test support (header only, not part of the library): a tiny hemispherical rig and a minimal
// renderer of camera frames and of the ideal panorama, for the pano unit tests and CLI tests until
// (and besides) the simulator. Scene: a far-field environment given as a 360x180 equirectangular
// texture (PanoGrid kEquirectFull convention: phi = 2 pi x / W, theta = pi y / H), optionally with
// one near sphere of uniform colour in front of it (parallax).
#pragma once

#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <string>
#include <vector>

#include "omma/core/frames.h"
#include "omma/core/grid.h"
#include "omma/core/io.h"
#include "omma/core/rig.h"

namespace omma::pano::testing {

// 15 cameras on a 5 mm dome: one at the pole, 6 at theta 45 deg, 8 at theta 80 deg; each
// `px` x `px` pixels, circular AOV `aov_deg`, no distortion. Covers the whole hemisphere.
inline Rig small_rig(int px = 64, double aov_deg = 64, double radius_mm = 5.0) {
  Rig rig;
  rig.name = "test-15";
  rig.dome.radius_mm = radius_mm;
  auto add = [&](double theta_deg, double phi_deg) {
    RigCamera cam;
    cam.id = static_cast<int>(rig.cameras.size());
    const Vec3 t = direction_from_spherical(deg2rad(theta_deg), deg2rad(phi_deg));
    cam.frame = frame_looking_at(t, theta_deg == 0 ? Vec3(1, 0, 0) : Vec3(0, 0, -1));
    cam.position_mm = radius_mm * t;
    cam.in.width = cam.in.height = px;
    cam.in.aov = deg2rad(aov_deg);
    cam.in.fu = cam.in.fv = Intrinsics::focal_for_aov(px, cam.in.aov);
    cam.in.cu = cam.in.cv = px / 2.0;
    rig.cameras.push_back(cam);
  };
  add(0, 0);
  for (int k = 0; k < 6; ++k) add(45, 60.0 * k);
  for (int k = 0; k < 8; ++k) add(80, 22.5 + 45.0 * k);
  return rig;
}

// A smooth procedural environment (low spatial frequencies, so that resampling errors are small).
inline cv::Mat smooth_texture(int width = 720, int height = 360) {
  cv::Mat tex(height, width, CV_32FC3);
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c) {
      const double phi = 2 * kPi * (c + 0.5) / width, theta = kPi * (r + 0.5) / height;
      tex.at<cv::Vec3f>(r, c) = cv::Vec3f(static_cast<float>(0.5 + 0.3 * std::sin(3 * phi) * std::sin(theta)),
                                          static_cast<float>(0.5 + 0.3 * std::cos(2 * theta)),
                                          static_cast<float>(0.5 + 0.25 * std::cos(phi + 4 * theta)));
    }
  return tex;
}

// A 360x180 photograph (e.g. OMMA_DATA_DIR/louvre.jpg), area-downsampled to width x width/2, CV_32FC3.
inline cv::Mat photo_texture(const std::string& path, int width = 720) {
  cv::Mat img = read_image(path, cv::IMREAD_COLOR);
  cv::Mat small;
  cv::resize(img, small, cv::Size(width, width / 2), 0, 0, cv::INTER_AREA);
  return to_float01(small);
}

struct NearSphere {
  Vec3 centre_mm;
  double radius_mm = 1;
  cv::Vec3f colour{1, 1, 1};  // BGR [0,1]
};

// Colour seen from `origin` along unit direction `d`: the sphere if the ray hits it in front,
// otherwise the far-field texture at direction d (bilinear, horizontally periodic).
inline cv::Vec3f trace(const cv::Mat& tex, const std::optional<NearSphere>& sphere, const Vec3& origin,
                       const Vec3& d) {
  if (sphere) {
    const Vec3 oc = origin - sphere->centre_mm;
    const double b = oc.dot(d), c = oc.squaredNorm() - sphere->radius_mm * sphere->radius_mm;
    const double disc = b * b - c;
    if (disc >= 0 && -b - std::sqrt(disc) > 0) return sphere->colour;
  }
  const PanoGrid full{Projection::kEquirectFull, tex.cols, tex.rows};
  const Vec2 p = *full.pixel(d);
  const double x = p.x() - 0.5, y = std::clamp(p.y() - 0.5, 0.0, tex.rows - 1.0);
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const float fx = static_cast<float>(x - x0), fy = static_cast<float>(y - y0);
  auto at = [&](int c, int r) {
    c = ((c % tex.cols) + tex.cols) % tex.cols;
    r = std::clamp(r, 0, tex.rows - 1);
    return tex.at<cv::Vec3f>(r, c);
  };
  return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) +
         fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
}

// One frame per camera, CV_32FC3 [0,1]: each pixel centre unprojected (camera model) and traced
// from the camera centre.
inline std::vector<cv::Mat> render_frames(const Rig& rig, const cv::Mat& tex,
                                          const std::optional<NearSphere>& sphere = std::nullopt) {
  std::vector<cv::Mat> frames;
  for (const auto& cam : rig.cameras) {
    const CameraModel m = cam.model();
    cv::Mat f(cam.in.height, cam.in.width, CV_32FC3);
    for (int r = 0; r < f.rows; ++r)
      for (int c = 0; c < f.cols; ++c)
        f.at<cv::Vec3f>(r, c) = trace(tex, sphere, cam.position_mm, m.unproject(Vec2(c + 0.5, r + 0.5)));
    frames.push_back(f);
  }
  return frames;
}

// The ideal panorama seen from the dome centre, CV_32FC3 [0,1].
inline cv::Mat render_truth(const PanoGrid& grid, const cv::Mat& tex,
                            const std::optional<NearSphere>& sphere = std::nullopt) {
  cv::Mat out(grid.height, grid.width, CV_32FC3);
  for (int r = 0; r < grid.height; ++r)
    for (int c = 0; c < grid.width; ++c)
      out.at<cv::Vec3f>(r, c) = trace(tex, sphere, Vec3::Zero(), grid.pixel_direction(c, r));
  return out;
}

// Writes DIR/rig.json, DIR/cam_XX.png (8-bit) and, if given, DIR/truth.png.
inline void write_frames_folder(const std::filesystem::path& dir, const Rig& rig,
                                const std::vector<cv::Mat>& frames, const cv::Mat& truth = {}) {
  std::filesystem::create_directories(dir);
  save_rig(rig, dir / "rig.json");
  for (size_t i = 0; i < frames.size(); ++i)
    write_image(dir / frame_filename(rig.cameras[i].id), to_u8(frames[i]));
  if (!truth.empty()) write_image(dir / "truth.png", to_u8(truth));
}

}  // namespace omma::pano::testing
