// Test support for the calibration stage (header only, used by calib tests): a small 24-camera
// test dome, a seeded rig perturbation, a minimal renderer of camera frames for a far-field scene
// (an equirect photo at infinity) and for a near-field closed tube (the 35 mm calibration tube of
// §3.6), a nearest-camera panorama render and PSNR. Kept small on purpose: the simulator (omma_sim)
// is the full renderer.
#pragma once

#include <cmath>
#include <random>
#include <string>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "omma/core/grid.h"
#include "omma/core/rig.h"

namespace omma::calib::testing {

// 3 + 9 + 12 cameras on a 5 mm hemisphere (the layer counts of the thesis' max-volume dome, Fig.
// 3.8), 250x250 pixels, 64 deg angle of view (f = 200 px).
inline Rig test_dome(int size = 250) {
  Rig rig;
  rig.name = "calib-test-24";
  rig.dome.radius_mm = 5;
  rig.dome.method = "test";
  const int counts[3] = {3, 9, 12};
  const double thetas[3] = {22, 52, 80};
  int id = 0;
  for (int layer = 0; layer < 3; ++layer)
    for (int j = 0; j < counts[layer]; ++j) {
      RigCamera c;
      c.id = id++;
      const double phi = 2 * kPi * (j + 0.5 * layer) / counts[layer];
      const Vec3 t = direction_from_spherical(deg2rad(thetas[layer]), phi);
      c.frame = frame_looking_at(t, Vec3(0, 0, -1));
      c.position_mm = 5.0 * t;
      c.in.width = c.in.height = size;
      c.in.aov = deg2rad(64);
      c.in.fu = c.in.fv = Intrinsics::focal_for_aov(size, c.in.aov);
      c.in.cu = c.in.cv = size / 2.0;
      rig.cameras.push_back(c);
    }
  return rig;
}

struct Perturbation {
  double orient_deg = 2;   // RMS rotation angle per camera
  double focal = 0.03;     // relative RMS focal change (fu and fv together)
  double center_px = 5;    // RMS principal point displacement
  double k1 = 0.05;        // RMS added k1
};

inline Rig perturb(const Rig& nominal, const Perturbation& p, unsigned seed = 7) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, 1);
  Rig rig = nominal;
  for (auto& c : rig.cameras) {
    const Vec3 aa = Vec3(g(rng), g(rng), g(rng)) * deg2rad(p.orient_deg) / std::sqrt(3.0);
    const Mat3 r = Eigen::AngleAxisd(aa.norm(), aa.normalized()).toRotationMatrix();
    // Rotate the camera in its own frame: new rows = r * old rows.
    const Mat3 m = r * c.frame.dome_to_camera();
    c.frame.t = m.row(0).transpose();
    c.frame.u = m.row(1).transpose();
    c.frame.v = m.row(2).transpose();
    const double s = 1 + p.focal * g(rng);
    c.in.fu *= s;
    c.in.fv *= s;
    c.in.cu += p.center_px / std::sqrt(2.0) * g(rng);
    c.in.cv += p.center_px / std::sqrt(2.0) * g(rng);
    c.in.k[0] += p.k1 * g(rng);
  }
  return rig;
}

// The equirect photo (360 x 180 deg, theta 0 at the top, phi 0..360 left to right), downsampled.
inline cv::Mat load_scene(const std::string& path, int width = 2048) {
  cv::Mat img = cv::imread(path, cv::IMREAD_COLOR);
  if (img.empty()) return img;
  cv::resize(img, img, cv::Size(width, width / 2), 0, 0, cv::INTER_AREA);
  return img;
}

// Scene lookup for a direction (far field) through an equirect photo: continuous source pixel.
inline cv::Point2f equirect_source(const cv::Mat& scene, const Vec3& w) {
  const Spherical s = spherical_from_direction(w);
  return {static_cast<float>(s.phi / (2 * kPi) * scene.cols - 0.5),
          static_cast<float>(s.theta / kPi * scene.rows - 0.5)};
}

// Closed tube (near field): radius R mm around the dome axis, closed at z = cap_mm. The wall is
// textured with the photo wrapped around it (phi -> columns, z -> rows over 0..height_mm), the cap
// with the photo's middle band mapped in x, y.
struct Tube {
  double radius_mm = 17.5;
  double cap_mm = 25;
  double bottom_mm = -5;
};

