// Photometric calibration: each camera's vignetting and colour gains (the model
// of core/photometric.h) estimated from the images themselves.
//
// Lens model of the estimation. The cameras of a dome carry the same lens, and a lens's falloff is
// a function of the angle a between the ray and the optical axis (cos^4 law, mechanical
// vignetting, both symmetric about the axis), not of the pixel radius: two cameras whose focal
// lengths differ have different falloffs at the same pixel radius. So the estimation
// fits ONE falloff of the ray angle for all cameras,
//   V(a) = 1 + beta1 q + ... + beta5 q^5,   q = tan^2 a   (from each camera's calibrated model),
// and per camera and channel a gain; then each camera's falloff is written in Hugin's pixel-radius
// model (b, c, d about the principal point: x = cu - W/2, y = cv - H/2) by the minimax fit over
// its pixels (core/photometric.h fit_vignetting; the largest relative error is reported as
// PhotometricSummary::max_fit_error). Five terms, because a cubic in q fitted by least squares
// misses cos^4 = (1 + q)^-2 in the corners (measured figures: docs/results/tuning-photometric.md).
//
// From overlaps (calibrate_photometric): cameras whose images overlap see the same scene radiance
// L along the same direction (far field; the stitcher's own assumption, pano/), so for a sample
// direction w seen at pixel p_a of camera a and p_b of camera b, per channel c:
//   log I_a,c(p_a) - log I_b,c(p_b) = log g_a,c + log V(a_a) - log g_b,c - log V(a_b)
// (I = linear signal, sRGB decoded, lightly smoothed). Samples are taken on a grid of camera a's
// pixels that camera b sees (the whole image, corners included: they hold most of the falloff),
// and kept only where both are well registered and well exposed: every channel inside
// [min_signal, max_signal] (saturation and black), away from saturated pixels, and a small log
// gradient (|grad log I| * registration_px < max_log_change: a misregistration of the geometric
// calibration or parallax changes the value little there). A Cauchy loss (scale loss_scale, log
// units) handles what remains (occlusion, parallax in the near field, moving things). Gauge: the
// overlaps fix only ratios of gains within each channel, so each channel's geometric mean gain
// over the calibrated cameras is held at 1 (the panorama's white balance is the scene's: an
// overall colour cast cannot be told from the scene's colour). Several frame sets (e.g. shots)
// add their samples.
//
// From a flat field (calibrate_flat_field): a uniformly lit white target, every camera sees the
// same radiance everywhere: I_c(p) = g_c V(a(p)) L, fitted directly per camera (the same angle
// polynomial, a separate one per camera: there is data everywhere), gains up to ONE global scale
// (the geometric mean of all gains over cameras and channels is 1: the target is white).
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/core/rig.h"

namespace omma::calib {

struct PhotometricOptions {
  int grid_step_px = 3;             // overlap samples on a grid of this pitch in camera a
  double smooth_sigma_px = 1.5;     // Gaussian smoothing of the linear images before sampling
  double min_signal = 0.003;        // linear, every channel of both samples above ...
  double max_signal = 0.9;          // ... and below (saturation: the smoothing spreads it)
  double registration_px = 0.3;     // assumed misregistration, pixels (more than a calibrated
                                    // far-field rig's: the margin covers parallax of distant objects)
  double max_log_change = 0.05;     // keep samples whose log value changes less than this over
                                    // registration_px (every channel, both cameras); tuning:
                                    // docs/results/tuning-photometric.md
  double loss_scale = 0.03;         // Cauchy scale, log units (3 %)
  double noise_signal = 0.01;       // linear signal at which a sample's weight is 1/sqrt(2): weight =
                                    // s / sqrt(s^2 + noise_signal^2), s = its darkest channel (dark
                                    // samples are noisy and biased in log units); 0 = equal weights
  int min_samples = 300;            // a camera with fewer samples keeps gain 1 (warning; its
                                    // falloff is the lens's, which every camera shares)
  int max_samples_per_pair = 6000;  // evenly thinned beyond this
  bool estimate_vignetting = true;  // false: gains only (V = 1)
  int threads = 2;                  // Ceres threads
  int max_iterations = 100;

  bool IsValid(std::string* why = nullptr) const;
};

struct PhotometricSummary {
  static constexpr int kLensTerms = 5;
  Rig rig;                                // the input rig with each camera's photometric model set
  std::array<double, kLensTerms> lens{};  // beta of the shared V(a) (overlaps), or the mean (flat)
  int pairs = 0;                          // overlapping camera pairs sampled
  int samples = 0;                        // samples in the fit (all frame sets)
  double rms_log = 0;                     // RMS residual (log units) of the samples after the fit
  double initial_rms_log = 0;             // the same with V = 1 and unit gains
  double max_fit_error = 0;               // largest |V_pixel_model - V_angle_model| over all cameras' pixels
  std::vector<int> samples_per_camera;    // rig order
  std::vector<int> uncalibrated_ids;      // cameras left at gain 1 (too few samples)
  std::vector<std::string> warnings;
};

// From the overlaps of one or more frame sets of `rig` (each a vector of frames in rig order,
// CV_8UC3 or CV_16UC3 sRGB, the cameras' sizes). Throws std::invalid_argument on bad input
// (sizes, counts, options), std::runtime_error if no pair has enough samples.
PhotometricSummary calibrate_photometric(const Rig& rig, const std::vector<std::vector<cv::Mat>>& frame_sets,
                                         const PhotometricOptions& opt = {});

// From flat-field frame sets (uniformly lit white target; several sets are averaged). Throws
// std::invalid_argument on bad input (wrong size or count), std::runtime_error if a camera's flat
// frame is too dark or saturated to fit (names the camera).
PhotometricSummary calibrate_flat_field(const Rig& rig, const std::vector<std::vector<cv::Mat>>& flat_sets,
                                        const PhotometricOptions& opt = {});

// The falloff polynomial of the ray angle, beta = (beta1, ..., beta5), written in the pixel
// radius model of `camera` (centred on its principal point), by the minimax fit over its pixels
// (core/photometric.h fit_vignetting).
// *max_error gets the largest relative difference over the image.
Photometric photometric_from_lens(const RigCamera& camera,
                                  const std::array<double, PhotometricSummary::kLensTerms>& beta,
                                  const std::array<double, 3>& gains, double* max_error = nullptr);

// Classic flat-fielding, no model and no geometry needed: each frame (sRGB 8/16-bit) divided in
// linear light by its camera's flat field (the flat sets averaged, smoothed by a Gaussian of
// sigma_px against noise, normalised to 1 at its brightest), encoded again as 16-bit sRGB.
// Removes vignetting and colour gains before the geometric calibration, whose patch alignment a
// brightness ramp across a patch biases (docs/near_field_calibration.md). Throws
// std::invalid_argument on mismatched counts or sizes.
std::vector<cv::Mat> flat_field_frames(const std::vector<cv::Mat>& frames,
                                       const std::vector<std::vector<cv::Mat>>& flat_sets,
                                       double sigma_px = 3);

// Linear frames: sRGB 8- or 16-bit -> CV_32FC3 linear light in [0, 1].
cv::Mat decode_linear(const cv::Mat& srgb);

}  // namespace omma::calib
