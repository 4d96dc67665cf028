#include "omma/engine/engine.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <future>
#include <mutex>
#include <thread>

#include <sys/resource.h>
#include <unistd.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "omma/isp/photometric.h"

namespace omma::engine {
namespace {

using Clock = std::chrono::steady_clock;
std::atomic<bool> g_stop{false};

// The latest frame of one camera, written by its source thread.
struct Latest {
  std::mutex mutex;
  cv::Mat frame;
  Clock::time_point captured;
  long seq = 0;          // frames delivered so far
  bool ended = false;    // the source ended or failed
  std::string reason;
  bool fatal = false;    // wrong frame size: stop the whole run
};

double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

}  // namespace

void request_stop() { g_stop = true; }

nlohmann::json EngineStats::to_json() const {
  nlohmann::json dropped = nlohmann::json::array();
  for (const auto& d : dropped_cameras)
    dropped.push_back({{"index", d.index}, {"id", d.id}, {"reason", d.reason}, {"at_frame", d.at_frame},
                       {"remapped", d.remapped}});
  return {{"frames", frames},
          {"seconds", seconds},
          {"fps", fps},
          {"render_ms_mean", render_ms_mean},
          {"latency_ms_mean", latency_ms_mean},
          {"latency_ms_max", latency_ms_max},
          {"camera_frames", camera_frames},
          {"dropped_frames", dropped_frames},
          {"dropped_cameras", dropped},
          {"map", {{"bytes_per_pixel", map_bytes_per_pixel}, {"seconds", map_seconds}, {"from_cache", map_from_cache}}}};
}

EngineStats run_engine(const Rig& rig, std::vector<std::unique_ptr<CameraSource>> sources,
                       std::vector<std::unique_ptr<Sink>>& sinks, const EngineOptions& opt) {
  const size_t n = rig.cameras.size();
  if (sources.size() != n)
    throw std::invalid_argument("run_engine: " + std::to_string(sources.size()) + " sources for " +
                                std::to_string(n) + " cameras");
  g_stop = false;
  EngineStats stats;
  MapOptions mopt = opt.map;
  mopt.active.assign(n, true);
  MapLoad first = compile_map_cached(rig, mopt, opt.cache_dir);
  auto map = std::make_shared<CompiledMap>(std::move(first.map));
  stats.map_bytes_per_pixel = map->bytes_per_pixel();
  stats.map_seconds = first.seconds;
  stats.map_from_cache = first.from_cache;
  spdlog::info("map {}x{} {}: {:.2f} bytes/pixel, {} in {:.2f} s", map->width, map->height,
               pano::to_string(mopt.method), map->bytes_per_pixel(), first.from_cache ? "loaded" : "compiled",
               first.seconds);

  // Warm-up render (black frames) from this thread, so that the renderer's worker threads are
  // created here at normal priority (threads inherit the nice value of their creator).
  {
    FrameStore warm(map->layout);
    cv::Mat out;
    render(*map, warm, out, {.threads = opt.threads});
  }
  // Photometric tables per camera (empty where the rig has no model or it is switched off).
  const std::vector<isp::PhotometricTable> tables = isp::photometric_tables(rig, opt.photometric);
  std::vector<std::unique_ptr<Latest>> latest;
  for (size_t c = 0; c < n; ++c) latest.push_back(std::make_unique<Latest>());
  std::atomic<bool> stop{false};
  std::mutex wake_mutex;
  std::condition_variable wake;
  std::vector<std::thread> threads;
  const StoreLayout L = map->layout;  // a copy: the map is swapped when a camera drops
  for (size_t c = 0; c < n; ++c)
    threads.emplace_back([&, c] {
      // Camera threads run at a lower priority than the render loop: on a busy machine a camera
      // may deliver late (its frame is reused), but the panorama is never starved by decoding.
      setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), 15);
      CameraSource& src = *sources[c];
      Latest& slot = *latest[c];
      const double fps = src.fps();
      auto next_due = Clock::now();
      std::string reason = "ended";
      bool fatal = false;
      try {
        cv::Mat frame;
        while (!stop) {
          if (!src.read(frame)) break;
          if (frame.size() != L.size[c]) {
            reason = "camera " + std::to_string(rig.cameras[c].id) + " (" + src.describe() + "): frame is " +
                     std::to_string(frame.cols) + "x" + std::to_string(frame.rows) + ", the rig says " +
                     std::to_string(L.size[c].width) + "x" + std::to_string(L.size[c].height);
            fatal = true;
            break;
          }
          cv::Mat ready;
          if (!tables[c].empty() && !src.photometric_applied()) {
            // The photometric correction, here in the camera's thread: the frame enters the
            // frame store corrected and the render loop does nothing more.
            tables[c].apply(to_bgr8(frame), ready);
          } else {
            ready = frame.clone();
          }
          {
            std::lock_guard<std::mutex> lock(slot.mutex);
            slot.frame = std::move(ready);
            slot.captured = Clock::now();
            ++slot.seq;
          }
          wake.notify_one();
          if (fps > 0) {
            next_due += std::chrono::microseconds(long(1e6 / fps));
            const auto now = Clock::now();
            if (next_due < now) next_due = now;
            while (!stop && Clock::now() < next_due)
              std::this_thread::sleep_for(std::min<Clock::duration>(next_due - Clock::now(), std::chrono::milliseconds(20)));
          }
        }
      } catch (const std::exception& e) {
        reason = e.what();
      }
      {
        std::lock_guard<std::mutex> lock(slot.mutex);
        slot.ended = true;
        slot.reason = reason;
        slot.fatal = fatal;
      }
      wake.notify_one();
    });

  auto shutdown = [&] {
    stop = true;
    wake.notify_all();
    for (auto& t : threads)
      if (t.joinable()) t.join();
  };

  FrameStore store(map->layout);
  std::vector<long> used_seq(n, 0);
  std::vector<Clock::time_point> captured(n);
  std::vector<bool> live(n, true), have(n, false);
  std::future<CompiledMap> pending;
  std::vector<bool> pending_active;
  cv::Mat pano;
  double render_ms_sum = 0, latency_sum = 0;
  const auto t0 = Clock::now();
  auto last_progress = t0;
  auto next_frame = t0;
  try {
    while (!g_stop) {
      // Pace the panorama rate; otherwise wait for any new frame.
      if (opt.fps > 0) {
        next_frame += std::chrono::microseconds(long(1e6 / opt.fps));
        const auto now = Clock::now();
        if (next_frame < now) next_frame = now;
        std::unique_lock<std::mutex> lock(wake_mutex);
        wake.wait_until(lock, next_frame, [] { return g_stop.load(); });
      } else {
        std::unique_lock<std::mutex> lock(wake_mutex);
        wake.wait_for(lock, std::chrono::milliseconds(2));
      }
      const double elapsed = std::chrono::duration<double>(Clock::now() - t0).count();
      if (opt.duration_s > 0 && elapsed >= opt.duration_s) break;
      // Collect the newest frames; notice cameras that ended.
      bool fresh = false, any_live = false;
      std::vector<int> newly_dead;
      for (size_t c = 0; c < n; ++c) {
        if (!live[c]) continue;
        Latest& slot = *latest[c];
        std::lock_guard<std::mutex> lock(slot.mutex);
        if (slot.fatal) throw SourceError(slot.reason);
        if (slot.seq > used_seq[c]) {
          store.set(int(c), slot.frame);
          stats.dropped_frames += used_seq[c] > 0 ? slot.seq - used_seq[c] - 1 : slot.seq - 1;
          used_seq[c] = slot.seq;
          captured[c] = slot.captured;
          have[c] = true;
          fresh = true;
        }
        if (slot.ended) {
          live[c] = false;
          newly_dead.push_back(int(c));
          stats.dropped_cameras.push_back({int(c), rig.cameras[c].id, slot.reason, stats.frames, false});
          spdlog::warn("camera {} dropped at frame {}: {}", rig.cameras[c].id, stats.frames, slot.reason);
        } else if (!have[c] && elapsed > opt.first_frame_timeout_s) {
          live[c] = false;
          newly_dead.push_back(int(c));
          stats.dropped_cameras.push_back({int(c), rig.cameras[c].id, "no frame within " +
                                          std::to_string(opt.first_frame_timeout_s) + " s", stats.frames, false});
          spdlog::warn("camera {} dropped: no first frame", rig.cameras[c].id);
        }
        any_live = any_live || live[c];
      }
      const bool finished = !any_live;
      // Recompile without the dropped cameras (in the background); swap when ready.
      if (!newly_dead.empty() && any_live) {
        std::vector<bool> active(n);
        for (size_t c = 0; c < n; ++c) active[c] = live[c];
        if (pending.valid()) pending.wait();
        pending_active = active;
        MapOptions m2 = mopt;
        m2.active = active;
        pending = std::async(std::launch::async, [&rig, m2, dir = opt.cache_dir] {
          return compile_map_cached(rig, m2, dir).map;
        });
      }
      if (pending.valid() && pending.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
        map = std::make_shared<CompiledMap>(pending.get());
        for (auto& d : stats.dropped_cameras)
          if (!pending_active[d.index]) d.remapped = true;
      }
      // Wait until every live camera has its first frame (or has been dropped for lacking one).
      bool all_have = true;
      for (size_t c = 0; c < n; ++c)
        if (live[c] && !have[c]) all_have = false;
      if (finished) {
        all_have = false;  // render the last frames of every camera once, then stop
        for (size_t c = 0; c < n; ++c) all_have = all_have || have[c];
        if (!fresh) break;
      }
      if (!all_have || (!fresh && opt.fps <= 0)) {
        if (finished) break;
        continue;
      }
      const auto r0 = Clock::now();
      render(*map, store, pano, {.threads = opt.threads});
      render_ms_sum += ms_since(r0);
      for (auto& s : sinks) s->write(pano, store);
      Clock::time_point oldest = Clock::now();
      for (size_t c = 0; c < n; ++c)
        if ((live[c] || finished) && have[c]) oldest = std::min(oldest, captured[c]);
      const double lat = ms_since(oldest);
      latency_sum += lat;
      stats.latency_ms_max = std::max(stats.latency_ms_max, lat);
      ++stats.frames;
      if (finished || (opt.max_frames > 0 && stats.frames >= opt.max_frames)) break;
      if (std::chrono::duration<double>(Clock::now() - last_progress).count() > 0.5) {
        last_progress = Clock::now();
        stats.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
        stats.fps = stats.frames / stats.seconds;
        stats.latency_ms_mean = latency_sum / stats.frames;
        stats.camera_frames = 0;
        for (size_t c = 0; c < n; ++c) stats.camera_frames += used_seq[c];
        nlohmann::json j = stats.to_json();
        j["latency_ms"] = stats.latency_ms_mean;
        j["cameras_live"] = std::count(live.begin(), live.end(), true);
        for (auto& s : sinks) s->set_stats(j);
        if (opt.on_progress) opt.on_progress(j);
      }
    }
    if (pending.valid()) {
      map = std::make_shared<CompiledMap>(pending.get());
      for (auto& d : stats.dropped_cameras)
        if (!pending_active[d.index]) d.remapped = true;
    }
  } catch (...) {
    shutdown();
    if (pending.valid()) pending.wait();
    for (auto& s : sinks) s->abort();
    throw;
  }
  shutdown();
  stats.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  if (stats.frames == 0) {
    for (auto& s : sinks) s->abort();
    std::string why = "no panorama was rendered";
    if (!stats.dropped_cameras.empty()) {
      why += ": " + stats.dropped_cameras.front().reason;
    } else {
      std::string waiting;
      for (size_t c = 0; c < n; ++c)
        if (!have[c]) waiting += (waiting.empty() ? "" : ", ") + std::to_string(rig.cameras[c].id);
      if (!waiting.empty()) why += " in " + fmt::format("{:.1f}", stats.seconds) + " s: still waiting for the first frame of camera(s) " + waiting;
    }
    throw std::runtime_error(why);
  }
  for (auto& s : sinks) s->finish();
  stats.camera_frames = 0;
  for (size_t c = 0; c < n; ++c) stats.camera_frames += latest[c]->seq;
  stats.fps = stats.frames / stats.seconds;
  stats.render_ms_mean = render_ms_sum / stats.frames;
  stats.latency_ms_mean = latency_sum / stats.frames;
  return stats;
}

}  // namespace omma::engine
