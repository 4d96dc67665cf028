// omma record / omma recording check: raw multi-camera recordings (Giga-Eye, thesis §7.1-7.2).
#include <algorithm>
#include <atomic>
#include <csignal>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include <fmt/format.h>

#include "apps/command.h"
#include "omma/core/log.h"
#include "omma/core/progress.h"
#include "omma/design/prototype.h"
#include "omma/live/recorder.h"

namespace omma::app {
namespace {

std::atomic<bool> g_stop{false};
extern "C" void on_stop_signal(int) { g_stop = true; }

struct RecordArgs {
  std::string rig, out, sensor_mode;
  std::vector<std::string> sources;
  double duration = 0, clock = 0, flush = 0.5, exposure_ms = 0;
  std::optional<double> fps, source_fps;
  int64_t frames = 0;
  int queue = 4;
  bool json = false;
};

void run_record(const RecordArgs& a) {
  set_json_mode(a.json);
  if (a.sources.empty()) throw std::invalid_argument("give at least one --source");
  if (a.duration <= 0 && a.frames <= 0) throw std::invalid_argument("give --duration or --frames (or both)");
  const Rig rig = design::load_rig_or_builtin(a.rig);
  live::RecordOptions o;
  o.duration_s = a.duration;
  o.frames = a.frames;
  o.queue_frames = a.queue;
  o.flush_interval_s = a.flush;
  o.fps = a.fps.value_or(0);  // 0: derived from the sources' own rates
  if (std::string why; a.fps && !io::valid_recording_fps(*a.fps, &why)) throw std::invalid_argument(why);
  if (!(a.exposure_ms >= 0)) throw std::invalid_argument("--exposure-ms must be >= 0");
  o.exposure_s = a.exposure_ms / 1e3;
  o.clock_mhz = a.clock;
  o.sensor_mode = a.sensor_mode.empty() ? rig.name : a.sensor_mode;
  o.progress = !a.json;
  o.stop = &g_stop;
  if (std::string why; !o.IsValid(&why)) throw std::invalid_argument(why);
  live::SourceOptions so;
  so.fps = a.source_fps.value_or(a.fps.value_or(live::kFallbackFps));
  if (so.fps < 0) throw std::invalid_argument("--source-fps must be >= 0");
  auto sources = live::open_sources(rig, a.sources, so);
  io::RecordingManifest m;
  m.rig = rig;
  // Ctrl-C, SIGTERM and SIGHUP (the terminal or ssh session gone) close the recording normally.
  // (SIGXFSZ is ignored for every command: apps/main.cc.)
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) std::signal(sig, on_stop_signal);
  const live::RecordSummary s = live::record(std::move(sources), a.out, m, o);
  int64_t frames = 0, dropped = 0;
  for (size_t c = 0; c < s.frames.size(); ++c) frames += s.frames[c], dropped += s.dropped[c];
  if (a.json) {
    print_json({{"out", a.out},
                {"cameras", rig.cameras.size()},
                {"fps", s.fps},
                {"camera_fps", s.camera_fps},
                {"frames", s.frames},
                {"dropped", s.dropped},
                {"bytes", s.bytes},
                {"seconds", s.seconds},
                {"mb_per_s", s.mb_per_s()},
                {"error", s.error.empty() ? nlohmann::json(nullptr) : nlohmann::json(s.error)}});
  } else {
    std::cout << fmt::format(
        "{}: {} cameras, {} frames ({} dropped by the recorder), {:.1f} MB in {:.2f} s = {:.1f} MB/s; "
        "frame sets at {:.4g} fps{}\n",
        a.out, rig.cameras.size(), frames, dropped, s.bytes / 1e6, s.seconds, s.mb_per_s(), s.fps,
        a.fps ? ""
        : std::any_of(s.camera_fps.begin(), s.camera_fps.end(), [](double f) { return f > 0; })
            ? " (0.9 x the slowest camera's rate)"
            : " (no camera knows its rate)");
  }
  if (!s.error.empty())
    throw std::runtime_error("recording stopped: " + s.error +
                             " (what was recorded before is readable: omma recording check " + a.out + ")");
}

void run_check(const std::string& dir, bool json) {
  set_json_mode(json);
  io::RecordingReader r(dir);
  // Read every frame of every stream: a damaged chunk shows here.
  size_t total = 0;
  for (int c = 0; c < r.cameras(); ++c) total += r.frames(c);
  Progress progress("check", total, !json);
  for (int c = 0; c < r.cameras(); ++c)
    for (int64_t i = 0; i < r.frames(c); ++i) {
      r.read(c, i);
      progress.step();
    }
  progress.finish();
  const auto& m = r.match();
  nlohmann::json cams = nlohmann::json::array();
  int64_t frames = 0, dropped = 0, dup = 0, missing = 0, extra = 0;
  double span = 0;
  for (int c = 0; c < r.cameras(); ++c) {
    const auto& st = m.cameras[c];
    cams.push_back({{"camera", r.manifest().rig.cameras[c].id},
                    {"frames", st.frames},
                    {"dropped", st.dropped},
                    {"duplicates", st.duplicates},
                    {"missing", st.missing},
                    {"extra", st.extra}});
    frames += st.frames, dropped += st.dropped, dup += st.duplicates, missing += st.missing,
        extra += st.extra;
    if (!r.meta(c).empty()) span = std::max(span, r.meta(c).back().t_ns / 1e9);
  }
  if (json) {
    print_json({{"recording", dir},
                {"complete", r.manifest().complete},
                {"cameras", r.cameras()},
                {"sensor_mode", r.manifest().sensor_mode},
                {"fps", r.manifest().fps},
                {"camera_fps", r.manifest().camera_fps},
                {"frames", frames},
                {"frame_sets", r.frame_sets()},
                {"complete_sets", m.complete_sets},
                {"dropped", dropped},
                {"duplicates", dup},
                {"missing", missing},
                {"extra", extra},
                {"last_frame_s", span},
                {"per_camera", cams}});
  } else {
    std::cout << fmt::format(
        "{}: {} ({}), {} cameras, {} frames readable, {} frame sets ({} complete; each camera's frame "
        "nearest each tick of a {:g} fps clock, within half a period); "
        "dropped {}, duplicated {}, missing from sets {}, left out {}; last frame at {:.2f} s\n",
        dir, r.manifest().complete ? "complete" : "not closed (the recorder was stopped or killed)",
        r.manifest().sensor_mode, r.cameras(), frames, r.frame_sets(), m.complete_sets, r.manifest().fps,
        dropped, dup, missing, extra, span);
  }
}

}  // namespace