inline cv::Point2f tube_source(const cv::Mat& scene, const Tube& tube, const Vec3& o, const Vec3& d) {
  // Cap plane first.
  if (d.z() > 1e-9) {
    const double s = (tube.cap_mm - o.z()) / d.z();
    const Vec3 p = o + s * d;
    if (p.head<2>().norm() <= tube.radius_mm)
      return {static_cast<float>((p.x() / tube.radius_mm * 0.5 + 0.5) * scene.cols * 0.3 + 0.35 * scene.cols - 0.5),
              static_cast<float>((p.y() / tube.radius_mm * 0.5 + 0.5) * scene.rows * 0.6 + 0.2 * scene.rows - 0.5)};
  }
  const double a = d.x() * d.x() + d.y() * d.y();
  const double b = 2 * (o.x() * d.x() + o.y() * d.y());
  const double c = o.x() * o.x() + o.y() * o.y() - tube.radius_mm * tube.radius_mm;
  const double s = (-b + std::sqrt(std::max(0.0, b * b - 4 * a * c))) / (2 * a);
  const Vec3 p = o + s * d;
  double phi = std::atan2(p.y(), p.x());
  if (phi < 0) phi += 2 * kPi;
  const double v = (p.z() - tube.bottom_mm) / (tube.cap_mm - tube.bottom_mm);
  return {static_cast<float>(phi / (2 * kPi) * scene.cols - 0.5),
          static_cast<float>((0.1 + 0.8 * std::clamp(v, 0.0, 1.0)) * scene.rows - 0.5)};
}

// Renders every camera of `rig`: far field (tube == nullptr) or the tube.
inline std::vector<cv::Mat> render_frames(const Rig& rig, const cv::Mat& scene, const Tube* tube = nullptr) {
  std::vector<cv::Mat> frames;
  for (const auto& c : rig.cameras) {
    const CameraModel m = c.model();
    cv::Mat mx(c.in.height, c.in.width, CV_32F), my(c.in.height, c.in.width, CV_32F);
    for (int r = 0; r < c.in.height; ++r)
      for (int col = 0; col < c.in.width; ++col) {
        const Vec3 w = m.unproject(Vec2(col + 0.5, r + 0.5));
        const cv::Point2f s = tube ? tube_source(scene, *tube, c.position_mm, w) : equirect_source(scene, w);
        mx.at<float>(r, col) = s.x;
        my.at<float>(r, col) = s.y;
      }
    cv::Mat out;
    cv::remap(scene, out, mx, my, cv::INTER_LINEAR, cv::BORDER_WRAP);
    frames.push_back(out);
  }
  return frames;
}

// Nearest-camera panorama (far field): each grid direction from the camera whose optical axis is
// closest, bilinear sample; pixels no camera sees stay black and are 0 in `mask`.
inline cv::Mat render_panorama(const Rig& rig, const std::vector<cv::Mat>& frames, const PanoGrid& grid,
                               cv::Mat* mask = nullptr) {
  cv::Mat out(grid.height, grid.width, CV_8UC3, cv::Scalar::all(0));
  if (mask) *mask = cv::Mat(grid.height, grid.width, CV_8U, cv::Scalar(0));
  for (int r = 0; r < grid.height; ++r)
    for (int col = 0; col < grid.width; ++col) {
      const Vec3 w = grid.pixel_direction(col, r);
      int best = -1;
      double best_dot = -2;
      Vec2 best_px;
      for (size_t i = 0; i < rig.cameras.size(); ++i) {
        const CameraModel m = rig.cameras[i].model();
        const double d = w.dot(m.frame.t);
        if (d <= best_dot || !m.sees(w)) continue;
        const auto px = m.project(w);
        if (!px || !m.inside(*px)) continue;
        best = static_cast<int>(i), best_dot = d, best_px = *px;
      }
      if (best < 0) continue;
      cv::Mat pix;
      cv::getRectSubPix(frames[best], cv::Size(1, 1),
                        cv::Point2f(static_cast<float>(best_px.x() - 0.5), static_cast<float>(best_px.y() - 0.5)), pix);
      out.at<cv::Vec3b>(r, col) = pix.at<cv::Vec3b>(0, 0);
      if (mask) mask->at<uchar>(r, col) = 255;
    }
  return out;
}

// The ideal far-field panorama straight from the photo.
inline cv::Mat render_truth(const cv::Mat& scene, const PanoGrid& grid) {
  cv::Mat mx(grid.height, grid.width, CV_32F), my(grid.height, grid.width, CV_32F);
  for (int r = 0; r < grid.height; ++r)
    for (int col = 0; col < grid.width; ++col) {
      const cv::Point2f s = equirect_source(scene, grid.pixel_direction(col, r));
      mx.at<float>(r, col) = s.x;
      my.at<float>(r, col) = s.y;
    }
  cv::Mat out;
  cv::remap(scene, out, mx, my, cv::INTER_LINEAR, cv::BORDER_WRAP);
  return out;
}

// PSNR (dB, peak 255) over the pixels where mask != 0.
inline double psnr(const cv::Mat& a, const cv::Mat& b, const cv::Mat& mask) {
  double sum = 0;
  long n = 0;
  for (int r = 0; r < a.rows; ++r)
    for (int c = 0; c < a.cols; ++c) {
      if (!mask.at<uchar>(r, c)) continue;
      const cv::Vec3b pa = a.at<cv::Vec3b>(r, c), pb = b.at<cv::Vec3b>(r, c);
      for (int k = 0; k < 3; ++k) sum += (double(pa[k]) - pb[k]) * (double(pa[k]) - pb[k]);
      n += 3;
    }
  return n ? 10 * std::log10(255.0 * 255.0 / std::max(sum / n, 1e-12)) : 0;
}

}  // namespace omma::calib::testing
