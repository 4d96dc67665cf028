// The whole simulation: every camera of a rig plus the ground truth, and the frames folder
// (omma/core/frames.h) it is written to:
//   DIR/cam_XX.png        8-bit sRGB frames (render.h), XX = camera id
//   DIR/cam_XX_raw.png    16-bit RGGB Bayer, values 0 .. 2^bits - 1 (with raw = true)
//   DIR/truth.png         the ideal panorama from the dome centre on the truth grid (8-bit sRGB)
//   DIR/truth_depth.tiff  the true depth of every truth pixel: 32-bit float, mm from the dome centre
//                         along the pixel's direction, +inf where nothing lies within the scene's
//                         range (render_truth_depth; `omma stitch --depth truth:FILE` reads it)
//   DIR/rig.json          the nominal rig (what the stitcher is told)
//   DIR/rig_true.json     the rig the frames were rendered with (= rig.json without perturbation)
//   DIR/sim.json          what was simulated: scene, seed, effects, per-camera gains and the
//                         vignetting polynomial closest to the truth (true_photometric), perturbation
// Several shots of a static scene (shots > 1, e.g. the calibration tube, thesis §3.6): the same rig,
// radiance and colour gains, independent sensor noise per shot; written as one frames folder per
// shot, DIR/shot_00, DIR/shot_01, ... (each complete: frames, truth, rigs, sim.json with "shot").
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "omma/sim/perturb.h"
#include "omma/sim/render.h"

namespace omma::sim {

struct SimulateOptions {
  CameraEffects effects;                                // effects.seed is the simulation seed
  PerturbSpec perturb;                                  // errors of the true rig (none by default)
  PanoGrid truth_grid{Projection::kVr180, 1080, 1080};  // grid of truth.png
  int truth_supersample = 0;  // N x N rays per truth pixel; 0: auto_truth_supersample
  bool truth = true;          // render the truth at all
  bool raw = false;           // also produce Bayer raw frames
  DomePose pose;              // where the dome is in the scene
  bool progress = true;       // progress bar on stderr
  int shots = 1;              // exposures of the static scene (>= 1)

  // False (with the reason in *why) when a value lies outside the range the code relies on.
  bool IsValid(std::string* why = nullptr) const;
};

struct SimulateSummary {
  Rig nominal;                                       // the rig given
  Rig true_rig;                                      // the rig rendered (perturbed)
  std::vector<CameraFrame> frames;                   // in rig order (shot 0)
  std::vector<std::vector<CameraFrame>> more_shots;  // shots 1 .. shots-1, each in rig order
  cv::Mat truth;                                     // CV_8UC3 sRGB (empty if options.truth is false)
  cv::Mat truth_depth;  // CV_32FC1 mm (render_truth_depth; empty if options.truth is false)
  double cameras_ms = 0, truth_ms = 0;
};

// Renders everything in memory. Throws std::invalid_argument / RigError on bad options or rig.
SimulateSummary simulate(const Rig& nominal, const Scene& scene, const SimulateOptions& options);

// Writes the frames folder. If `dir` does not exist it is written as a temporary sibling folder
// and renamed at the end (all or nothing); if it exists each file is replaced atomically.
// Throws IoError if `dir` is a file or cannot be written.
void write_frames_folder(const std::filesystem::path& dir, const SimulateSummary& result,
                         const SimulateOptions& options, const Scene& scene);

// The colon cases of the depth tables (tests, `omma demo`, docs/results/depth_table.sh):
// seed s (1, 2, 3, ...) simulates the default colon with effects.seed = s (noise, colour gains) and
// the dome (s - 1) * 12 mm along the tube, so that each seed sees other folds and polyps at other
// distances (`omma simulate --scene colon --seed s --dome-z 12(s-1)`; seed 1 is the demo's scene).
struct ColonCase {
  ColonParams scene;
  SimulateOptions options;  // effects.seed and pose set; everything else default
};
ColonCase colon_case(uint64_t seed);

// Writes DIR/shot_00 .. DIR/shot_<N-1> (N = 1 + result.more_shots.size()), all or nothing.
void write_shots_folder(const std::filesystem::path& dir, const SimulateSummary& result,
                        const SimulateOptions& options, const Scene& scene);
std::string shot_folder_name(int shot);  // "shot_03"

// The content of DIR/sim.json (of shot `shot`).
nlohmann::json simulation_summary(const SimulateSummary& result, const SimulateOptions& options,
                                  const Scene& scene, int shot = 0);

}  // namespace omma::sim
