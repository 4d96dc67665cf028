#include "omma/bench/stream_bench.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <functional>
#include <mutex>
#include <numeric>
#include <stdexcept>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>
#include <spdlog/spdlog.h>

#include "omma/core/valid.h"
#include "omma/live/engine.h"
#include "omma/live/gst.h"
#include "omma/live/gst_util.h"
#include "omma/testing/net.h"

#if OMMA_HAVE_GSTREAMER
#include <gst/app/gstappsink.h>
#include <gst/app/gstappsrc.h>
#include <gst/gst.h>
#include <gst/video/video.h>
#endif

namespace omma::bench {

bool StreamBenchOptions::IsValid(std::string* why) const {
  if (size.width < 16 || size.height < 16 || size.width > 8192 || size.height > 8192)
    return invalid(why, "size must be 16x16 .. 8192x8192");
  if (!(fps >= 1 && fps <= 240) || !(camera_fps >= 1 && camera_fps <= 1000))
    return invalid(why, "fps must be 1..240 and camera_fps 1..1000");
  if (!(seconds >= 1 && seconds <= 600) || !(reader_seconds >= 0.5 && reader_seconds <= 600))
    return invalid(why, "seconds must be 1..600 and reader_seconds 0.5..600");
  if (!(flash_period_s >= 0.2 && flash_period_s <= 10)) return invalid(why, "flash_period_s must be 0.2..10");
  if (max_readers < 1 || max_readers > 64) return invalid(why, "max_readers must be 1..64");
  return true;
}

#if !OMMA_HAVE_GSTREAMER

nlohmann::json run_stream_bench(const Rig&, const StreamBenchOptions&) {
  live::init_gstreamer();  // throws: built without GStreamer
  return {};
}

#else

namespace {

using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

double ms(Clock::duration d) { return std::chrono::duration<double, std::milli>(d).count(); }

// The flash: black (0) or white (1), switch k at t0 + period (k + 0.3 frac(k g)), g the golden
// ratio: about one switch per period, at instants that drift against every frame clock (with a
// fixed period of a whole number of frame periods every sample would see the same phase of the
// camera and panorama ticks, and the spread of the latency would be lost).
struct Flash {
  Clock::time_point t0;
  double period = 1;
  double offset(long k) const {
    const double g = 0.6180339887498949 * double(k);
    return period * (double(k) + 0.3 * (g - std::floor(g)));
  }
  Clock::time_point switch_at(long k) const {
    return t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(offset(k)));
  }
  int level_at(Clock::time_point t) const {
    const double s = std::chrono::duration<double>(t - t0).count();
    if (s < 0) return 0;
    long k = long(std::floor(s / period));  // offset(k) >= k period, so the switch before s is k or k - 1
    if (offset(k) > s) --k;
    return int(k % 2);
  }
};

// A camera that shows the flash, free-running at `fps`, capture instant = the moment the frame is
// made. Its two frames never change after they are made (sources.h's contract). With `textured`
// it shows instead a detailed texture (noise blurred with sigma 1.5 px, as fine as a sharp photo)
// that scrolls 2 px per frame: an encoder's load of a moving, detailed scene (the readers' run).
class FlashSource : public live::CameraSource {
 public:
  FlashSource(const RigCamera& cam, double fps, const Flash& flash, Clock::time_point first, bool textured,
              uint64_t seed)
      : fps_(fps), flash_(flash), next_(first), textured_(textured) {
    black_ = cv::Mat(cam.in.height, cam.in.width, CV_8UC3, cv::Scalar::all(0));
    white_ = cv::Mat(cam.in.height, cam.in.width, CV_8UC3, cv::Scalar::all(255));
    if (textured_) {
      cv::Mat noise(cam.in.height, cam.in.width, CV_8UC3);
      cv::RNG rng(seed);
      rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
      cv::GaussianBlur(noise, noise, cv::Size(), 1.5);
      cv::hconcat(noise, noise, texture_);  // wraps around
    }
  }
  bool read(cv::Mat& frame) override {
    std::this_thread::sleep_until(next_);
    captured_ = Clock::now();
    if (textured_) {
      const int w = black_.cols, x = int((2 * count_++) % uint64_t(w));
      frame = texture_(cv::Rect(x, 0, w, black_.rows)).clone();  // a new buffer per frame
    } else {
      frame = flash_.level_at(captured_) ? white_ : black_;
    }
    next_ += std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1 / fps_));
    if (next_ < captured_) next_ = captured_;
    return true;
  }
  double fps() const override { return fps_; }
  Clock::time_point next_capture() override { return next_; }
  Clock::time_point last_capture() const override { return captured_; }
  std::string describe() const override { return textured_ ? "moving texture" : "flash"; }

 private:
  double fps_;
  Flash flash_;
  Clock::time_point next_, captured_;
  bool textured_;
  uint64_t count_ = 0;
  cv::Mat black_, white_, texture_;
};

