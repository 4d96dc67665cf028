// omma bench: the engine's renderer against OpenCV peers and the memory bandwidth bound
// (thesis §5.4).
#include "omma/bench/bench.h"

#include <algorithm>
#include <iostream>
#include <thread>

#include <fmt/format.h>

#include "apps/command.h"
#include "omma/bench/stream_bench.h"
#include "omma/core/progress.h"
#include "omma/core/rig.h"
#include "omma/design/prototype.h"

namespace omma::app {

namespace {

// `omma bench --stream`: bench/stream_bench.h.
void run_stream(const Rig& rig, bool quick, bool json, const std::string& plugin, int max_readers) {
  bench::StreamBenchOptions so;
  if (quick) {
    so.size = {512, 512};
    so.seconds = 4;
    so.reader_seconds = 1.5;
    so.max_readers = std::min(max_readers, 4);
  } else {
    so.max_readers = max_readers;
  }
  so.plugin = plugin;
  so.progress = progress_enabled();
  const nlohmann::json r = bench::run_stream_bench(rig, so);
  if (json) {
    print_json(r);
    return;
  }
  auto row = [&](const char* name, const char* path) {
    if (!r.contains(name)) return;
    const auto& j = r[name];
    if (j.contains("error")) {
      std::cout << fmt::format("{:<44} error: {}\n", path, j["error"].get<std::string>());
      return;
    }
    if (!j.contains("median_ms")) {
      std::cout << fmt::format("{:<44} no flash seen ({} samples)\n", path, j.value("samples", 0));
      return;
    }
    std::cout << fmt::format("{:<44} {:>8.1f} {:>8.1f} {:>8.1f} {:>8}\n", path, j["median_ms"].get<double>(),
                             j["p90_ms"].get<double>(), j["max_ms"].get<double>(), j["samples"].get<int>());
  };
  std::cout << fmt::format("{} cameras, {} panoramas at {}/s; flash latency, ms:\n", r["cameras"].get<int>(),
                           r["size"].get<std::string>(), r["fps"].get<double>());
  std::cout << fmt::format("{:<44} {:>8} {:>8} {:>8} {:>8}\n", "path", "median", "p90", "max", "flashes");
  row("element", "ommastitch (appsrc -> element -> appsink)");
  row("rtsp", "engine -> rtsp:// -> rtspsrc + avdec_h264");
  row("mjpeg", "engine -> /stream.mjpg -> souphttpsrc + jpegdec");
  if (r.contains("engine"))
    std::cout << fmt::format("engine in that run: {:.1f} panoramas/s, frame age at render {:.1f} ms\n",
                             r["engine"]["fps"].get<double>(), r["engine"]["latency_ms"].get<double>());
  if (r.contains("readers")) {
    for (const auto& l : r["readers"])
      std::cout << fmt::format(
          "{:>3} RTSP readers: slowest {:.1f} frames/s, mean {:.1f}, stream {:.1f} Mbit/s\n",
          l["readers"].get<int>(), l["slowest_fps"].get<double>(), l["mean_fps"].get<double>(),
          l.value("stream_mbit_s", 0.0));
    std::cout << fmt::format("readers at full rate (>= 95 % of {:.1f} panoramas/s): {}\n",
                             r["readers_engine_fps"].get<double>(), r["max_readers_full_rate"].get<int>());
  }
}

}  // namespace

void add_bench_command(CLI::App& root) {
  auto* cmd = root.add_subcommand(
      "bench",
      "Measure the engine's renderer (nn, linear, mrf; 1 thread and all threads) against OpenCV "
      "per-camera cv::remap (peer A), cv::detail::MultiBandBlender (peer B) and the memcpy bandwidth "
      "bound, at 1080x1080 vr180 and 1920x512 equirect, random-texture frames");
  struct Opts {
    std::string rig, save_rig;
    bool json = false, quick = false, depth = false, stream = false;
    std::string plugin;
    int max_readers = bench::StreamBenchOptions{}.max_readers;
    double seconds = bench::BenchOptions{}.min_seconds;
    int rounds = 5;
    std::vector<std::string> only;
  };
  static Opts o;
  cmd->add_option("--rig", o.rig,
                  "Rig file (JSON); default: the thesis prototype, 24 cameras 250x250, 64 deg");
  cmd->add_option("--save-rig", o.save_rig, "Also write the rig used to this file (JSON)");
  cmd->add_option("--seconds", o.seconds, "Minimum measuring time per workload in all, seconds (default 2)")
      ->check(CLI::Range(0.01, 60.0));
  cmd->add_option("--rounds", o.rounds,
                  "Measure the workloads in turn, this many slices each, so that a drifting machine "
                  "speed affects ours and the peers alike (default 5)")
      ->check(CLI::Range(1, 100));
  cmd->add_option("--only", o.only, "Run only workloads whose name contains one of these strings");
  cmd->add_flag("--quick", o.quick, "Small panoramas (216x216, 384x102) for smoke tests");
  cmd->add_flag(
      "--depth", o.depth,
      "Also the depth-adaptive mrf renderer (`omma run --depth`): depth estimated every frame on a\n"
      "coarse grid, taps moved; reported beside the static mrf map of the same run (target >= 56 fps\n"
      "at 1080x1080 on 2 cores)");
  cmd->add_flag(
      "--stream", o.stream,
      "Instead of the renderer: the live outputs' latency and load, glass to glass with a flashing scene\n"
      "(every camera black/white, switching each second): the GStreamer element (ommastitch, appsrc in,\n"
      "appsink out), the engine through rtsp:// to an RTSP reader and through the live view's MJPEG\n"
      "stream in the same run, and how many RTSP readers keep the full rate (needs GStreamer;\n"
      "1080x1080 at 30 panoramas/s, 50 camera frames/s; --quick: 512x512, shorter)");
  cmd->add_option("--plugin", o.plugin,
                  "--stream: the plugin file libgstomma.so (default: the build tree's gst/, the installed "
                  "one, or GST_PLUGIN_PATH)");
  cmd->add_option("--max-readers", o.max_readers, "--stream: RTSP readers at most (default 16)")
      ->check(CLI::Range(1, 64));
  cmd->add_flag(
      "--json", o.json,
      "Print {\"results\": [{\"name\", \"fps\", ...}], \"ratios\": [{\"name\", \"vs_opencv_remap\", "
      "\"vs_opencv_multiband\", \"memcpy_bound_over_ours\", targets met}]} on stdout");
  cmd->callback([] {
    set_json_mode(o.json);
    const Rig rig = o.rig.empty() ? design::thesis_prototype_rig() : design::load_rig_or_builtin(o.rig);
    if (!o.save_rig.empty()) save_rig(rig, o.save_rig);
    if (o.stream) {
      run_stream(rig, o.quick, o.json, o.plugin, o.max_readers);
      return;
    }
    bench::BenchOptions bo;
    bo.min_seconds = o.seconds;
    bo.rounds = o.rounds;
    bo.quick = o.quick;
    bo.depth = o.depth;
    bo.only = o.only;
    std::vector<std::string> skipped;
    const auto entries = bench::run_bench_suite(rig, bo, &skipped);
    nlohmann::json results = nlohmann::json::array();
    for (const auto& e : entries) {
      nlohmann::json r = {{"name", e.name}, {"fps", e.fps}};
      for (auto it = e.info.begin(); it != e.info.end(); ++it) r[it.key()] = it.value();
      r["round_fps"] = e.round_fps;
      results.push_back(r);
    }
    const auto ratios = bench::bench_ratios(entries);
    nlohmann::json ratios_json = nlohmann::json::array();
    for (const auto& r : ratios) ratios_json.push_back(r.to_json());
    if (o.json) {
      print_json({{"results", results},
                  {"ratios", ratios_json},
                  {"skipped", skipped},
                  {"rig", rig.name},
                  {"cameras", rig.cameras.size()},
                  {"hardware_threads", std::thread::hardware_concurrency()}});
      return;
    }
    std::cout << fmt::format("{:<36} {:>12}\n", "workload", "fps");
    for (const auto& e : entries) std::cout << fmt::format("{:<36} {:>12.1f}\n", e.name, e.fps);
    for (const auto& s : skipped) std::cout << "skipped: " << s << "\n";
    if (!ratios.empty()) {
      std::cout << fmt::format("\n{:<36} {:>12} {:>14} {:>14}\n", "ours (all threads)", "x remap (A)",
                               "x multiband (B)", "bound / ours");
      auto num = [](double v) { return v > 0 ? fmt::format("{:.2f}", v) : std::string("-"); };
      auto range = [](const std::vector<double>& v) {
        if (v.empty()) return std::string("-");
        const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
        return fmt::format("{:.1f}-{:.1f}", *lo, *hi);
      };
      for (const auto& r : ratios)
        std::cout << fmt::format("{:<36} {:>12} {:>14} {:>14}   per round: A {}, B {}\n", r.name,
                                 num(r.vs_remap), num(r.vs_multiband), num(r.bound_over),
                                 range(r.vs_remap_rounds), range(r.vs_multiband_rounds));
      std::cout << "targets (mrf 1080x1080): >= 400 fps, >= 10x A, >= 100x B, bound / ours <= 2\n";
      for (const auto& r : ratios)
        if (r.vs_static > 0)
          std::cout << fmt::format(
              "{}: {:.1f} fps = {:.3f} x the static map (target: >= 56 fps at "
              "1080x1080 on 2 cores, depth every frame)\n",
              r.name, r.fps, r.vs_static);
    }
  });
}

}  // namespace omma::app
