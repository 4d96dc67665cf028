// The live engine for Python: omma.run(rig, source=..., sinks=[...]) is an iterator of panoramas,
// the peer of `omma run` (live/engine.h). The engine runs in a C++ thread (sources, render loop and
// sinks in their own threads, the GIL never taken there); each panorama is copied into a bounded
// queue that the Python loop takes from, the GIL released while it waits. A consumer slower than
// the engine holds the render loop back (no panorama is skipped: the sinks get the same frames as
// Python); leaving the loop (break, close(), garbage collection) stops the engine, which finishes
// its sinks (playable videos).
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <thread>

#include <fmt/format.h>
#include <opencv2/core/utility.hpp>
#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "omma/core/grid.h"
#include "omma/live/engine.h"

namespace omma::py {

namespace {

class LiveRun {
 public:
  LiveRun(Rig rig, const std::vector<std::string>& sources, const std::vector<std::string>& sinks,
          const live::EngineOptions& eo, const live::SourceOptions& so, const live::SinkOptions& sk,
          size_t queue)
      : rig_(std::move(rig)), eo_(eo), cap_(queue) {
    for (const std::string& why : {valid_why(eo_), valid_why(so), valid_why(sk)})
      if (!why.empty()) throw py::value_error(why);
    eo_.on_panorama = [this](const cv::Mat& pano, const live::PanoramaInfo& info) { push(pano, info); };
    const cv::Size size(eo_.map.grid.width, eo_.map.grid.height);
    py::gil_scoped_release release;
    auto src = live::open_sources(rig_, sources, so);
    try {
      for (const auto& s : sinks) sinks_.push_back(live::open_sink(s, rig_, size, sk));
    } catch (...) {
      for (auto& s : sinks_) s->abort();
      throw;
    }
    thread_ = std::thread([this, src = std::move(src)]() mutable {
      live::EngineSummary sum;
      std::exception_ptr err;
      try {
        sum = live::run_engine(rig_, std::move(src), sinks_, eo_);
      } catch (...) {
        err = std::current_exception();
      }
      std::lock_guard lock(mu_);
      summary_ = std::move(sum);
      error_ = err;
      done_ = true;
      cv_.notify_all();
    });
  }
  ~LiveRun() { stop(); }

  py::object next() {
    cv::Mat pano;
    // Waits without the GIL, checking Python's signals every 0.1 s: Ctrl-C stops the engine (the
    // sinks are finished) and raises KeyboardInterrupt.
    for (bool ready = false; !ready;) {
      {
        py::gil_scoped_release release;
        std::unique_lock lock(mu_);
        ready = cv_.wait_for(lock, std::chrono::milliseconds(100), [&] { return !queue_.empty() || done_; });
        if (!queue_.empty()) {
          pano = std::move(queue_.front().first);
          last_ = queue_.front().second;
          queue_.pop_front();
          cv_.notify_all();
        }
      }
      if (!ready && PyErr_CheckSignals() != 0) {
        py::error_already_set interrupted;  // takes the pending exception (KeyboardInterrupt)
        stop();
        throw interrupted;
      }
    }
    if (!pano.empty()) return array_from_mat(pano);
    stop();
    if (error_) {
      auto e = error_;
      error_ = nullptr;  // raised once
      std::rethrow_exception(e);
    }
    throw py::stop_iteration();
  }

  // Stops the engine (if still running) and waits for it: the sinks are finished.
  void stop() {
    {
      std::lock_guard lock(mu_);
      closed_ = true;
      cv_.notify_all();
    }
    if (thread_.joinable()) {
      py::gil_scoped_release release;
      live::request_stop();
      thread_.join();
    }
  }

  bool done() const { return done_; }
  const live::EngineSummary& summary() const { return summary_; }
  const live::PanoramaInfo& last() const { return last_; }
  std::vector<std::string> sink_names() const {
    std::vector<std::string> out;
    for (const auto& s : sinks_) out.push_back(s->describe());
    return out;
  }