// A free port on 127.0.0.1 (testing/net.h; bound and released: another program could take it in
// between).
int free_port() {
  const int port = testing::free_port();
  if (port <= 0) throw std::runtime_error("stream bench: cannot find a free port");
  return port;
}

// The mean grey level of a GRAY8 sample from every 7th byte (whatever the row stride; the padding
// of a row is at most 3 bytes of its width, so it barely moves the mean of a black or white frame).
double mean_grey(GstSample* s) {
  GstBuffer* b = gst_sample_get_buffer(s);
  GstMapInfo map;
  if (!b || !gst_buffer_map(b, &map, GST_MAP_READ)) return 0;
  double sum = 0;
  size_t n = 0;
  for (size_t i = 0; i < map.size; i += 7, ++n) sum += map.data[i];
  gst_buffer_unmap(b, &map);
  return n ? sum / double(n) : 0;
}

// A GStreamer pipeline ending in an appsink named "out", pulled in its own thread: the arrival
// instant of every buffer and, for GRAY8 video, its mean grey level. Before its first buffer an
// error restarts the pipeline (the server may not be up yet), until `give_up`.
class Reader {
 public:
  Reader(std::string launch, bool measure_level, Clock::time_point give_up)
      : launch_(std::move(launch)), level_(measure_level), give_up_(give_up) {
    thread_ = std::thread([this] { loop(); });
  }
  ~Reader() { stop(); }
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  struct Sample {
    Clock::time_point t;
    double mean = 0;
    size_t bytes = 0;  // the buffer's size
  };
  std::vector<Sample> samples() {
    std::lock_guard<std::mutex> lock(mutex_);
    return samples_;
  }
  // Buffers that arrived in [a, b).
  long count_between(Clock::time_point a, Clock::time_point b) {
    std::lock_guard<std::mutex> lock(mutex_);
    return std::count_if(samples_.begin(), samples_.end(),
                         [&](const Sample& s) { return s.t >= a && s.t < b; });
  }
  // Bytes of the buffers that arrived in [a, b).
  size_t bytes_between(Clock::time_point a, Clock::time_point b) {
    std::lock_guard<std::mutex> lock(mutex_);
    size_t n = 0;
    for (const Sample& s : samples_)
      if (s.t >= a && s.t < b) n += s.bytes;
    return n;
  }
  std::string error() {
    std::lock_guard<std::mutex> lock(mutex_);
    return error_;
  }

