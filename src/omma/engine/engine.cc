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

namespace omma::engine {
namespace {

std::atomic<bool> g_stop{false};

// The latest frame of one camera: a triple buffer. The camera fills buf[back] and swaps it with the
// middle one (marking it fresh); the render loop, when the middle one is fresh, swaps it with its
// buf[front]. Neither ever waits for the other.
struct Latest {
  struct Frame {
    cv::Mat image;
    Clock::time_point captured;
    long seq = 0;
  };
  static constexpr int kFresh = 4;
  Frame buf[3];
  std::atomic<int> middle{1};
  int back = 0;   // the camera's
  int front = 2;  // the render loop's
  std::atomic<long> delivered{0};
  // Set once by the camera's thread before `ended` (release); read after `ended` (acquire).
  std::string reason;
  bool fatal = false;  // wrong frame size: stop the whole run
  std::atomic<bool> ended{false};

  void publish(cv::Mat image, Clock::time_point captured) {
    Frame& f = buf[back];
    f.image = std::move(image);
    f.captured = captured;
    f.seq = delivered.fetch_add(1, std::memory_order_relaxed) + 1;
    back = middle.exchange(back | kFresh, std::memory_order_acq_rel) & 3;
  }
  // The newest frame if one arrived since the last take, else nullptr.
  const Frame* take() {
    if (!(middle.load(std::memory_order_acquire) & kFresh)) return nullptr;
    front = middle.exchange(front, std::memory_order_acq_rel) & 3;
    return &buf[front];
  }
  void end(std::string why, bool is_fatal) {
    reason = std::move(why);
    fatal = is_fatal;
    ended.store(true, std::memory_order_release);
  }
};

double ms_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

}  // namespace

void request_stop() { g_stop = true; }

bool EngineOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (!map.IsValid(why)) return false;
  if (!(duration_s >= 0) || max_frames < 0 || !(fps >= 0) || !(first_frame_timeout_s > 0) || threads < 0)
    return fail("duration, frames, fps and threads must be >= 0, the first-frame timeout > 0");
  if (max_camera_threads < 1) return fail("max_camera_threads must be >= 1");
  return true;
}

nlohmann::json EngineStats::to_json() const {
  nlohmann::json dropped = nlohmann::json::array();
  for (const auto& d : dropped_cameras)
    dropped.push_back({{"index", d.index}, {"id", d.id}, {"reason", d.reason}, {"at_frame", d.at_frame},
                       {"remapped", d.remapped}});
  return {{"frames", frames},
          {"seconds", seconds},
          {"fps", fps},
          {"render_ms_mean", render_ms_mean},
          {"latency_ms", latency_ms},
          {"latency_ms_max", latency_ms_max},
          {"oldest_frame_ms_max", oldest_frame_ms_max},
          {"camera_frames", camera_frames},
          {"camera_fps_min", camera_fps_min},
          {"camera_fps_max", camera_fps_max},
          {"dropped_frames", dropped_frames},
          {"camera_threads", camera_threads},
          {"cameras_live", cameras_live},
          {"window",
           {{"seconds", window.seconds},
            {"fps", window.fps},
            {"latency_ms", window.latency_ms},
            {"camera_fps_min", window.camera_fps_min},
            {"camera_fps_max", window.camera_fps_max}}},
          {"dropped_cameras", dropped},
          {"map", {{"bytes_per_pixel", map_bytes_per_pixel}, {"seconds", map_seconds}, {"from_cache", map_from_cache}}}};
}

