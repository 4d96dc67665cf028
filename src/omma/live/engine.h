// The live engine (thesis §5.3): every camera free-running in its own thread into
// a latest-frame buffer, one render loop that takes the newest frame of every camera, renders the
// compiled map and hands the panorama to the sinks. A camera that ends or fails is dropped: the
// map is recompiled in the background without it (its static weights renormalised among the
// others, eq. 2.8 ff.), and until then its last frame is used, so the panorama never stalls.
//
// The latest-frame buffer of a camera is a lock-free triple buffer: the camera publishes a frame
// by swapping one index, the render loop takes the newest one by swapping another, so a camera
// delivering faster than the renderer only overwrites (it can never hold a lock the renderer
// waits for). Cameras beyond `max_camera_threads` share threads (each thread serves its cameras
// in the order their next frames are due).
//
// Latency (the `latency_ms` of EngineSummary, of the progress line and of the live view's
// /stats.json, one figure): the mean age of the camera frames a panorama is made of, on the
// steady clock, from each frame's capture instant to the moment the panorama is rendered (before
// the sinks encode it), averaged over the live cameras of the panorama and then over the
// panoramas. A frame's capture instant is the source's own (sim: sources: the simulated sensor's
// clock) or else the moment the source delivered it.
#pragma once

#include <atomic>
#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "omma/live/sinks.h"
#include "omma/live/sources.h"
#include "omma/render/compiled_map.h"
#include "omma/render/depth_render.h"
#include "omma/render/render.h"

namespace omma::live {

// What one panorama was made of.
struct PanoramaInfo {
  long index = 0;
  Clock::time_point rendered;               // when the render finished
  std::vector<Clock::time_point> captured;  // per rig camera: its frame's capture instant
                                            // (time_point{} for a camera not used)
  double latency_ms = 0;                    // mean age of the frames used (see above)
};

// Statistics over an interval of the run (the last progress interval, about 0.5 s).
struct WindowStats {
  double seconds = 0;
  double fps = 0;             // panoramas/s
  double latency_ms = 0;      // mean frame age of its panoramas
  double render_ms = 0;       // mean render time of its panoramas (as EngineSummary::render_ms_mean)
  double camera_fps_min = 0;  // frames delivered per second by the slowest live camera
  double camera_fps_max = 0;
};

struct EngineOptions {
  render::MapOptions map;
  std::filesystem::path cache_dir;  // empty: no map cache
  double duration_s = 0;            // stop after this long (0: when every source has ended)
  long max_frames = 0;              // stop after this many panoramas (0: no limit)
  double fps = 30;  // panorama rate (0: render whenever a camera has a new frame; else kMinRate..kMaxRate)
  double first_frame_timeout_s = 5;  // a camera without a first frame by then is dropped
  int threads = 0;                   // renderer threads (0: all)
  int max_camera_threads = 64;       // camera threads at most; more cameras share them
  // Depth-adaptive rendering (render/depth_render.h): the depth estimated every panorama on a
  // coarse grid and the taps moved to it (map.method, not sad). A dropped camera's last frame stays
  // in use (no recompile in this mode).
  bool depth = false;
  pano::PlaneSweepOptions depth_sweep = render::engine_sweep_options();
  // Apply the rig's photometric model (vignetting and colour gains, core/photometric.h) to every
  // frame as it arrives, in its camera's thread (per-camera tables, isp/photometric.h), so that the
  // frame store holds corrected frames and the render loop does no extra work.
  bool photometric = true;
  // Called about twice a second from the render loop with the running statistics (to_json()): every
  // figure so far (render_ms_mean, depth estimate_ms_mean, latency_ms, fps ...) and `window`, the
  // last interval. The same JSON goes to every sink's set_stats (the live view's /stats.json).
  std::function<void(const nlohmann::json&)> on_progress;
  // Stops this run when it becomes true (set from any thread; the render loop checks it at every
  // tick and at least every 50 ms): for an engine embedded in another program (the GStreamer
  // element, gst/), where request_stop() would stop every engine of the process. Not owned.
  const std::atomic<bool>* stop = nullptr;
  // Called after every render (before the sinks), from the render loop (tests, measurements).
  std::function<void(const cv::Mat& panorama, const PanoramaInfo&)> on_panorama;
  bool IsValid(std::string* why = nullptr) const;
};

struct DroppedCamera {
  int index = 0;          // rig camera index
  int id = 0;             // camera id
  std::string reason;     // "ended", or the error
  long at_frame = 0;      // panorama frame count when it was dropped
  bool remapped = false;  // a map without it was compiled and in use by the end
};

struct EngineSummary {
  long frames = 0;     // panoramas rendered
  double seconds = 0;  // wall time of the render loop
  double fps = 0;
  double render_ms_mean = 0;       // render time per panorama, ms (running: so far, in the progress
                                   //   statistics; the sinks' set_stats and on_progress see it live)
  double latency_ms = 0;           // mean frame age (see above), mean over the panoramas
  double latency_ms_max = 0;       // the largest mean frame age of one panorama
  double oldest_frame_ms_max = 0;  // the oldest frame used in any panorama
  long camera_frames = 0;          // frames delivered by the cameras
  double camera_fps_min = 0;       // frames/s delivered by the slowest / fastest live camera
  double camera_fps_max = 0;       //   (from its first to its last frame)
  long dropped_frames = 0;         // camera frames overwritten before any panorama used them
  int camera_threads = 0;          // threads the cameras ran on
  int cameras_live = 0;            // cameras not dropped
  WindowStats window;              // the last interval
  std::vector<DroppedCamera> dropped_cameras;
  double map_bytes_per_pixel = 0;
  double map_seconds = 0;
  bool map_from_cache = false;
  double depth_ms_mean = 0;  // depth mode: estimate per panorama (included in render_ms_mean)
  double depth_compile_s = 0;
  nlohmann::json to_json() const;
};

// Runs the engine until the duration, the frame limit or the end of every source. Sources must
// be one per rig camera (rig order). Throws (after stopping every thread and aborting the sinks)
// if a frame has the wrong size, a sink fails, or no camera delivers a frame at all.
EngineSummary run_engine(const Rig& rig, std::vector<std::unique_ptr<CameraSource>> sources,
                         std::vector<std::unique_ptr<Sink>>& sinks, const EngineOptions& opt);

// Stops a running run_engine from another thread (e.g. a signal handler's watcher).
void request_stop();

}  // namespace omma::live