 private:
  void loop() {
    while (!stop_) {
      std::string why;
      GstElement* pipe = live::parse_pipeline(launch_, &why);  // live/gst_util.h
      if (!pipe) {
        set_error(why);
        return;
      }
      GstElement* sink = gst_bin_get_by_name(GST_BIN(pipe), "out");
      GstBus* bus = gst_element_get_bus(pipe);
      gst_element_set_state(pipe, GST_STATE_PLAYING);
      bool retry = false;
      while (!stop_) {
        if (GstSample* s = gst_app_sink_try_pull_sample(GST_APP_SINK(sink), 50 * GST_MSECOND)) {
          record(s);
          gst_sample_unref(s);
        }
        if (GstMessage* m = gst_bus_pop_filtered(bus, GstMessageType(GST_MESSAGE_ERROR | GST_MESSAGE_EOS))) {
          if (GST_MESSAGE_TYPE(m) == GST_MESSAGE_ERROR) {
            set_error(live::message_text(m));
          } else {
            set_error("end of stream");
          }
          gst_message_unref(m);
          retry = !got_any_ && Clock::now() < give_up_;
          break;
        }
      }
      gst_element_set_state(pipe, GST_STATE_NULL);
      gst_object_unref(bus);
      gst_object_unref(sink);
      gst_object_unref(pipe);
      if (!retry) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
  }
  void record(GstSample* s) {
    GstBuffer* b = gst_sample_get_buffer(s);
    const Sample out{Clock::now(), level_ ? mean_grey(s) : 0, b ? gst_buffer_get_size(b) : 0};
    std::lock_guard<std::mutex> lock(mutex_);
    samples_.push_back(out);
    got_any_ = true;
  }
  void set_error(const std::string& e) {
    std::lock_guard<std::mutex> lock(mutex_);
    error_ = e;
  }

  std::string launch_;
  bool level_;
  Clock::time_point give_up_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> got_any_{false};
  std::mutex mutex_;
  std::vector<Sample> samples_;
  std::string error_;
  std::thread thread_;
};

// Latency samples (ms) of one reader: for every switch of the flash between `from` and `to`, the
// first buffer after it whose level is the new one (threshold: halfway between the darkest and
// the brightest buffer the reader saw), if within one period.
std::vector<double> flash_latencies(const std::vector<Reader::Sample>& samples, const Flash& flash,
                                    Clock::time_point from, Clock::time_point to) {
  std::vector<double> out;
  if (samples.empty()) return out;
  double lo = 255, hi = 0;
  for (const auto& s : samples) lo = std::min(lo, s.mean), hi = std::max(hi, s.mean);
  if (hi - lo < 32) return out;  // never saw both levels
  const double mid = (lo + hi) / 2;
  for (long k = 1;; ++k) {
    const Clock::time_point t = flash.switch_at(k);
    if (t > to) break;
    if (t < from) continue;
    const int level = k % 2;
    const auto end =
        t + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(flash.period));
    for (const auto& s : samples) {
      if (s.t <= t) continue;
      if (s.t >= end) break;
      if ((s.mean > mid) == (level == 1)) {
        out.push_back(ms(s.t - t));
        break;
      }
    }
  }
  return out;
}

nlohmann::json stats_of(std::vector<double> v) {
  nlohmann::json j = {{"samples", v.size()}};
  if (v.empty()) return j;
  std::sort(v.begin(), v.end());
  auto q = [&](double p) { return v[std::min(v.size() - 1, size_t(p * double(v.size() - 1) + 0.5))]; };
  j["min_ms"] = v.front();
  j["median_ms"] = q(0.5);
  j["p90_ms"] = q(0.9);
  j["max_ms"] = v.back();
  return j;
}

void say(const StreamBenchOptions& opt, const std::string& what) {
  if (opt.progress) fmt::print(stderr, "stream bench: {}\n", what);
}