 private:
  template <class T>
  static std::string valid_why(const T& o) {
    std::string why;
    return o.IsValid(&why) ? std::string() : why;
  }
  // From the render loop: hands the panorama over, waiting while the queue is full.
  void push(const cv::Mat& pano, const live::PanoramaInfo& info) {
    std::unique_lock lock(mu_);
    cv_.wait(lock, [&] { return queue_.size() < cap_ || closed_; });
    if (closed_) {
      live::request_stop();
      return;
    }
    queue_.emplace_back(pano.clone(), info);
    cv_.notify_all();
  }

  Rig rig_;
  live::EngineOptions eo_;
  size_t cap_;
  std::vector<std::unique_ptr<live::Sink>> sinks_;
  std::thread thread_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<std::pair<cv::Mat, live::PanoramaInfo>> queue_;
  bool closed_ = false;
  std::atomic<bool> done_{false};
  std::exception_ptr error_;
  live::EngineSummary summary_;
  live::PanoramaInfo last_;
};

std::vector<std::string> spec_list(const py::object& v, const char* what, bool empty_ok) {
  std::vector<std::string> out;
  if (v.is_none()) {
  } else if (py::isinstance<py::str>(v) || py::hasattr(v, "__fspath__")) {
    out.push_back(py::str(py::module_::import("os").attr("fspath")(v)).cast<std::string>());
  } else {
    for (const auto& s : v)
      out.push_back(py::str(py::module_::import("os").attr("fspath")(s)).cast<std::string>());
  }
  if (out.empty() && !empty_ok) throw py::value_error(fmt::format("{}: give at least one spec", what));
  return out;
}

}  // namespace

void add_live(py::module_& m) {
  py::class_<LiveRun>(
      m, "LiveRun",
      "A running live engine (omma.run): an iterator of panoramas, uint8 (H, W, 3) BGR, one per "
      "render. Leaving the loop or close() stops the engine; `summary` then holds its statistics.")
      .def("__iter__", [](py::object self) { return self; })
      .def("__next__", &LiveRun::next)
      .def("close", &LiveRun::stop,
           "Stops the engine and waits for it (the sinks are finished, videos playable).")
      .def("__enter__", [](py::object self) { return self; })
      .def(
          "__exit__", [](LiveRun& r, const py::args&) { r.stop(); }, "Stops the engine (close()).")
      .def_property_readonly(
          "summary",
          [](const LiveRun& r) {
            if (!r.done()) return py::object(py::none());
            py::object d = to_python(r.summary().to_json());
            d["sinks"] = r.sink_names();
            return d;
          },
          "The engine's summary (as `omma run --json`: frames, fps, latency_ms, dropped cameras, ...) once "
          "it "
          "has stopped; None while it runs.")
      .def_property_readonly(
          "latency_ms", [](const LiveRun& r) { return r.last().latency_ms; },
          "Mean age of the camera frames of the last panorama handed out, ms.")
      .def_property_readonly(
          "index", [](const LiveRun& r) { return r.last().index; },
          "Index of the last panorama handed out (0-based).")
      .def_property_readonly("sinks", &LiveRun::sink_names);

  m.def(
      "run",
      [](const Rig& rig, const py::object& source, const py::object& sinks, const std::string& method,
         const std::string& projection, const py::object& size, long frames, double duration, double fps,
         double source_fps, bool loop, double min_weight, int threads, const py::object& cache_dir,
         bool photometric, bool depth, const py::object& sim_fps, double sim_loop, double sim_jitter_ms,
         int camera_threads, int max_streams, double first_frame_timeout, int queue, bool progress) {
        live::EngineOptions eo;
        eo.map.method = pano::parse_method(method);
        const cv::Size s = size_from_python(size);
        eo.map.grid = PanoGrid{parse_projection(projection), s.width, s.height};
        eo.map.min_weight = min_weight;
        eo.cache_dir = cache_dir_from_python(cache_dir);
        if (frames < 0) throw py::value_error("frames must be >= 0");
        if (duration < 0) throw py::value_error("duration must be >= 0");
        eo.duration_s = duration;
        eo.max_frames = frames;
        eo.fps = fps;
        eo.threads = threads;
        eo.depth = depth;
        eo.photometric = photometric;
        eo.first_frame_timeout_s = first_frame_timeout;
        eo.max_camera_threads = camera_threads;
        live::SourceOptions so;
        so.fps = source_fps;
        so.loop = loop;
        so.sim.progress = progress;
        so.sim.loop_s = sim_loop;
        so.sim.jitter_ms = sim_jitter_ms;
        if (!sim_fps.is_none()) {
          if (py::isinstance<py::sequence>(sim_fps) && py::len(sim_fps) == 2) {
            const auto r = sim_fps.cast<std::pair<double, double>>();
            so.sim.fps_min = r.first, so.sim.fps_max = r.second;
          } else {
            so.sim.fps_min = so.sim.fps_max = sim_fps.cast<double>();
          }
        }
        live::SinkOptions sk;
        sk.fps = fps > 0 ? fps : 30;
        sk.projection = eo.map.grid.projection;
        sk.spherical_metadata = true;
        sk.max_streams = max_streams;
        if (queue < 1) throw py::value_error("queue must be >= 1");
        cv::setNumThreads(1);  // as `omma run`: OpenCV's own threads would compete with the renderer's
        return std::make_unique<LiveRun>(rig, spec_list(source, "source", false),
                                         spec_list(sinks, "sinks", true), eo, so, sk, size_t(queue));
      },
      py::arg("rig"), py::arg("source"), py::arg("sinks") = py::none(), py::arg("method") = "linear",
      py::arg("projection") = "vr180", py::arg("size") = py::make_tuple(1080, 1080), py::arg("frames") = 0,
      py::arg("duration") = 0.0, py::arg("fps") = 30.0, py::arg("source_fps") = 30.0, py::arg("loop") = false,
      py::arg("min_weight") = 1.0 / 20, py::arg("threads") = 0, py::arg("cache_dir") = py::none(),
      py::arg("photometric") = true, py::arg("depth") = false, py::arg("sim_fps") = py::none(),
      py::arg("sim_loop") = live::SimCameraOptions{}.loop_s,
      py::arg("sim_jitter_ms") = live::SimCameraOptions{}.jitter_ms,
      py::arg("camera_threads") = live::EngineOptions{}.max_camera_threads,
      py::arg("max_streams") = live::SinkOptions{}.max_streams, py::arg("first_frame_timeout") = 10.0,
      py::arg("queue") = 2, py::arg("progress") = false,
      "The live engine, as `omma run`: free-running camera sources -> compiled map -> renderer -> sinks, "
      "and\n"
      "each panorama (uint8 (H, W, 3) BGR) handed to Python:\n"
      "    for pano in omma.run(rig, source='sim:colon', frames=10, sinks=['out.mp4']): ...\n"
      "source: one spec for all cameras or one per camera (sim:SCENE[@SPEED], frames:DIR, "
      "pano:IMAGE[@DEG_S],\n"
      "DIR, FILE.mp4, v4l2:N, link:FILE, patterns with {id}); sinks: FILE.mp4|mkv|avi, png:DIR, "
      "cam:ID:SINK,\n"
      "http:PORT (mp4 and png with 360-degree metadata). Stops after `frames` panoramas, `duration` s, or\n"
      "when every source has ended. fps: panorama rate (0: whenever a camera has a new frame). sim_fps: the\n"
      "simulated cameras' rate, one value or (min, max) (default 44-56); sim_loop: seconds of the "
      "pre-rendered\n"
      "loop (memory and start-up time grow with it); sim_jitter_ms: capture-time jitter. queue: panoramas "
      "waiting for Python at most (the\n"
      "engine waits for a slower consumer). cache_dir: None = the default map cache, False = none. Returns "
      "a\n"
      "LiveRun (iterator; .summary once stopped). Ctrl-C while waiting for a panorama stops the engine and\n"
      "raises KeyboardInterrupt. One run at a time per process: close() stops all.");
}

}  // namespace omma::py
