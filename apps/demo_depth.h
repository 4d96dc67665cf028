// omma demo, the depth section: the depth estimated from the overlaps, the
// panorama without and with it, the boundaries from depth, the numbers, and the engine's
// depth-adaptive rendering of the same frames. Kept apart from demo.cc's other sections.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "omma/core/grid.h"
#include "omma/core/rig.h"

namespace omma::app {

struct DepthDemo {
  std::string markdown, html;  // the report's section
  std::string summary;         // one line for the terminal
  nlohmann::json json;
};

// frames: the cameras' 8-bit frames; truth: the ideal panorama (8-bit); truth_depth: the simulator's
// depth (CV_32FC1 mm); pano_inf: the mrf panorama at infinity (8-bit). Writes depth_estimate.png
// (+ .tiff), depth_truth.png, pano_mrf_depth.png, boundary_depth.png and pano_mrf_engine_depth.png
// into dir.
DepthDemo run_depth_demo(const Rig& rig, const PanoGrid& grid, const std::vector<cv::Mat>& frames,
                         const cv::Mat& truth, const cv::Mat& truth_depth, const cv::Mat& pano_inf,
                         const std::filesystem::path& dir, bool progress);

}  // namespace omma::app
