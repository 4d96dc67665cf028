// omma run: the live panoramic video engine (thesis §5.3-5.4).
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <iostream>

#include <fmt/format.h>
#include <opencv2/core/utility.hpp>
#include <spdlog/spdlog.h>

#include "apps/command.h"
#include "omma/core/grid.h"
#include "omma/core/parse.h"
#include "omma/core/progress.h"
#include "omma/core/rig.h"
#include "omma/core/valid.h"
#include "omma/design/prototype.h"
#include "omma/io/video_writer.h"
#include "omma/live/engine.h"

namespace omma::app {
namespace {
extern "C" void on_signal(int) { live::request_stop(); }

// "MIN-MAX" or "F" (frames/s).
void parse_fps_range(const std::string& text, double* lo, double* hi) {
  const size_t dash = text.find('-', 1);
  const std::optional<double> a = parse_double(text.substr(0, dash));  // core/parse.h
  const std::optional<double> b = dash == std::string::npos ? a : parse_double(text.substr(dash + 1));
  if (a && b) {
    *lo = *a, *hi = *b;
    return;
  }
  throw std::invalid_argument("--sim-fps '" + text +
                              "': expected MIN-MAX or one rate, frames/s (e.g. 44-56)");
}
}  // namespace

void add_run_command(CLI::App& root) {
  auto* cmd = root.add_subcommand(
      "run",
      "Live panoramic video: free-running camera sources -> compiled map -> fast renderer -> sinks.\n"
      "Sources (one per camera in rig order, or one for all): DIR (image sequence), FILE.mp4|mkv|avi "
      "(video), /dev/videoN or v4l2:N (V4L2), frames:DIR (cam_XX.png stills), pano:IMAGE[@DEG_S] "
      "(views of a turning 360x180 photograph), sim:SCENE[@SPEED] (the simulator: colon, room[:PATH], "
      "photo:PATH, "
      "usaf, checker; free-running cameras at 44-56 fps, a loop pre-rendered at start-up), link:FILE or "
      "FILE.bin "
      "(raw sensor link), gst:PIPELINE (any GStreamer pipeline ending in raw video: RTSP/IP cameras, "
      "v4l2src, files of any container; a camera that errors or stalls for --stall-timeout is dropped), a "
      "pattern with {id} (two-digit camera id).\n"
      "Sinks: FILE.mp4|mov|mkv|webm|avi (H.264, VP9 in webm; 360-degree metadata), - (raw bgr24 frames on "
      "stdout, for ffmpeg), png:DIR or DIR/, cam:ID:SINK (one camera passed through), "
      "http:PORT (live view on 127.0.0.1, or --bind: / 360-degree viewer, /stream.mjpg MJPEG, /frame.jpg, "
      "/stats.json), rtsp://HOST:PORT/PATH (an RTSP server, H.264), srt://HOST:PORT[?mode=caller] (H.264 in "
      "MPEG-TS over SRT, a listener by default; neither carries 360-degree metadata).\n"
      "Latency = mean age of a panorama's camera frames when it is rendered (docs/guide/live.md).\n"
      "A camera that ends or fails is dropped and the map recompiled without it. Ctrl-C, SIGTERM or SIGHUP "
      "stops "
      "cleanly and leaves playable videos.");
  struct Opts {
    std::string rig, method = "linear", projection = "vr180", size = "1080x1080", cache, sim_fps = "44-56";
    std::vector<std::string> sources, sinks;
    double duration = 0, fps = 30, source_fps = 30, first_timeout = 10, stall = live::SourceOptions{}.stall_s,
           min_weight = render::MapOptions{}.min_weight;
    double sim_jitter = live::SimCameraOptions{}.jitter_ms, sim_loop = live::SimCameraOptions{}.loop_s;
    long frames = 0;
    int threads = 0, camera_threads = live::EngineOptions{}.max_camera_threads,
        max_streams = live::SinkOptions{}.max_streams;
    bool loop = false, json = false, no_cache = false, depth = false, no_photometric = false;
  };
  static Opts o;
  static std::string bind = live::SinkOptions{}.bind, token = "auto";  // live view: --bind, --token
  cmd->add_option("--rig", o.rig, "Rig file (JSON)")->required();
  cmd->add_option("--source", o.sources, "Camera sources (see above)")->required();
  cmd->add_option("--sink", o.sinks, "Outputs (see above); none: render and measure only");
  cmd->add_option("--method", o.method,
                  "Blending: nn, linear, gaussian, mrf, mrf-spherical, sad (per-frame weights, own kernel); "
                  "default linear");
  cmd->add_option("--projection", o.projection,
                  "Panorama projection: vr180, equirect, equirect-full (default vr180)");
  cmd->add_option("--size", o.size, "Panorama size WxH, pixels (default 1080x1080)");
  cmd->add_option("--min-weight", o.min_weight,
                  "Drop taps lighter than this fraction of a pixel's weight, renormalising the others "
                  "(faster, smaller map; 0 = keep all; default 1/20 = 0.05)")
      ->check(CLI::Range(0.0, 0.49));
  cmd->add_option("--duration", o.duration, "Stop after S seconds (default: when every source has ended)")
      ->check(CLI::Range(0.0, 1e7));
  cmd->add_option("--frames", o.frames, "Stop after N panoramas (default: no limit)")
      ->check(CLI::Range(0, INT32_MAX));
  cmd->add_option("--fps", o.fps,
                  "Panorama rate, frames/s (0: whenever a camera has a new frame; default 30)")
      ->check(CLI::Range(0.0, live::kMaxRate));
  cmd->add_option(
         "--source-fps", o.source_fps,
         "Rate of image sequences, stills and pano: sources, frames/s (0: as fast as possible; default 30)")
      ->check(CLI::Range(0.0, live::kMaxRate));
  cmd->add_option("--first-frame-timeout", o.first_timeout,
                  "A camera without a first frame after this many seconds is dropped (default 10)")
      ->check(CLI::Range(1e-3, 1e6));
  cmd->add_option("--stall-timeout", o.stall,
                  "A gst: camera that delivers no new frame for this many seconds fails and is dropped "
                  "(default 5)")
      ->check(CLI::Range(1e-3, 1e6));
  cmd->add_flag(
      "--depth", o.depth,
      "Depth-adaptive rendering: the scene's depth estimated from the overlaps every\n"
      "panorama on a coarse grid (sphere sweep, ZNCC, semi-global, temporal), each pixel's taps moved\n"
      "to where the cameras see its surface point (not with sad)");
  cmd->add_option(
      "--sim-fps", o.sim_fps,
      "sim: sources: the cameras' rates, frames/s, MIN-MAX (each camera draws its own) or one value "
      "(default 44-56, the thesis's sensors)");
  cmd->add_option("--sim-jitter", o.sim_jitter,
                  "sim: sources: standard deviation of each frame's capture instant, ms (default 0.5)")
      ->check(CLI::Range(0.0, 1000.0));
  cmd->add_option("--sim-loop", o.sim_loop,
                  "sim: sources: length of the pre-rendered loop = period of the back-and-forth motion, s "
                  "(default 1; memory and start-up time grow with it: 3 bytes per camera pixel per frame)")
      ->check(CLI::Range(0.01, 3600.0));
  cmd->add_option("--camera-threads", o.camera_threads,
                  "Camera threads at most; more cameras share them (default 64)")
      ->check(CLI::Range(1, 4096));
  cmd->add_option("--max-streams", o.max_streams,
                  "Live view: concurrent /stream.mjpg viewers (each open page is one); the next one gets "
                  "503 (default 8)")
      ->check(CLI::Range(1, 256));
  cmd->add_option("--bind", bind,
                  "Live view: the address to serve on, numeric IPv4 or IPv6 (0.0.0.0 or :: = every "
                  "interface; default 127.0.0.1, this machine only). Other than loopback: a warning, and "
                  "the URLs need a random token (see --token)");
  cmd->add_option("--token", token,
                  "Live view: auto (a random 128-bit token required in every URL, ?token=..., when --bind "
                  "is not loopback), random (always), none (never, even on the network); default auto. The "
                  "URL with the token is printed on stderr");
  // Video files (io/video_writer.h).
  static std::string codec = "auto";
  static live::SinkOptions video_sk;
  cmd->add_option("--codec", codec, "Video files: auto (vp9 for .webm, h264 otherwise), h264, vp9");
  cmd->add_option(
         "--crf", video_sk.video.crf,
         "Video files: quality, lower = better and larger (h264 0..51, default 20; vp9 0..63, default 31)")
      ->check(CLI::Range(0, 63));
  cmd->add_option("--gop", video_sk.video.gop_s, "Video files: keyframe interval, s (default 2)")
      ->check(CLI::Range(1e-3, 3600.0));
  cmd->add_flag("--10bit", video_sk.video.ten_bit,
                "Video files: 10-bit 4:2:0 (yuv420p10le) instead of 8-bit");
  static std::string preset = io::to_string(io::VideoPreset::kFaster);
  cmd->add_option("--preset", preset,
                  "Video files: encoder speed, x264's ultrafast .. veryslow (default faster)");
  cmd->add_flag("--loop", o.loop, "Restart image sequences and video files at their end");
  cmd->add_option("--threads", o.threads, "Renderer threads (0: all; default 0)")->check(CLI::Range(0, 1024));
  cmd->add_option("--cache", o.cache, "Map cache folder (default $OMMA_CACHE_DIR or ~/.cache/omma)");
  cmd->add_flag("--no-cache", o.no_cache, "Do not read or write the map cache");
  cmd->add_flag("--no-photometric", o.no_photometric,
                "Ignore the rig's photometric model (by default each camera's frames are corrected for its "
                "vignetting and colour gains as they arrive, in the camera's thread)");
  cmd->add_flag("--json", o.json, "Print only the JSON summary on stdout (no progress line)");
  cmd->callback([] {
    set_json_mode(o.json);
    const Rig rig = design::load_rig_or_builtin(o.rig);
    live::EngineOptions eo;
    eo.map.method = pano::parse_method(o.method);
    const Size2 size = parse_size(o.size);
    eo.map.grid = PanoGrid{parse_projection(o.projection), size.width, size.height};
    eo.map.min_weight = o.min_weight;
    eo.cache_dir = o.no_cache
                       ? std::filesystem::path()
                       : (o.cache.empty() ? render::default_cache_dir() : std::filesystem::path(o.cache));
    eo.duration_s = o.duration;
    eo.max_frames = o.frames;
    eo.fps = o.fps;
    eo.threads = o.threads;
    eo.depth = o.depth;
    eo.photometric = !o.no_photometric;
    eo.first_frame_timeout_s = o.first_timeout;
    eo.max_camera_threads = o.camera_threads;
    live::SourceOptions so;
    so.fps = o.source_fps;
    so.loop = o.loop;
    so.stall_s = o.stall;
    so.sim.jitter_ms = o.sim_jitter;
    so.sim.loop_s = o.sim_loop;
    so.sim.progress = !o.json && progress_enabled();
    parse_fps_range(o.sim_fps, &so.sim.fps_min, &so.sim.fps_max);
    live::SinkOptions sk;
    sk.fps = o.fps > 0 ? o.fps : 30;
    sk.max_streams = o.max_streams;
    sk.bind = bind;
    sk.token = live::parse_token_mode(token);
    if ((bind != live::SinkOptions{}.bind || token != "auto") &&
        std::none_of(o.sinks.begin(), o.sinks.end(), [](const auto& s) { return s.rfind("http", 0) == 0; }))
      spdlog::warn("--bind and --token are for the live view (--sink http:PORT), which this run has not");
    sk.projection = eo.map.grid.projection;
    sk.spherical_metadata = true;  // 360-degree metadata in mp4 and png outputs
    sk.video = video_sk.video;
    sk.video.codec = io::parse_video_codec(codec);
    sk.video.preset = io::parse_video_preset(preset);
    const bool raw_stdout = std::count(o.sinks.begin(), o.sinks.end(), "-") > 0;
    if (raw_stdout && o.json)
      throw std::invalid_argument(
          "--sink - writes the frames on stdout: no --json with it (the summary goes to stderr)");
    // Every option checked before the sources start (the simulator pre-renders its loop first).
    for (const std::string& why : {valid_or_why(eo), valid_or_why(so), valid_or_why(sk)})
      if (!why.empty()) throw std::invalid_argument(why);
    auto sources = live::open_sources(rig, o.sources, so);
    std::vector<std::unique_ptr<live::Sink>> sinks;
    try {
      for (const auto& s : o.sinks)
        sinks.push_back(live::open_sink(s, rig, cv::Size(size.width, size.height), sk));
    } catch (...) {
      for (auto& s : sinks) s->abort();
      throw;
    }
    const bool show = !o.json && progress_enabled();
    const bool tty = isatty(2);
    eo.on_progress = [show, tty](const nlohmann::json& j) {
      if (!show) return;
      const std::string line = fmt::format(
          "omma run: {} frames  {:.1f} fps  latency {:.1f} ms  cameras live {} at {:.1f}-{:.1f} fps  dropped "
          "frames {}",
          j["frames"].get<long>(), j["fps"].get<double>(), j["latency_ms"].get<double>(),
          j["cameras_live"].get<long>(), j["window"]["camera_fps_min"].get<double>(),
          j["window"]["camera_fps_max"].get<double>(), j["dropped_frames"].get<long>());
      std::fprintf(stderr, tty ? "\r%s\033[K" : "%s\n", line.c_str());
    };
    // Sources and sinks run in their own threads; OpenCV's own parallelism inside them would only
    // compete with the renderer's threads.
    cv::setNumThreads(1);
    // Ctrl-C, SIGTERM and SIGHUP (the terminal or ssh session gone) stop the run cleanly: the video
    // is finished and playable. (SIGXFSZ is ignored for every command: apps/main.cc.)
    for (const int sig : {SIGINT, SIGTERM, SIGHUP}) std::signal(sig, on_signal);
    const live::EngineSummary st = live::run_engine(rig, std::move(sources), sinks, eo);
    for (const int sig : {SIGINT, SIGTERM, SIGHUP}) std::signal(sig, SIG_DFL);
    if (show && tty) std::fprintf(stderr, "\n");
    nlohmann::json j = st.to_json();
    j["method"] = o.method;
    j["depth_adaptive"] = o.depth;
    j["min_weight"] = o.min_weight;
    j["projection"] = o.projection;
    j["size"] = o.size;
    j["photometric"] = eo.photometric && has_photometric(rig);
    nlohmann::json sk_names = nlohmann::json::array();
    for (const auto& s : sinks) sk_names.push_back(s->describe());
    j["sinks"] = sk_names;
    if (raw_stdout)
      std::fprintf(stderr, "%s\n", j.dump().c_str());  // stdout holds the frames
    else
      print_json(j);
  });
}

}  // namespace omma::app