// The element: appsrc x N -> ommastitch -> appsink, the flash pushed into every pad.
nlohmann::json measure_element(const Rig& rig, const StreamBenchOptions& opt, const fs::path& work) {
  std::string plugin = opt.plugin;
  if (plugin.empty()) {
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    for (const fs::path& p :
         {exe.parent_path() / "gst" / "libgstomma.so",
          exe.parent_path().parent_path() / "lib" / "x86_64-linux-gnu" / "gstreamer-1.0" / "libgstomma.so",
          exe.parent_path().parent_path() / "lib" / "gstreamer-1.0" / "libgstomma.so"})
      if (!ec && fs::exists(p)) {
        plugin = p.string();
        break;
      }
  }
  if (!plugin.empty()) {
    GError* err = nullptr;
    GstPlugin* p = gst_plugin_load_file(plugin.c_str(), &err);
    if (!p) {
      const std::string why = err ? err->message : "unknown error";
      if (err) g_error_free(err);
      return {{"error", "cannot load the plugin " + plugin + ": " + why}};
    }
    gst_object_unref(p);
  }
  GstElementFactory* factory = gst_element_factory_find("ommastitch");
  if (!factory)
    return {{"error", "the ommastitch element is not found (build gst/, or set GST_PLUGIN_PATH)"}};
  gst_object_unref(factory);

  const fs::path rig_path = work / "rig.json";
  save_rig(rig, rig_path);
  const int n = int(rig.cameras.size());
  std::string launch;
  for (int c = 0; c < n; ++c)
    launch += fmt::format(
        "appsrc name=c{} is-live=true format=time do-timestamp=true block=false max-bytes=0 "
        "caps=video/x-raw,format=BGR,width={},height={},framerate={}/1 ! s.sink_{} ",
        c, rig.cameras[c].in.width, rig.cameras[c].in.height, int(std::lround(opt.camera_fps)), c);
  launch += fmt::format(
      "ommastitch name=s rig=\"{}\" size={}x{} fps={} photometric=false ! videoconvert ! "
      "video/x-raw,format=GRAY8 ! appsink name=out sync=false max-buffers=4 drop=true",
      rig_path.string(), opt.size.width, opt.size.height, opt.fps);

  std::string why;
  GstElement* pipe = live::parse_pipeline(launch, &why);
  if (!pipe) return {{"error", why}};
  std::vector<GstElement*> srcs;
  for (int c = 0; c < n; ++c)
    srcs.push_back(gst_bin_get_by_name(GST_BIN(pipe), fmt::format("c{}", c).c_str()));
  GstElement* sink = gst_bin_get_by_name(GST_BIN(pipe), "out");
  GstBus* bus = gst_element_get_bus(pipe);

  // Each camera's frame in GStreamer's layout of its caps (rows padded to 4 bytes), all 0 or all 255.
  std::vector<size_t> frame_bytes;
  for (const auto& cam : rig.cameras) {
    GstVideoInfo info;
    gst_video_info_set_format(&info, GST_VIDEO_FORMAT_BGR, guint(cam.in.width), guint(cam.in.height));
    frame_bytes.push_back(GST_VIDEO_INFO_SIZE(&info));
  }
  const std::vector<uint8_t> black(*std::max_element(frame_bytes.begin(), frame_bytes.end()), 0),
      white(black.size(), 255);
  const Flash flash{Clock::now() + std::chrono::seconds(1), opt.flash_period_s};
  std::atomic<bool> stop{false};
  gst_element_set_state(pipe, GST_STATE_PLAYING);
  std::thread pusher([&] {
    auto next = Clock::now();
    const auto step =
        std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1 / opt.camera_fps));
    while (!stop) {
      std::this_thread::sleep_until(next);
      next += step;
      const int level = flash.level_at(Clock::now());
      for (int c = 0; c < n; ++c) {
        GstBuffer* b = gst_buffer_new_memdup((level ? white : black).data(), frame_bytes[c]);
        gst_app_src_push_buffer(GST_APP_SRC(srcs[c]), b);  // takes the buffer
      }
    }
  });
  std::vector<Reader::Sample> samples;
  nlohmann::json stats;
  std::string error;
  const auto t_end = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                        std::chrono::duration<double>(opt.seconds + 1.5));
  Clock::time_point first{};
  while (Clock::now() < t_end) {
    if (GstSample* s = gst_app_sink_try_pull_sample(GST_APP_SINK(sink), 50 * GST_MSECOND)) {
      const Reader::Sample out{Clock::now(), mean_grey(s)};
      if (first == Clock::time_point{}) first = out.t;
      samples.push_back(out);
      gst_sample_unref(s);
    }
    while (GstMessage* m = gst_bus_pop(bus)) {
      if (GST_MESSAGE_TYPE(m) == GST_MESSAGE_ERROR) {
        error = live::message_text(m);
      } else if (GST_MESSAGE_TYPE(m) == GST_MESSAGE_ELEMENT) {
        const GstStructure* st = gst_message_get_structure(m);
        if (st && gst_structure_has_name(st, "omma-stats")) {
          for (const char* f : {"fps", "render-ms", "latency-ms", "push-latency-ms"}) {
            double v = 0;
            if (gst_structure_get_double(st, f, &v)) stats[f] = v;
          }
        }
      }
      gst_message_unref(m);
    }
    if (!error.empty()) break;
  }
  stop = true;
  pusher.join();
  gst_element_set_state(pipe, GST_STATE_NULL);
  for (GstElement* e : srcs) gst_object_unref(e);
  gst_object_unref(sink);
  gst_object_unref(bus);
  gst_object_unref(pipe);

  nlohmann::json j = stats_of(flash_latencies(samples, flash, first + std::chrono::milliseconds(500), t_end));
  j["panoramas"] = samples.size();
  if (samples.size() > 1)
    j["fps"] = double(samples.size() - 1) /
               std::chrono::duration<double>(samples.back().t - samples.front().t).count();
  j["element_stats"] = stats;  // the element's own omma-stats message, the last one
  j["plugin"] = plugin;
  if (!error.empty()) j["error"] = error;
  return j;
}

