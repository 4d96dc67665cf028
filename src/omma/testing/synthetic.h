// Synthetic rigs and frames for the renderer's and the live runtime's tests and benchmarks: a
// 24-camera hemispherical rig and random-texture frames. Camera views of a photograph:
// sim/panorama_views.h.
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/core/rig.h"

namespace omma::testing {

// 24 cameras (3 + 9 + 12 at polar angles 12, 38 and 70 deg), 250x250 pixels, 64 deg angle of view,
// on a 5 mm dome, image +y pointing away from the dome axis.
Rig ring_rig_24(int width = 250, int height = 250, double aov_deg = 64);

// Random-texture 8-bit BGR frames, one per camera (uniform noise blurred to ~2 px features).
std::vector<cv::Mat> random_frames(const Rig& rig, uint32_t seed = 1);

}  // namespace omma::testing
