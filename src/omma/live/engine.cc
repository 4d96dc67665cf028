#include "omma/live/engine.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <future>
#include <mutex>
#include <thread>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "omma/core/valid.h"
#include "omma/isp/photometric.h"

namespace omma::live {
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
  if (!map.IsValid(why)) return false;
  if (!(duration_s >= 0 && duration_s <= 1e7) || max_frames < 0 || threads < 0 ||
      !(first_frame_timeout_s > 0 && first_frame_timeout_s <= 1e6))
    return invalid(why,
                   "duration (at most 10^7 s), frames and threads must be >= 0, the first-frame timeout in "
                   "(0, 10^6] s");
  if (!valid_rate(fps, true))
    return invalid(why, fmt::format("fps must be 0 (every new frame) or {}..{}", kMinRate, kMaxRate));
  if (max_camera_threads < 1) return invalid(why, "max_camera_threads must be >= 1");
  return true;
}

nlohmann::json EngineSummary::to_json() const {
  nlohmann::json dropped = nlohmann::json::array();
  for (const auto& d : dropped_cameras)
    dropped.push_back({{"index", d.index},
                       {"id", d.id},
                       {"reason", d.reason},
                       {"at_frame", d.at_frame},
                       {"remapped", d.remapped}});
  return {
      {"frames", frames},
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
        {"render_ms", window.render_ms},
        {"camera_fps_min", window.camera_fps_min},
        {"camera_fps_max", window.camera_fps_max}}},
      {"dropped_cameras", dropped},
      {"map",
       {{"bytes_per_pixel", map_bytes_per_pixel}, {"seconds", map_seconds}, {"from_cache", map_from_cache}}},
      {"depth", depth_compile_s > 0
                    ? nlohmann::json{{"estimate_ms_mean", depth_ms_mean}, {"compile_s", depth_compile_s}}
                    : nlohmann::json(nullptr)}};
}