namespace {

// The camera threads: thread t serves the cameras c with c % threads == t, each when its next frame
// is due (the source's own clock, its fps, or at once for "as fast as it can").
class CameraThreads {
 public:
  CameraThreads(const Rig& rig, std::vector<std::unique_ptr<CameraSource>>& sources,
                std::vector<std::unique_ptr<Latest>>& latest, const StoreLayout& layout, int max_threads,
                std::function<void()> notify)
      : rig_(rig), sources_(sources), latest_(latest), layout_(layout), notify_(std::move(notify)) {
    const int n = int(sources.size());
    const int want = std::min(n, std::max(1, max_threads));
    // Start the threads first, parked until every camera has a thread; if the system refuses a
    // thread (limits on threads or address space), the cameras share the threads that did start.
    std::string refused;
    threads_.reserve(want);
    for (int t = 0; t < want; ++t) {
      try {
        threads_.emplace_back([this, t] { serve(t); });
      } catch (const std::system_error& e) {
        refused = e.what();
        break;
      }
    }
    const int got = int(threads_.size());
    if (got == 0) {
      for (int c = 0; c < n; ++c) latest_[c]->end("cannot start a camera thread: " + refused, false);
      spdlog::error("no camera thread could be started: {}", refused);
    } else if (got < want) {
      spdlog::warn("only {} of {} camera threads could be started ({}); the {} cameras share them", got, want,
                   refused, n);
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      threads_started_ = got;
      released_ = true;
    }
    cv_.notify_all();
  }
  ~CameraThreads() { stop(); }
  int count() const { return int(threads_.size()); }
  void stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
      released_ = true;
    }
    cv_.notify_all();
    for (auto& t : threads_)
      if (t.joinable()) t.join();
  }

 private:
  struct Cam {
    int c;
    Clock::time_point due;
    double fps;
  };
  void serve(int t) {
    int nthreads = 0;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      cv_.wait(lock, [&] { return released_; });
      if (stopping()) return;
      nthreads = threads_started_;
    }
    std::vector<Cam> cams;
    const auto now = Clock::now();
    bool own_clocks = true;
    for (int c = t; c < int(sources_.size()); c += nthreads) {
      cams.push_back({c, now, sources_[c]->fps()});
      own_clocks = own_clocks && sources_[c]->next_capture() != Clock::time_point{};
    }
    // Camera threads run at a lower priority than the render loop: on a busy machine a camera
    // may deliver late (its frame is reused), but the panorama is never starved by decoding.
    // Sources with their own clock (simulated sensors) only hand over frames that are ready, at
    // their capture instants: they keep the normal priority, so that they wake up on time.
    if (!own_clocks) setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), 15);
    while (!cams.empty() && !stopping()) {
      // The camera due first; its own clock if it keeps one.
      for (auto& k : cams)
        if (const auto own = sources_[k.c]->next_capture(); own != Clock::time_point{}) k.due = own;
      auto it = std::min_element(cams.begin(), cams.end(), [](const Cam& a, const Cam& b) { return a.due < b.due; });
      const auto wait = it->due - Clock::now();
      if (wait > Clock::duration::zero()) {  // (at most 20 ms: then look at `stop` again)
        std::this_thread::sleep_for(std::min<Clock::duration>(wait, std::chrono::milliseconds(20)));
        continue;
      }
      if (!read_one(it->c)) {
        cams.erase(it);
        continue;
      }
      if (it->fps > 0) {
        it->due += std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / it->fps));
        if (it->due < Clock::now()) it->due = Clock::now();
      } else {
        it->due = Clock::now();
      }
    }
  }
  // Reads one frame of camera c into its buffer; false (and the camera marked ended) at its end.
  bool read_one(int c) {
    CameraSource& src = *sources_[c];
    Latest& slot = *latest_[c];
    try {
      cv::Mat frame;  // a new header per frame: the slot keeps a reference (sources.h)
      if (!src.read(frame)) {
        slot.end("ended", false);
        notify_();
        return false;
      }
      if (frame.size() != layout_.size[c]) {
        slot.end("camera " + std::to_string(rig_.cameras[c].id) + " (" + src.describe() + "): frame is " +
                     std::to_string(frame.cols) + "x" + std::to_string(frame.rows) + ", the rig says " +
                     std::to_string(layout_.size[c].width) + "x" + std::to_string(layout_.size[c].height),
                 true);
        notify_();
        return false;
      }
      const auto own = src.last_capture();
      slot.publish(std::move(frame), own != Clock::time_point{} ? own : Clock::now());
    } catch (const std::exception& e) {
      slot.end(e.what(), false);
      notify_();
      return false;
    }
    notify_();
    return true;
  }
  bool stopping() const { return stop_.load(std::memory_order_relaxed); }
  const Rig& rig_;
  std::vector<std::unique_ptr<CameraSource>>& sources_;
  std::vector<std::unique_ptr<Latest>>& latest_;
  StoreLayout layout_;
  std::function<void()> notify_;
  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable cv_;
  int threads_started_ = 0;
  bool released_ = false;
  std::atomic<bool> stop_{false};
};

}  // namespace

