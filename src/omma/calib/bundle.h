// Geometric calibration, stage 2 of calibrate.h: the Ceres bundle adjustment of the cameras'
// rotations, focal lengths, principal points and radial distortion on feature tracks (model, scene
// points, gauge, priors and passes: calibrate.h). Used by calibrate_rig and calibrate_from_tracks.
#pragma once

#include <array>
#include <optional>
#include <vector>

#include "omma/calib/calibrate.h"

namespace omma::calib {

// What a solve leaves for the subpixel refinement: the tracks it used (observations of uncalibrated
// cameras and short tracks removed, outliers kept) and their scene points (near: (P, h), far: unit
// direction in the first three entries).
struct SolveState {
  std::vector<std::vector<TrackObservation>> tracks;
  std::vector<std::array<double, 4>> points;
  std::optional<std::array<double, 4>> tube_axis;  // the calibration tube's axis (ox, oy, tx, ty), if used;
                                                   // also the start of the next solve's
};

// Steps 4-6 of calibrate_rig on given tracks: cameras with too few observations, bundle
// adjustment, statistics and the calibrated rig. The parameters start from `start` (the nominal rig,
// or a previous solution); the priors refer to `nominal`.
// `res` carries the counts of the earlier stages (matches, inliers, pairs, warnings) through;
// `state` (optional) receives what the subpixel refinement needs.
CalibrationSummary solve_tracks(const Rig& nominal, const Rig& start,
                                std::vector<std::vector<TrackObservation>> tracks, SceneModel scene,
                                const CalibrationOptions& opt, CalibrationSummary res,
                                SolveState* state = nullptr);

}  // namespace omma::calib
