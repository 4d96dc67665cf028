// Test support for the calibration stage (header only, used by calib tests): a small 24-camera
// test dome, a seeded rig perturbation (normal errors, unlike omma_sim's exact magnitudes), a
// minimal noise-free renderer of camera frames for a far-field scene (an equirect photo at
// infinity), the ideal panorama and PSNR. Kept small on purpose: the accuracy tests use the
// simulator (omma_sim); this serves the PTO tests, which need exact, effect-free frames.
#pragma once

#include <cmath>
#include <random>
#include <string>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "omma/core/grid.h"
#include "omma/core/rig.h"
#include "omma/design/dome.h"

namespace omma::calib::testing {

// 3 + 9 + 12 cameras on a 5 mm hemisphere (the layer counts of the thesis' max-volume dome, Fig.
// 3.8), 250x250 pixels, 64 deg angle of view (f = 200 px).
inline Rig test_dome(int size = 250) {
  const int counts[3] = {3, 9, 12};
  const double thetas[3] = {22, 52, 80};
  std::vector<Vec3> axes;
  for (int layer = 0; layer < 3; ++layer)
    for (int j = 0; j < counts[layer]; ++j)
      axes.push_back(direction_from_spherical(deg2rad(thetas[layer]), 2 * kPi * (j + 0.5 * layer) / counts[layer]));
  return design::radial_rig(axes, 5.0, design::ideal_intrinsics(deg2rad(64), size, size), false, "test",
                            "calib-test-24");
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

// Renders every camera of `rig` looking at the far-field photo (bilinear, no sensor effects).
inline std::vector<cv::Mat> render_frames(const Rig& rig, const cv::Mat& scene) {
  std::vector<cv::Mat> frames;
  for (const auto& c : rig.cameras) {
    const CameraModel m = c.model();
    cv::Mat mx(c.in.height, c.in.width, CV_32F), my(c.in.height, c.in.width, CV_32F);
    for (int r = 0; r < c.in.height; ++r)
      for (int col = 0; col < c.in.width; ++col) {
        const Vec3 w = m.unproject(Vec2(col + 0.5, r + 0.5));
        const cv::Point2f s = equirect_source(scene, w);
        mx.at<float>(r, col) = s.x;
        my.at<float>(r, col) = s.y;
      }
    cv::Mat out;
    cv::remap(scene, out, mx, my, cv::INTER_LINEAR, cv::BORDER_WRAP);
    frames.push_back(out);
  }
  return frames;
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
