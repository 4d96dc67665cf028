// omma run: the live panoramic video engine (issue 5 point 3, thesis §5.3-5.4).
#include <csignal>
#include <cstdio>
#include <iostream>
#include <unistd.h>

#include <fmt/format.h>
#include <opencv2/core/utility.hpp>

#include "apps/command.h"
#include "omma/core/grid.h"
#include "omma/core/progress.h"
#include "omma/core/rig.h"
#include "omma/engine/engine.h"

namespace omma::app {
namespace {
extern "C" void on_signal(int) { engine::request_stop(); }
}  // namespace

void add_run_command(CLI::App& root) {
  auto* cmd = root.add_subcommand(
      "run",
      "Live panoramic video: free-running camera sources -> compiled map -> fast renderer -> sinks.\n"
      "Sources (one per camera in rig order, or one for all): DIR (image sequence), FILE.mp4|mkv|avi "
      "(video), /dev/videoN or v4l2:N (V4L2), frames:DIR (cam_XX.png stills), pano:IMAGE[@DEG_S] "
      "(views of a turning 360x180 photograph), a pattern with {id} (two-digit camera id).\n"
      "Sinks: FILE.mp4|mkv|avi, png:DIR or DIR/, cam:ID:SINK (one camera passed through), "
      "http:PORT (live view on 127.0.0.1: / page, /stream.mjpg MJPEG).\n"
      "A camera that ends or fails is dropped and the map recompiled without it. Ctrl-C stops cleanly.");
  struct Opts {
    std::string rig, method = "linear", projection = "vr180", size = "1080x1080", cache;
    std::vector<std::string> sources, sinks;
    double duration = 0, fps = 30, source_fps = 30, first_timeout = 10, min_weight = engine::MapOptions{}.min_weight;
    long frames = 0;
    int threads = 0;
    bool loop = false, json = false, no_cache = false;
  };
  static Opts o;
  cmd->add_option("--rig", o.rig, "Rig file (JSON)")->required();
  cmd->add_option("--source", o.sources, "Camera sources (see above)")->required();
  cmd->add_option("--sink", o.sinks, "Outputs (see above); none: render and measure only");
  cmd->add_option("--method", o.method, "Blending: nn, linear, gaussian, mrf, mrf-spherical, sad (per-frame weights, own kernel); default linear");
  cmd->add_option("--projection", o.projection, "Panorama projection: vr180, equirect, equirect-full (default vr180)");
  cmd->add_option("--size", o.size, "Panorama size WxH, pixels (default 1080x1080)");
  cmd->add_option("--min-weight", o.min_weight,
                  "Drop taps lighter than this fraction of a pixel's weight, renormalising the others "
                  "(faster, smaller map; 0 = keep all; default 1/20 = 0.05)")
      ->check(CLI::Range(0.0, 0.49));
  cmd->add_option("--duration", o.duration, "Stop after S seconds (default: when every source has ended)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--frames", o.frames, "Stop after N panoramas (default: no limit)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--fps", o.fps, "Panorama rate, frames/s (0: whenever a camera has a new frame; default 30)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--source-fps", o.source_fps,
                  "Rate of image sequences, stills and pano: sources, frames/s (0: as fast as possible; default 30)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--first-frame-timeout", o.first_timeout,
                  "A camera without a first frame after this many seconds is dropped (default 10)")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--loop", o.loop, "Restart image sequences and video files at their end");
  cmd->add_option("--threads", o.threads, "Renderer threads (0: all; default 0)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--cache", o.cache, "Map cache folder (default $OMMA_CACHE_DIR or ~/.cache/omma)");
  cmd->add_flag("--no-cache", o.no_cache, "Do not read or write the map cache");
  cmd->add_flag("--json", o.json, "Print only the JSON summary on stdout (no progress line)");
  cmd->callback([] {
    set_json_mode(o.json);
    const Rig rig = load_rig(o.rig);
    engine::EngineOptions eo;
    eo.map.method = pano::parse_method(o.method);
    const Size2 size = parse_size(o.size);
    eo.map.grid = PanoGrid{parse_projection(o.projection), size.width, size.height};
    eo.map.min_weight = o.min_weight;
    eo.cache_dir = o.no_cache ? std::filesystem::path() : (o.cache.empty() ? engine::default_cache_dir() : std::filesystem::path(o.cache));
    eo.duration_s = o.duration;
    eo.max_frames = o.frames;
    eo.fps = o.fps;
    eo.threads = o.threads;
    eo.first_frame_timeout_s = o.first_timeout;
    engine::SourceOptions so;
    so.fps = o.source_fps;
    so.loop = o.loop;
    auto sources = engine::open_sources(rig, o.sources, so);
    std::vector<std::unique_ptr<engine::Sink>> sinks;
    engine::SinkOptions sk;
    sk.fps = o.fps > 0 ? o.fps : 30;
    sk.projection = eo.map.grid.projection;
    sk.spherical_metadata = true;  // 360-degree metadata in mp4 and png outputs
    try {
      for (const auto& s : o.sinks)
        sinks.push_back(engine::open_sink(s, rig, cv::Size(size.width, size.height), sk));
    } catch (...) {
      for (auto& s : sinks) s->abort();
      throw;
    }
    const bool show = !o.json && progress_enabled();
    const bool tty = isatty(2);
    eo.on_progress = [show, tty](const nlohmann::json& j) {
      if (!show) return;
      const std::string line = fmt::format(
          "omma run: {} frames  {:.1f} fps  latency {:.1f} ms  dropped frames {}  cameras live {}",
          j["frames"].get<long>(), j["fps"].get<double>(), j["latency_ms"].get<double>(),
          j["dropped_frames"].get<long>(), j["cameras_live"].get<long>());
      std::fprintf(stderr, tty ? "\r%s\033[K" : "%s\n", line.c_str());
    };
    // Sources and sinks run in their own threads; OpenCV's own parallelism inside them would only
    // compete with the renderer's threads.
    cv::setNumThreads(1);
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    const engine::EngineStats st = engine::run_engine(rig, std::move(sources), sinks, eo);
    std::signal(SIGINT, SIG_DFL);
    std::signal(SIGTERM, SIG_DFL);
    if (show && tty) std::fprintf(stderr, "\n");
    nlohmann::json j = st.to_json();
    j["method"] = o.method;
    j["min_weight"] = o.min_weight;
    j["projection"] = o.projection;
    j["size"] = o.size;
    nlohmann::json sk_names = nlohmann::json::array();
    for (const auto& s : sinks) sk_names.push_back(s->describe());
    j["sinks"] = sk_names;
    print_json(j);
  });
}

}  // namespace omma::app