// One engine run with the flash cameras and `sinks`, while `during` runs in this thread; returns
// the engine's summary.
nlohmann::json run_with(const Rig& rig, const StreamBenchOptions& opt,
                        const std::vector<std::string>& sink_specs, double duration_s, const Flash& flash,
                        bool textured, const std::function<void()>& during) {
  live::SinkOptions so;
  so.fps = opt.fps;
  std::vector<std::unique_ptr<live::Sink> > sinks;
  for (const auto& s : sink_specs) sinks.push_back(live::open_sink(s, rig, opt.size, so));
  std::vector<std::unique_ptr<live::CameraSource> > sources;
  const auto first = Clock::now();
  for (const auto& cam : rig.cameras)
    sources.push_back(std::make_unique<FlashSource>(cam, opt.camera_fps, flash, first, textured,
                                                    uint64_t(sources.size()) + 1));
  live::EngineOptions eo;
  eo.map.grid = PanoGrid(Projection::kVr180, opt.size.width, opt.size.height);
  eo.fps = opt.fps;
  eo.duration_s = duration_s;
  eo.photometric = false;  // black stays black and white white
  std::atomic<bool> stop{false};
  eo.stop = &stop;
  live::EngineSummary summary;
  std::exception_ptr failed;
  std::thread engine([&] {
    try {
      summary = live::run_engine(rig, std::move(sources), sinks, eo);
      for (auto& s : sinks) s->finish();
    } catch (...) {
      failed = std::current_exception();
    }
  });
  try {
    during();
  } catch (...) {
    stop = true;
    engine.join();
    throw;
  }
  engine.join();
  if (failed) std::rethrow_exception(failed);
  return summary.to_json();
}

}  // namespace