void add_record_command(CLI::App& root) {
  static RecordArgs a;
  auto* cmd = root.add_subcommand(
      "record",
      "Record free-running cameras as raw 12-bit RGGB Bayer with per-frame capture timestamps and sequence\n"
      "numbers: one HDF5 stream per camera (cam_XX.h5) and manifest.json in OUT (io/recording.h). Crash\n"
      "safe: flushed every --flush seconds; `omma recording check OUT` reads a killed recording.");
  cmd->add_option("--rig", a.rig, "Rig file or built-in rig")->required();
  cmd->add_option(
         "--source", a.sources,
         "Sources as in `omma run` (16-bit single-channel frames are raw already; others are mosaicked RGGB)")
      ->required();
  cmd->add_option("--out", a.out, "Recording folder (must not exist)")->required();
  cmd->add_option("--duration", a.duration, "Seconds to record");
  cmd->add_option("--frames", a.frames, "Frames per camera to record");
  cmd->add_option(
      "--fps", a.fps,
      "Nominal frame-set rate written to the recording (frame sets are matched on a clock of period\n"
      "1/fps, each camera's frame nearest each tick within half a period). Default: 0.9 x the slowest\n"
      "camera's own rate (the simulator's 44-56 fps sensors: 39.6), so that every free-running camera\n"
      "has a frame in every set; 30 if no source knows its rate");
  cmd->add_option(
      "--source-fps", a.source_fps,
      "Rate of image-sequence, still and panorama sources (default: --fps, else 30; 0 = as fast as "
      "they go); the simulator's sensors keep their own rates");
  cmd->add_option("--exposure-ms", a.exposure_ms,
                  "Exposure time of the cameras in ms, written to the recording (default: not known)");
  cmd->add_option("--sensor-mode", a.sensor_mode,
                  "Sensor mode written to the manifest (default: the rig's name)");
  cmd->add_option("--clock", a.clock, "Pixel clock in MHz written to the manifest");
  cmd->add_option("--queue", a.queue, "Frames queued per camera before frames are dropped")
      ->capture_default_str();
  cmd->add_option("--flush", a.flush, "Seconds between flushes (at most this much is lost on a crash)")
      ->capture_default_str();
  cmd->add_flag("--json", a.json, "Print one JSON summary on stdout");
  cmd->callback([] { run_record(a); });
}

void add_recording_command(CLI::App& root) {
  static std::string dir;
  static bool json = false;
  auto* cmd = root.add_subcommand("recording", "Inspect recordings made by omma record");
  cmd->require_subcommand(1);
  auto* check = cmd->add_subcommand(
      "check",
      "Read every frame of a recording (also one whose recorder was killed), match frame sets by nearest\n"
      "timestamp on the recording's frame-set clock (within half a period), and count dropped, duplicated,\n"
      "missing and left-out frames.");
  check->add_option("RECORDING", dir, "Recording folder")->required();
  check->add_flag("--json", json, "Print one JSON summary on stdout");
  check->callback([] { run_check(dir, json); });
}

}  // namespace omma::app