EngineStats run_engine(const Rig& rig, std::vector<std::unique_ptr<CameraSource>> sources,
                       std::vector<std::unique_ptr<Sink>>& sinks, const EngineOptions& opt) {
  const size_t n = rig.cameras.size();
  if (sources.size() != n)
    throw std::invalid_argument("run_engine: " + std::to_string(sources.size()) + " sources for " +
                                std::to_string(n) + " cameras");
  if (std::string why; !opt.IsValid(&why)) throw std::invalid_argument("run_engine: " + why);
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
  std::vector<std::unique_ptr<Latest>> latest;
  for (size_t c = 0; c < n; ++c) latest.push_back(std::make_unique<Latest>());
  std::mutex wake_mutex;
  std::condition_variable wake;
  // A copy of the layout: the map is swapped when a camera drops.
  // The render loop waits for new frames only when it is not paced (fps 0).
  CameraThreads cameras(rig, sources, latest, map->layout, opt.max_camera_threads, [&wake, paced = opt.fps > 0] {
    if (!paced) wake.notify_one();
  });
  stats.camera_threads = cameras.count();

  FrameStore store(map->layout);
  std::vector<long> used_seq(n, 0);
  std::vector<Clock::time_point> captured(n);
  std::vector<bool> live(n, true), have(n, false);
  // Per camera: the sequence number and capture instant of its first frame, of its newest frame
  // at the window's start and of its newest frame (rates = frames between two capture instants).
  std::vector<long> seq_first(n, 0), seq_window(n, 0);
  std::vector<Clock::time_point> t_first(n), t_window(n), t_last(n);
  std::future<CompiledMap> pending;
  std::vector<bool> pending_active;
  cv::Mat pano;
  PanoramaInfo info;
  double render_ms_sum = 0, latency_sum = 0, window_latency_sum = 0;
  long window_frames = 0;
  const auto t0 = Clock::now();
  auto window_start = t0;
  auto next_frame = t0;
  // Frames/s of the slowest and the fastest camera since (seq, t) = its window start or its first
  // frame; live cameras, or every camera once all have ended.
  auto camera_rates = [&](const std::vector<long>& seq, const std::vector<Clock::time_point>& t, double* lo,
                          double* hi) {
    *lo = 0;
    *hi = 0;
    bool any = false;
    const bool all_ended = std::none_of(live.begin(), live.end(), [](bool b) { return b; });
    for (size_t c = 0; c < n; ++c) {
      if (!have[c] || (!live[c] && !all_ended)) continue;
      const double s = std::chrono::duration<double>(t_last[c] - t[c]).count();
      const double f = s > 0 ? (used_seq[c] - seq[c]) / s : 0;
      *lo = any ? std::min(*lo, f) : f;
      *hi = any ? std::max(*hi, f) : f;
      any = true;
    }
  };
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
        const bool ended = slot.ended.load(std::memory_order_acquire);
        if (ended && slot.fatal) throw SourceError(slot.reason);
        if (const Latest::Frame* f = slot.take()) {
          store.set(int(c), f->image);
          stats.dropped_frames += f->seq - used_seq[c] - 1;
          if (!have[c]) {
            seq_first[c] = seq_window[c] = f->seq;
            t_first[c] = t_window[c] = f->captured;
          }
          used_seq[c] = f->seq;
          captured[c] = t_last[c] = f->captured;
          have[c] = true;
          fresh = true;
        }
        if (ended) {
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
      const auto done = Clock::now();
      render_ms_sum += ms_between(r0, done);
      // Frame ages (engine.h, "Latency").
      info.index = stats.frames;
      info.rendered = done;
      info.captured.assign(n, Clock::time_point{});
      double age_sum = 0, oldest = 0;
      int used = 0;
      for (size_t c = 0; c < n; ++c)
        if ((live[c] || finished) && have[c]) {
          info.captured[c] = captured[c];
          const double age = ms_between(captured[c], done);
          age_sum += age;
          oldest = std::max(oldest, age);
          ++used;
        }
      info.latency_ms = used > 0 ? age_sum / used : 0;
      latency_sum += info.latency_ms;
      window_latency_sum += info.latency_ms;
      ++window_frames;
      stats.latency_ms_max = std::max(stats.latency_ms_max, info.latency_ms);
      stats.oldest_frame_ms_max = std::max(stats.oldest_frame_ms_max, oldest);
      if (opt.on_panorama) opt.on_panorama(pano, info);
      for (auto& s : sinks) s->write(pano, store);
      ++stats.frames;
      if (finished || (opt.max_frames > 0 && stats.frames >= opt.max_frames)) break;
      const double window_s = std::chrono::duration<double>(Clock::now() - window_start).count();
      if (window_s > 0.5) {
        stats.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
        stats.fps = stats.frames / stats.seconds;
        stats.latency_ms = latency_sum / stats.frames;
        stats.camera_frames = 0;
        for (size_t c = 0; c < n; ++c) stats.camera_frames += used_seq[c];
        camera_rates(seq_first, t_first, &stats.camera_fps_min, &stats.camera_fps_max);
        stats.window.seconds = window_s;
        stats.window.fps = window_frames / window_s;
        stats.window.latency_ms = window_latency_sum / window_frames;
        camera_rates(seq_window, t_window, &stats.window.camera_fps_min, &stats.window.camera_fps_max);
        stats.cameras_live = int(std::count(live.begin(), live.end(), true));
        seq_window = used_seq;
        t_window = t_last;
        window_start = Clock::now();
        window_frames = 0;
        window_latency_sum = 0;
        const nlohmann::json j = stats.to_json();
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
    cameras.stop();
    if (pending.valid()) pending.wait();
    for (auto& s : sinks) s->abort();
    throw;
  }
  cameras.stop();
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
  for (size_t c = 0; c < n; ++c) stats.camera_frames += latest[c]->delivered.load();
  stats.fps = stats.frames / stats.seconds;
  stats.render_ms_mean = render_ms_sum / stats.frames;
  stats.latency_ms = latency_sum / stats.frames;
  camera_rates(seq_first, t_first, &stats.camera_fps_min, &stats.camera_fps_max);
  stats.cameras_live = int(std::count(live.begin(), live.end(), true));
  return stats;
}

}  // namespace omma::engine
