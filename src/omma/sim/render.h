// The camera renderer and the ground-truth panorama of the dome simulator.
//
// A camera pixel's signal (linear, full scale 1) is
//   S = clip( exposure * gain_c * V(angle) * mean over N x N subpixel rays of radiance + noise )
// quantised to `bits`; the frame written to DIR/cam_XX.png is S encoded with the sRGB curve in 8
// bits, the raw frame (DIR/cam_XX_raw.png) is S as integers 0 .. 2^bits - 1 in an RGGB mosaic.
// Subpixel rays start at the camera's position and go through (col + (i + 0.5) / N, row + (j + 0.5)
// / N) by CameraModel::unproject (eq. 5.21-5.26 inverted), so N x N supersampling is the optical
// blur (a box filter of one pixel). Vignetting V = 1 - strength (1 - cos^4 a), a = angle between the
// ray and the optical axis. Shot noise: Gaussian with variance S * full_scale_electrons (electrons
// -> signal), read noise: Gaussian with sigma read_noise_dn quantiser steps. Per-camera colour
// gains gain_c are drawn uniformly in [1 - color_gain, 1 + color_gain] per channel.
// Everything random is drawn from (seed, camera id, row), so results do not depend on threads.
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/core/grid.h"
#include "omma/core/photometric.h"
#include "omma/core/progress.h"
#include "omma/core/rig.h"
#include "omma/sim/scene.h"

namespace omma::sim {

// Where the dome is in the scene: x_scene = rotation * x_dome + translation_mm. Identity = at rest
// (scene frame = dome frame). The dome's light source sits at the dome centre (translation_mm).
struct DomePose {
  Mat3 rotation = Mat3::Identity();
  Vec3 translation_mm = Vec3::Zero();
};

struct CameraEffects {
  int supersample = 3;                 // N: N x N rays per pixel (optical blur); 1 = one ray at the centre
  double exposure = 1.0;               // scales the radiance before the sensor
  double vignetting = 0.5;             // strength in [0, 1]: V = 1 - strength (1 - cos^4 a)
  double color_gain = 0.10;            // per-channel gains uniform in [1 - g, 1 + g]; 0 = none
  double full_scale_electrons = 4000;  // electrons at signal 1 (shot noise); 0 = no shot noise
  double read_noise_dn = 2.0;          // read noise sigma in quantiser steps (DN); 0 = none
  int bits = 10;                       // quantiser bits (8..16); 0 = no quantisation (float)
  uint64_t seed = 1;                   // noise and gains; the camera id is mixed in
  int shot = 0;                        // exposure index of a static scene: fresh noise, the same gains

  // No vignetting, gains, noise or quantisation; keeps supersample.
  static CameraEffects ideal(int supersample = 1);
};

// The per-camera colour gains (BGR) that `effects` gives camera `camera_id`.
cv::Vec3d camera_gains(const CameraEffects& effects, int camera_id);
// The vignetting V = 1 - strength (1 - cos^4 a) at continuous pixel px of `camera` (a = angle of
// the pixel's ray to the optical axis): the simulator's truth, which calib/photometric.h estimates.
double true_falloff(const RigCamera& camera, const CameraEffects& effects, const Vec2& px);
// The photometric model (core/photometric.h) closest to the simulator's truth for `camera`: its
// gains, and the vignetting polynomial fitted to true_falloff over the pixel centres (minimax in
// the relative error, fit_vignetting; centred, so x = y = 0). The largest relative error |fit /
// truth - 1| over the image in *max_error if given.
Photometric true_photometric(const RigCamera& camera, const CameraEffects& effects,
                             double* max_error = nullptr);

// Mean linear radiance per pixel (CV_32FC3, camera size), before any sensor effect.
cv::Mat render_radiance(const Scene& scene, const RigCamera& camera, const DomePose& pose = {},
                        int supersample = 3);

struct CameraFrame {
  cv::Mat signal;   // CV_32FC3 linear sensor signal in [0, 1] (quantised values q / (2^bits - 1))
  cv::Mat image;    // CV_8UC3 sRGB-encoded frame, as written to DIR/cam_XX.png
  cv::Mat raw;      // CV_16UC1 RGGB Bayer mosaic of the quantised signal (only if want_raw)
  cv::Vec3d gains;  // the colour gains applied (BGR)
};

// Renders one camera of the (possibly moved) dome. The engine animates a scene by calling this
// with a new pose per frame (and a new effects.seed for fresh noise).
CameraFrame render_camera(const Scene& scene, const RigCamera& camera, const DomePose& pose,
                          const CameraEffects& effects, bool want_raw = false);

// Every camera of `rig` (in rig order, cameras in parallel) for one dome pose: one frame of an
// animated sequence. Each camera's noise comes from (effects.seed, camera id): vary effects.seed per
// frame for fresh noise.
std::vector<CameraFrame> render_rig(const Scene& scene, const Rig& rig, const DomePose& pose,
                                    const CameraEffects& effects, bool want_raw = false);

// Sensor effects alone, applied to a linear radiance image (as render_radiance gives).
CameraFrame apply_sensor(const cv::Mat& radiance, const RigCamera& camera, const CameraEffects& effects,
                         bool want_raw = false);

// RGGB mosaic of a 3-channel image: (0,0)=R, (0,1)=G, (1,0)=G, (1,1)=B (row, col). Any depth.
cv::Mat bayer_rggb(const cv::Mat& bgr);

// The ground truth: the ideal panorama seen from the dome centre on `grid`, noise-free, no sensor
// effects, N x N supersampled, sRGB-encoded CV_8UC3 (linear CV_32FC3 from render_truth_linear).
// `progress` (optional) is stepped once per finished row.
cv::Mat render_truth(const Scene& scene, const PanoGrid& grid, const DomePose& pose = {}, int supersample = 2,
                     double exposure = 1.0, Progress* progress = nullptr);
cv::Mat render_truth_linear(const Scene& scene, const PanoGrid& grid, const DomePose& pose = {},
                            int supersample = 2, double exposure = 1.0, Progress* progress = nullptr);

// The ground-truth depth of the truth panorama (pano/surface.h): for every truth pixel, the distance (mm)
// from the dome centre along its centre direction to the surface the truth shows (Scene::distance);
// +infinity where the ray meets nothing within the scene's range (and for far-field scenes).
// CV_32FC1, grid-sized. Written by the simulator as DIR/truth_depth.tiff (32-bit float, mm).
cv::Mat render_truth_depth(const Scene& scene, const PanoGrid& grid, const DomePose& pose = {});

// Truth supersampling that keeps the ray spacing at or below 0.09 deg (the pixel pitch of a
// 4096-wide 360-degree photo): ceil(grid pixel pitch / 0.09 deg), clamped to 1..4. 2 for vr180
// 1080x1080, 4 for vr180 540x540.
int auto_truth_supersample(const PanoGrid& grid);

// Linear CV_32FC3 -> sRGB-encoded CV_8UC3 (clipped to [0, 1]).
cv::Mat encode_srgb8(const cv::Mat& linear);

}  // namespace omma::sim
