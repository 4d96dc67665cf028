// `omma bench` workloads: our renderer against OpenCV peers and the memory
// bandwidth bound, on one rig with random-texture frames. Shared by `omma bench` and the Google
// Benchmark program bench/engine_bench.cc.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "omma/core/grid.h"
#include "omma/core/rig.h"
#include "omma/render/compiled_map.h"
#include "omma/render/render.h"

namespace omma::bench {

// One measurable workload: run() renders (or copies) one panorama frame.
struct Workload {
  std::string name;  // e.g. "omma-mrf-1080x1080", "opencv-remap-1080x1080"
  int threads = 0;   // 0 = all
  std::function<void()> run;
  nlohmann::json info;  // extra facts (bytes per pixel, compile time, ...)
};

// Our renderer for the map of `opt` (threads: 0 = all, 1 = one), named "omma-<method><variant>-
// <W>x<H><suffix>". Throws std::logic_error if pano does not implement the method yet. The frames
// are copied into a frame store once.
Workload omma_workload(const Rig& rig, const render::MapOptions& opt, int threads,
                       const std::vector<cv::Mat>& frames, const std::string& variant = "",
                       const std::string& suffix = "");

// The depth-adaptive renderer (depth_render.h): per frame the depth estimate on its
// coarse grid (with the temporal term) and the render with moved taps; named
// "omma-<method>-depth-<W>x<H>".
Workload omma_depth_workload(const Rig& rig, const render::MapOptions& opt,
                             const std::vector<cv::Mat>& frames);

// Our renderer with frames arriving as in the live engine (engine.h): per panorama one camera's new
// frame (round robin over the cameras) is made ready on a camera thread, as the engine's camera
// threads do it (photometric: corrected by that camera's table, isp/photometric.h; otherwise
// copied), concurrently with the render of the panorama on the render threads, and then set into
// the frame store. The tables are the simulator's model of the default sensor
// (sim::true_photometric: 50 % cos^4 vignetting, gains in [0.9, 1.1]). Named
// "omma-<method>-photometric-<W>x<H>" / "omma-<method>-store-<W>x<H>". One camera frame per
// panorama at ~1200 panoramas/s is the thesis's whole camera load (24 cameras at 44-56 frames/s);
// the live engine renders only 30 of those panoramas per second.
Workload omma_live_workload(const Rig& rig, const render::MapOptions& opt, const std::vector<cv::Mat>& frames,
                            bool photometric);

// Peer A: per-camera cv::remap (fixed-point maps from cv::convertMaps, INTER_LINEAR) of every
// camera's frame into its footprint on the panorama, no blending (each camera overwrites).
Workload opencv_remap_workload(const Rig& rig, const PanoGrid& grid, const std::vector<cv::Mat>& frames);

// Peer B: cv::detail::MultiBandBlender (5 bands) fed the warped images and masks of peer A.
Workload opencv_multiband_workload(const Rig& rig, const PanoGrid& grid, const std::vector<cv::Mat>& frames);

// The bandwidth bound: memcpy of the bytes a render of `map` must touch (the whole map, the cache
// lines of the frame store its taps read, the output), split among all threads.
Workload memcpy_workload(const render::CompiledMap& map, const std::string& size_tag);

// Runs w repeatedly for at least min_seconds (and at least min_iterations); returns frames per
// wall-clock second; *cpu_s_per_frame (if given) gets the process CPU time per frame.
double measure_fps(const Workload& w, double min_seconds, int min_iterations = 3,
                   double* cpu_s_per_frame = nullptr);

struct BenchEntry {
  std::string name;
  double fps = 0;  // all rounds together: frames / seconds
  nlohmann::json info;
  std::vector<double> round_fps;  // each round's own fps (run_bench_suite)
};
struct BenchOptions {
  double min_seconds = 2;         // per workload, in all
  int rounds = 5;                 // the workloads are measured in turn, this many slices each
  bool quick = false;             // small sizes (tests)
  bool depth = false;             // also the depth-adaptive mrf renderer beside the static one
  std::vector<std::string> only;  // substrings of names to run; empty = all
  bool IsValid(std::string* why = nullptr) const;  // min_seconds > 0, rounds >= 1
};
// The whole suite of point 4 on the thesis prototype rig (or `rig` if it has cameras). All
// workloads are set up first, then measured in `rounds` interleaved slices of min_seconds / rounds
// each (after one untimed frame per slice), so that a machine whose speed drifts (shared cores,
// other tenants) slows ours and the peers alike and the ratios stay comparable.
std::vector<BenchEntry> run_bench_suite(const Rig& rig, const BenchOptions& opt,
                                        std::vector<std::string>* skipped = nullptr);

// The comparisons for one of our workloads (e.g. "omma-mrf-1080x1080") against the peers
// of the same size in the same run: ours / peer A, ours / peer B, bound / ours (0 where a workload
// is missing), and whether the targets are met (>= 400 fps for mrf at
// 1080x1080, >= 10x peer A, >= 100x peer B, within 2x of the bound).
struct BenchRatio {
  std::string name;
  double fps = 0;
  double vs_remap = 0;      // fps / opencv-remap fps
  double vs_multiband = 0;  // fps / opencv-multiband fps
  double bound_over = 0;    // memcpy-bound fps / fps (1 = at the bound)
  double vs_static = 0;     // depth-adaptive workloads: fps / the static map's fps (same method and size)
  // Per round (where both entries have the same rounds): ours / peer A and ours / peer B of that
  // round alone, which shows how much the ratio moves with the machine's load.
  std::vector<double> vs_remap_rounds, vs_multiband_rounds;
  // "-photometric-" entries: fps over the same method's plain render and over its "-store-"
  // workload (frames entering the store without the correction), whole run and per round.
  double vs_plain = 0, vs_store = 0;
  std::vector<double> vs_plain_rounds, vs_store_rounds;
  nlohmann::json to_json() const;
};
// One BenchRatio per "omma-*" entry with all threads (not the -1thread ones).
std::vector<BenchRatio> bench_ratios(const std::vector<BenchEntry>& entries);

}  // namespace omma::bench
