// The shared 24-camera test rig (built by the design stage) and random-texture frames, for the
// renderer's and the live runtime's tests and benchmarks. Camera views of a photograph:
// sim/panorama_views.h.
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/core/rig.h"

namespace omma::testing {

// The shared 24-camera test rig: the thesis's prototype dome (design::thesis_prototype_rig: 3 + 9 + 12
// cameras on a 5 mm dome) with ideal pinhole cameras of width x height pixels and the given angle of
// view (the prototype's own: 64 deg).
Rig test_rig_24(int width = 250, int height = 250, double aov_deg = 64);

// Random-texture 8-bit BGR frames, one per camera (uniform noise blurred to ~2 px features).
std::vector<cv::Mat> random_frames(const Rig& rig, uint32_t seed = 1);

}  // namespace omma::testing
