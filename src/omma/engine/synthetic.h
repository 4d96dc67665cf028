// Synthetic rigs and camera frames for the engine's tests, benchmarks and the `pano:` source:
// a 24-camera hemispherical rig and camera views rendered from a 360x180 equirect photograph.
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/core/rig.h"

namespace omma::engine {

// 24 cameras (3 + 9 + 12 at polar angles 12, 38 and 70 deg), 250x250 pixels, 64 deg angle of view,
// on a 5 mm dome, image +y pointing away from the dome axis. Used until the thesis prototype rig
// (design stage) is on main.
Rig ring_rig_24(int width = 250, int height = 250, double aov_deg = 64);

// Per-camera remap tables from an equirect-full (360 x 180 deg, theta 0 at the top) photograph of
// size `pano_size` to each camera's pixels: CV_32FC2 maps for cv::remap (OpenCV pixel centres).
std::vector<cv::Mat> panorama_to_camera_maps(const Rig& rig, cv::Size pano_size, double yaw_rad = 0);

// Each camera's view of the equirect-full photograph `pano` (8-bit BGR), rotated by yaw_rad about
// the dome axis (the world turning past the dome); distortion-free pinhole per the rig.
std::vector<cv::Mat> views_of_panorama(const Rig& rig, const cv::Mat& pano, double yaw_rad = 0);

// Random-texture 8-bit BGR frames, one per camera (uniform noise blurred to ~2 px features).
std::vector<cv::Mat> random_frames(const Rig& rig, uint32_t seed = 1);

}  // namespace omma::engine
