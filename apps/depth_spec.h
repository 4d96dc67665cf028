// The projection surface a command is given on its command line (--depth of omma stitch, render and
// refocus): "inf", "sphere:R", "truth:FILE" or "estimate[:NEAR,FAR,STEPS]" (pano/surface.h,
// pano/plane_sweep.h), with --depth-pitch for the estimate's grid.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "omma/core/grid.h"
#include "omma/core/rig.h"
#include "omma/pano/plane_sweep.h"

namespace omma::app {

// The depth map (CV_32FC1 of the grid, mm from the dome centre; empty for inf) and the facts for a
// --json summary ("mode", and for an estimate its range, grid, confidence).
struct DepthChoice {
  cv::Mat depth;
  nlohmann::json info;
  pano::DepthEstimate estimate;  // filled for "estimate" (confidence, coarse grid)
};

// The --depth texts every command accepts, for --help.
extern const char* const kDepthSpecHelp;

// --depth-pitch: DEG or "camera" (pano::camera_pitch_deg); sets pitch_deg with factor 0.
void apply_depth_pitch(const std::string& pitch, const Rig& rig, pano::PlaneSweepOptions& so);
// Is `spec` an estimate ("estimate" or "estimate:...")?
bool is_estimate_spec(const std::string& spec);
// Throws std::invalid_argument naming --depth unless `spec` is inf, sphere:..., truth:... or
// estimate[:...] (the values after the colon are checked where they are used).
void check_depth_spec(const std::string& spec);
// The sweep of "estimate" or "estimate:NEAR,FAR,STEPS" (any suffix may be left out): `base` with the
// values the spec names put in. Throws std::invalid_argument naming --depth estimate.
pano::PlaneSweepOptions parse_estimate_spec(const std::string& spec, pano::PlaneSweepOptions base = {});
// The surface of `spec` on `grid`; frames are needed for an estimate only (the sweep's defaults, with
// what the spec and `pitch` name). Throws std::invalid_argument with the option's name for anything
// malformed or a range that excludes the scene.
DepthChoice choose_depth(const std::string& spec, const std::string& pitch, const Rig& rig,
                         const std::vector<cv::Mat>& frames, const PanoGrid& grid);

}  // namespace omma::app