namespace {

// The camera threads: thread t serves the cameras c with c % threads == t, each when its next frame
// is due (the source's own clock, its fps, or at once for "as fast as it can").
class CameraThreads {
 public:
  // `tables`: the photometric tables per camera (empty ones: no correction), applied to each frame
  // in its camera's thread before it is handed over.
  CameraThreads(const Rig& rig, std::vector<std::unique_ptr<CameraSource>>& sources,
                std::vector<std::unique_ptr<Latest>>& latest, const render::StoreLayout& layout,
                int max_threads, std::function<void()> notify,
                const std::vector<isp::PhotometricTable>& tables)
      : rig_(rig),
        sources_(sources),
        latest_(latest),
        layout_(layout),
        notify_(std::move(notify)),
        tables_(tables) {
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
      auto it = std::min_element(cams.begin(), cams.end(),
                                 [](const Cam& a, const Cam& b) { return a.due < b.due; });
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
      if (!tables_[c].empty() && !src.photometric_applied()) {
        // The photometric correction, here in the camera's thread: the frame enters the frame
        // store corrected and the render loop does nothing more.
        cv::Mat corrected;
        tables_[c].apply(render::to_bgr8(frame), corrected);
        frame = corrected;
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
  render::StoreLayout layout_;
  std::function<void()> notify_;
  const std::vector<isp::PhotometricTable>& tables_;
  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable cv_;
  int threads_started_ = 0;
  bool released_ = false;
  std::atomic<bool> stop_{false};
};

// One run of the engine, phase by phase: the maps (set-up), then per panorama: wait for the tick,
// collect the cameras' newest frames (dropping cameras that ended), swap in a map recompiled without
// them, render, measure the frame ages, hand the panorama to the sinks, and every half second publish
// the statistics; finally the summary. The camera threads (CameraThreads) fill `latest`.
class RenderLoop {
 public:
  RenderLoop(const Rig& rig, std::vector<std::unique_ptr<CameraSource>>& sources,
             std::vector<std::unique_ptr<Sink>>& sinks, const EngineOptions& opt)
      : rig_(rig), sinks_(sinks), opt_(opt), n_(rig.cameras.size()) {
    compile_maps();
    tables_ = isp::photometric_tables(rig, opt.photometric);  // empty where no model or switched off
    for (size_t c = 0; c < n_; ++c) latest_.push_back(std::make_unique<Latest>());
    // The render loop waits for new frames only when it is not paced (fps 0).
    cameras_ = std::make_unique<CameraThreads>(
        rig, sources, latest_, map_->layout, opt.max_camera_threads,
        [this, paced = opt.fps > 0] {
          if (!paced) wake_.notify_one();
        },
        tables_);
    stats_.camera_threads = cameras_->count();
    store_ = std::make_unique<render::FrameStore>(map_->layout);
    current_.resize(n_);
    used_seq_.assign(n_, 0);
    captured_.resize(n_);
    live_.assign(n_, true);
    have_.assign(n_, false);
    seq_first_.assign(n_, 0);
    seq_window_.assign(n_, 0);
    t_first_.resize(n_);
    t_window_.resize(n_);
    t_last_.resize(n_);
  }

  EngineSummary run() {
    t0_ = window_start_ = next_frame_ = Clock::now();
    try {
      while (!stopping()) {
        wait_for_tick();
        const double elapsed = std::chrono::duration<double>(Clock::now() - t0_).count();
        if (opt_.duration_s > 0 && elapsed >= opt_.duration_s) break;
        const bool fresh = collect_frames(elapsed);
        const bool finished = all_ended();
        swap_map_if_ready(false);
        if (!ready_to_render(fresh, finished)) {
          if (finished) break;
          continue;
        }
        render_panorama(finished);
        ++stats_.frames;
        if (finished || (opt_.max_frames > 0 && stats_.frames >= opt_.max_frames)) break;
        publish_window_if_due();
      }
      swap_map_if_ready(true);
    } catch (...) {
      cameras_->stop();
      if (pending_.valid()) pending_.wait();
      for (auto& s : sinks_) s->abort();
      throw;
    }
    cameras_->stop();
    return summary();
  }

 private:
  bool stopping() const { return g_stop.load() || (opt_.stop && opt_.stop->load()); }

  // The map of every camera (cached), a warm-up render, and the depth-adaptive renderer if asked.
  void compile_maps() {
    mopt_ = opt_.map;
    mopt_.active.assign(n_, true);
    render::MapLoad first = render::compile_map_cached(rig_, mopt_, opt_.cache_dir);
    map_ = std::make_shared<render::CompiledMap>(std::move(first.map));
    stats_.map_bytes_per_pixel = map_->bytes_per_pixel();
    stats_.map_seconds = first.seconds;
    stats_.map_from_cache = first.from_cache;
    spdlog::info("map {}x{} {}: {:.2f} bytes/pixel, {} in {:.2f} s", map_->width, map_->height,
                 pano::to_string(mopt_.method), map_->bytes_per_pixel(),
                 first.from_cache ? "loaded" : "compiled", first.seconds);
    // Warm-up render (black frames) from this thread, so that the renderer's worker threads are
    // created here at normal priority (threads inherit the nice value of their creator).
    {
      render::FrameStore warm(map_->layout);
      cv::Mat out;
      render::render(*map_, warm, out, {.threads = opt_.threads});
    }
    if (opt_.depth) {
      render::DepthRenderOptions dopt;
      dopt.map = mopt_;
      dopt.map.min_weight = render::kEngineDepthMinWeight;
      dopt.sweep = opt_.depth_sweep;
      dopt.threads = opt_.threads;
      depth_ = std::make_unique<render::DepthRenderer>(rig_, dopt);
      stats_.depth_compile_s = depth_->compile_seconds();
      spdlog::info("depth-adaptive map: {:.1f} bytes/pixel, depth grid {}x{}, compiled in {:.2f} s",
                   depth_->bytes_per_pixel(), depth_->sweep().coarse_grid().width,
                   depth_->sweep().coarse_grid().height, depth_->compile_seconds());
    }
  }

  // Paces the panorama rate; unpaced (fps 0), waits for any new frame (at most 2 ms).
  void wait_for_tick() {
    std::unique_lock<std::mutex> lock(wake_mutex_);
    if (opt_.fps > 0) {
      next_frame_ += std::chrono::microseconds(long(1e6 / opt_.fps));
      const auto now = Clock::now();
      if (next_frame_ < now) next_frame_ = now;
      // In slices of at most 50 ms: an outside stop flag (EngineOptions::stop) has no one to notify.
      while (!stopping() && Clock::now() < next_frame_)
        wake_.wait_until(lock, std::min(next_frame_, Clock::now() + std::chrono::milliseconds(50)));
    } else {
      wake_.wait_for(lock, std::chrono::milliseconds(2));
    }
  }

  // Takes the newest frame of every live camera into the store; drops cameras that ended or gave
  // no first frame in time, and starts recompiling the map without them. True if any frame is new.
  bool collect_frames(double elapsed) {
    bool fresh = false, any_live = false;
    std::vector<int> newly_dead;
    for (size_t c = 0; c < n_; ++c) {
      if (!live_[c]) continue;
      Latest& slot = *latest_[c];
      const bool ended = slot.ended.load(std::memory_order_acquire);
      if (ended && slot.fatal) throw SourceError(slot.reason);
      if (const Latest::Frame* f = slot.take()) {
        store_->set(int(c), f->image);
        if (depth_) current_[c] = f->image.clone();  // the buffer slot is reused by the camera thread
        stats_.dropped_frames += f->seq - used_seq_[c] - 1;
        if (!have_[c]) {
          seq_first_[c] = seq_window_[c] = f->seq;
          t_first_[c] = t_window_[c] = f->captured;
        }
        used_seq_[c] = f->seq;
        captured_[c] = t_last_[c] = f->captured;
        have_[c] = true;
        fresh = true;
      }
      if (ended) {
        live_[c] = false;
        newly_dead.push_back(int(c));
        stats_.dropped_cameras.push_back({int(c), rig_.cameras[c].id, slot.reason, stats_.frames, false});
        spdlog::warn("camera {} dropped at frame {}: {}", rig_.cameras[c].id, stats_.frames, slot.reason);
      } else if (!have_[c] && elapsed > opt_.first_frame_timeout_s) {
        live_[c] = false;
        newly_dead.push_back(int(c));
        stats_.dropped_cameras.push_back(
            {int(c), rig_.cameras[c].id,
             "no frame within " + std::to_string(opt_.first_frame_timeout_s) + " s", stats_.frames, false});
        spdlog::warn("camera {} dropped: no first frame", rig_.cameras[c].id);
      }
      any_live = any_live || live_[c];
    }
    // Recompile without the dropped cameras (in the background); swapped in when ready.
    if (!newly_dead.empty() && any_live) {
      if (pending_.valid()) pending_.wait();
      pending_active_ = live_;
      render::MapOptions m2 = mopt_;
      m2.active = live_;
      pending_ = std::async(std::launch::async,
                            [this, m2] { return render::compile_map_cached(rig_, m2, opt_.cache_dir).map; });
    }
    return fresh;
  }

  // Every camera has ended (or been dropped).
  bool all_ended() const {
    return std::none_of(live_.begin(), live_.end(), [](bool b) { return b; });
  }

  // The recompiled map, once ready (or waiting for it: at the end of the run).
  void swap_map_if_ready(bool wait) {
    if (!pending_.valid()) return;
    if (!wait && pending_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
    map_ = std::make_shared<render::CompiledMap>(pending_.get());
    for (auto& d : stats_.dropped_cameras)
      if (!pending_active_[d.index]) d.remapped = true;
  }

  // Every live camera has its first frame (or has been dropped for lacking one), and there is a
  // new frame or the rate is paced; once every camera has ended, the last frames render once.
  bool ready_to_render(bool fresh, bool finished) const {
    bool all_have = true;
    for (size_t c = 0; c < n_; ++c)
      if (live_[c] && !have_[c]) all_have = false;
    if (finished) {
      all_have = false;
      for (size_t c = 0; c < n_; ++c) all_have = all_have || have_[c];
      if (!fresh) return false;
    }
    return all_have && (fresh || opt_.fps > 0);
  }

  // Renders one panorama, measures its frame ages (engine.h, "Latency") and hands it to the sinks.
  void render_panorama(bool finished) {
    const auto r0 = Clock::now();
    if (depth_) {
      for (size_t c = 0; c < n_; ++c)  // a camera without a frame yet (dropped): black
        if (current_[c].empty()) current_[c] = cv::Mat(map_->layout.size[c], CV_8UC3, cv::Scalar::all(0));
      depth_ms_sum_ += depth_->render(*store_, current_, pano_).estimate_ms;
    } else {
      render::render(*map_, *store_, pano_, {.threads = opt_.threads});
    }
    const auto done = Clock::now();
    const double render_ms = ms_between(r0, done);
    render_ms_sum_ += render_ms;
    window_render_ms_sum_ += render_ms;
    info_.index = stats_.frames;
    info_.rendered = done;
    info_.captured.assign(n_, Clock::time_point{});
    double age_sum = 0, oldest = 0;
    int used = 0;
    for (size_t c = 0; c < n_; ++c)
      if ((live_[c] || finished) && have_[c]) {
        info_.captured[c] = captured_[c];
        const double age = ms_between(captured_[c], done);
        age_sum += age;
        oldest = std::max(oldest, age);
        ++used;
      }
    info_.latency_ms = used > 0 ? age_sum / used : 0;
    latency_sum_ += info_.latency_ms;
    window_latency_sum_ += info_.latency_ms;
    ++window_frames_;
    stats_.latency_ms_max = std::max(stats_.latency_ms_max, info_.latency_ms);
    stats_.oldest_frame_ms_max = std::max(stats_.oldest_frame_ms_max, oldest);
    if (opt_.on_panorama) opt_.on_panorama(pano_, info_);
    for (auto& s : sinks_) s->write(pano_, *store_);
  }

  // Frames/s of the slowest and the fastest camera since (seq, t) = its window start or its first
  // frame; live cameras, or every camera once all have ended.
  void camera_rates(const std::vector<long>& seq, const std::vector<Clock::time_point>& t, double* lo,
                    double* hi) const {
    *lo = 0;
    *hi = 0;
    bool any = false;
    const bool ended = all_ended();
    for (size_t c = 0; c < n_; ++c) {
      if (!have_[c] || (!live_[c] && !ended)) continue;
      const double s = std::chrono::duration<double>(t_last_[c] - t[c]).count();
      const double f = s > 0 ? (used_seq_[c] - seq[c]) / s : 0;
      *lo = any ? std::min(*lo, f) : f;
      *hi = any ? std::max(*hi, f) : f;
      any = true;
    }
  }

  // Every half second: the statistics so far and of the last window, to the sinks and on_progress.
  void publish_window_if_due() {
    const double window_s = std::chrono::duration<double>(Clock::now() - window_start_).count();
    if (window_s <= 0.5) return;
    stats_.seconds = std::chrono::duration<double>(Clock::now() - t0_).count();
    stats_.fps = stats_.frames / stats_.seconds;
    stats_.latency_ms = latency_sum_ / stats_.frames;
    stats_.render_ms_mean = render_ms_sum_ / stats_.frames;  // so far (the summary's is the run's)
    stats_.depth_ms_mean = depth_ms_sum_ / stats_.frames;
    stats_.camera_frames = 0;
    for (size_t c = 0; c < n_; ++c) stats_.camera_frames += used_seq_[c];
    camera_rates(seq_first_, t_first_, &stats_.camera_fps_min, &stats_.camera_fps_max);
    stats_.window.seconds = window_s;
    stats_.window.fps = window_frames_ / window_s;
    stats_.window.latency_ms = window_latency_sum_ / window_frames_;
    stats_.window.render_ms = window_render_ms_sum_ / window_frames_;
    camera_rates(seq_window_, t_window_, &stats_.window.camera_fps_min, &stats_.window.camera_fps_max);
    stats_.cameras_live = int(std::count(live_.begin(), live_.end(), true));
    seq_window_ = used_seq_;
    t_window_ = t_last_;
    window_start_ = Clock::now();
    window_frames_ = 0;
    window_latency_sum_ = 0;
    window_render_ms_sum_ = 0;
    const nlohmann::json j = stats_.to_json();
    for (auto& s : sinks_) s->set_stats(j);
    if (opt_.on_progress) opt_.on_progress(j);
  }

  // The run's summary; throws (sinks aborted) if no panorama was rendered, saying why.
  EngineSummary summary() {
    stats_.seconds = std::chrono::duration<double>(Clock::now() - t0_).count();
    if (stats_.frames == 0) {
      for (auto& s : sinks_) s->abort();
      std::string why = "no panorama was rendered";
      if (!stats_.dropped_cameras.empty()) {
        why += ": " + stats_.dropped_cameras.front().reason;
      } else {
        std::string waiting;
        for (size_t c = 0; c < n_; ++c)
          if (!have_[c]) waiting += (waiting.empty() ? "" : ", ") + std::to_string(rig_.cameras[c].id);
        if (!waiting.empty())
          why += " in " + fmt::format("{:.1f}", stats_.seconds) +
                 " s: still waiting for the first frame of camera(s) " + waiting;
      }
      throw std::runtime_error(why);
    }
    for (auto& s : sinks_) s->finish();
    stats_.camera_frames = 0;
    for (size_t c = 0; c < n_; ++c) stats_.camera_frames += latest_[c]->delivered.load();
    stats_.fps = stats_.frames / stats_.seconds;
    stats_.render_ms_mean = render_ms_sum_ / stats_.frames;
    stats_.depth_ms_mean = depth_ms_sum_ / stats_.frames;
    stats_.latency_ms = latency_sum_ / stats_.frames;
    camera_rates(seq_first_, t_first_, &stats_.camera_fps_min, &stats_.camera_fps_max);
    stats_.cameras_live = int(std::count(live_.begin(), live_.end(), true));
    return stats_;
  }

  const Rig& rig_;
  std::vector<std::unique_ptr<Sink>>& sinks_;
  const EngineOptions& opt_;
  const size_t n_;
  EngineSummary stats_;
  render::MapOptions mopt_;
  std::shared_ptr<render::CompiledMap> map_;
  std::unique_ptr<render::DepthRenderer> depth_;
  std::vector<isp::PhotometricTable> tables_;
  std::vector<std::unique_ptr<Latest>> latest_;
  std::mutex wake_mutex_;
  std::condition_variable wake_;
  std::unique_ptr<CameraThreads> cameras_;
  std::unique_ptr<render::FrameStore> store_;
  std::vector<cv::Mat> current_;  // depth mode: the frames in the store
  std::vector<long> used_seq_;
  std::vector<Clock::time_point> captured_;
  std::vector<bool> live_, have_;
  // Per camera: the sequence number and capture instant of its first frame, of its newest frame
  // at the window's start and of its newest frame (rates = frames between two capture instants).
  std::vector<long> seq_first_, seq_window_;
  std::vector<Clock::time_point> t_first_, t_window_, t_last_;
  std::future<render::CompiledMap> pending_;
  std::vector<bool> pending_active_;
  cv::Mat pano_;
  PanoramaInfo info_;
  double render_ms_sum_ = 0, depth_ms_sum_ = 0, latency_sum_ = 0, window_latency_sum_ = 0,
         window_render_ms_sum_ = 0;
  long window_frames_ = 0;
  Clock::time_point t0_, window_start_, next_frame_;
};

}  // namespace

EngineSummary run_engine(const Rig& rig, std::vector<std::unique_ptr<CameraSource>> sources,
                         std::vector<std::unique_ptr<Sink>>& sinks, const EngineOptions& opt) {
  const size_t n = rig.cameras.size();
  if (sources.size() != n)
    throw std::invalid_argument("run_engine: " + std::to_string(sources.size()) + " sources for " +
                                std::to_string(n) + " cameras");
  if (std::string why; !opt.IsValid(&why)) throw std::invalid_argument("run_engine: " + why);
  g_stop = false;
  RenderLoop loop(rig, sources, sinks, opt);
  return loop.run();
}

}  // namespace omma::live
