// Camera views of a far-field 360-degree photograph: each camera of a rig sees an equirect-full
// panorama (360 x 180 deg, theta 0 at the top, longitude per conventions.h (G1)) at infinity,
// distortion-free pinhole per the rig, bilinear (cv::remap). The `pano:` live source and the
// renderer tests use it; sim/scene.h's photo scene is the full simulator's version of the same.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "omma/core/rig.h"

namespace omma::sim {

// Per-camera remap tables from an equirect-full photograph of size `pano_size` to each camera's
// pixels: CV_32FC2 maps for cv::remap (OpenCV pixel centres); the world turned by yaw_rad about +z.
std::vector<cv::Mat> panorama_to_camera_maps(const Rig& rig, cv::Size pano_size, double yaw_rad = 0);

// Each camera's view of the equirect-full photograph `pano` (8-bit BGR), rotated by yaw_rad about
// the dome axis (the world turning past the dome).
std::vector<cv::Mat> views_of_panorama(const Rig& rig, const cv::Mat& pano, double yaw_rad = 0);

}  // namespace omma::sim