nlohmann::json run_stream_bench(const Rig& rig, const StreamBenchOptions& opt) {
  if (std::string why; !opt.IsValid(&why)) throw std::invalid_argument("stream bench: " + why);
  live::init_gstreamer();
  const fs::path work = fs::temp_directory_path() / fmt::format("omma-stream-bench-{}", ::getpid());
  fs::create_directories(work);
  nlohmann::json out = {{"size", fmt::format("{}x{}", opt.size.width, opt.size.height)},
                        {"fps", opt.fps},
                        {"camera_fps", opt.camera_fps},
                        {"cameras", rig.cameras.size()},
                        {"rig", rig.name},
                        {"hardware_threads", std::thread::hardware_concurrency()}};
  try {
    if (opt.element) {
      say(opt, "element: appsrc x " + std::to_string(rig.cameras.size()) + " -> ommastitch -> appsink");
      out["element"] = measure_element(rig, opt, work);
    }
    if (opt.rtsp) {
      const int rtsp_port = free_port(), http_port = free_port();
      const std::string url = fmt::format("rtsp://127.0.0.1:{}/pano", rtsp_port);
      say(opt, "rtsp and mjpeg: the engine -> " + url + " and http:" + std::to_string(http_port));
      const Flash flash{Clock::now() + std::chrono::seconds(2), opt.flash_period_s};
      std::vector<Reader::Sample> rtsp_samples, mjpeg_samples;
      std::string rtsp_error, mjpeg_error;
      Clock::time_point from{}, to{};
      const double duration = opt.seconds + 4;
      nlohmann::json engine =
          run_with(rig, opt, {url, fmt::format("http:{}", http_port)}, duration, flash, false, [&] {
            const auto give_up = Clock::now() + std::chrono::seconds(10);
            Reader rtsp(
                fmt::format("rtspsrc location={} protocols=tcp latency=0 ! rtph264depay ! avdec_h264 ! "
                            "videoconvert ! video/x-raw,format=GRAY8 ! appsink name=out sync=false "
                            "max-buffers=2 drop=true",
                            url),
                true, give_up);
            Reader mjpeg(fmt::format("souphttpsrc location=http://127.0.0.1:{}/stream.mjpg is-live=true ! "
                                     "multipartdemux ! jpegdec ! videoconvert ! video/x-raw,format=GRAY8 ! "
                                     "appsink name=out sync=false max-buffers=2 drop=true",
                                     http_port),
                         true, give_up);
            from = Clock::now() + std::chrono::seconds(2);
            to = from +
                 std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(opt.seconds));
            std::this_thread::sleep_until(to + std::chrono::milliseconds(500));
            rtsp.stop();
            mjpeg.stop();
            rtsp_samples = rtsp.samples();
            mjpeg_samples = mjpeg.samples();
            rtsp_error = rtsp.error();
            mjpeg_error = mjpeg.error();
          });
      out["rtsp"] = stats_of(flash_latencies(rtsp_samples, flash, from, to));
      out["rtsp"]["frames"] = rtsp_samples.size();
      if (rtsp_samples.empty()) out["rtsp"]["error"] = rtsp_error;
      out["mjpeg"] = stats_of(flash_latencies(mjpeg_samples, flash, from, to));
      out["mjpeg"]["frames"] = mjpeg_samples.size();
      if (mjpeg_samples.empty()) out["mjpeg"]["error"] = mjpeg_error;
      out["engine"] = {{"fps", engine.value("fps", 0.0)},
                       {"latency_ms", engine.value("latency_ms", 0.0)},
                       {"render_ms_mean", engine.value("render_ms_mean", 0.0)}};
    }
    if (opt.readers) {
      const int port = free_port();
      const std::string url = fmt::format("rtsp://127.0.0.1:{}/pano", port);
      std::vector<int> ks;
      for (int k = 1; k <= opt.max_readers; k *= 2) ks.push_back(k);
      if (ks.back() != opt.max_readers) ks.push_back(opt.max_readers);
      say(opt, fmt::format("readers: up to {} RTSP readers of {}", opt.max_readers, url));
      const Flash flash{Clock::now(), 1e9};
      nlohmann::json levels = nlohmann::json::array();
      const double stage = opt.reader_seconds + 1.5;
      const double duration = 3 + stage * double(ks.size()) + 1;
      nlohmann::json engine = run_with(rig, opt, {url}, duration, flash, true, [&] {
        std::vector<std::unique_ptr<Reader> > readers;
        std::this_thread::sleep_for(std::chrono::seconds(2));
        for (int k : ks) {
          while (int(readers.size()) < k)
            readers.push_back(std::make_unique<Reader>(
                fmt::format("rtspsrc location={} protocols=tcp latency=0 ! rtph264depay ! appsink name=out "
                            "sync=false",
                            url),
                false, Clock::now() + std::chrono::seconds(5)));
          std::this_thread::sleep_for(std::chrono::milliseconds(1500));
          const auto a = Clock::now();
          std::this_thread::sleep_for(std::chrono::duration<double>(opt.reader_seconds));
          const auto b = Clock::now();
          std::vector<double> rates;
          for (auto& r : readers)
            rates.push_back(double(r->count_between(a, b)) / std::chrono::duration<double>(b - a).count());
          const double slowest = *std::min_element(rates.begin(), rates.end());
          const double mbit_s =
              8e-6 * double(readers[0]->bytes_between(a, b)) / std::chrono::duration<double>(b - a).count();
          levels.push_back(
              {{"readers", k},
               {"stream_mbit_s", mbit_s},
               {"slowest_fps", slowest},
               {"mean_fps", std::accumulate(rates.begin(), rates.end(), 0.0) / double(rates.size())}});
          say(opt, fmt::format("  {} readers: slowest {:.1f} frames/s", k, slowest));
          if (slowest < 0.5 * opt.fps) break;  // far below: more readers only load the machine
        }
        for (auto& r : readers) r->stop();
      });
      int best = 0;
      for (const auto& l : levels)
        if (l["slowest_fps"].get<double>() >= 0.95 * engine.value("fps", opt.fps)) best = l["readers"];
      out["readers"] = levels;
      out["readers_engine_fps"] = engine.value("fps", 0.0);
      out["max_readers_full_rate"] = best;
    }
  } catch (...) {
    std::error_code ec;
    fs::remove_all(work, ec);
    throw;
  }
  std::error_code ec;
  fs::remove_all(work, ec);
  return out;
}

#endif

}  // namespace omma::bench
