// gst:PIPELINE camera sources (gst.h): the user's pipeline, then videoconvert to BGR and an appsink
// that keeps only the newest frame; read() takes the next frame, watching the bus for errors, the
// end of the stream and stalls.
#include <stdexcept>

#include "omma/live/gst.h"
#include "omma/live/gst_util.h"

#if OMMA_HAVE_GSTREAMER
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <set>
#include <thread>

#include <fmt/format.h>
#include <gst/app/gstappsink.h>
#include <gst/gst.h>
#include <gst/video/video.h>
#include <spdlog/spdlog.h>
#endif

namespace omma::live {

#if OMMA_HAVE_GSTREAMER
namespace {

constexpr const char* kSinkName = "omma_appsink";
// read() waits for a sample in slices of this long, looking at the bus in between.
constexpr GstClockTime kSlice = 50 * GST_MSECOND;
// The destructor waits this long for the pipeline to stop; a pipeline stuck longer is left to stop
// in the background.
constexpr auto kStopWait = std::chrono::seconds(2);

// The pipeline as named in messages: "gst:" and the description, shortened if long.
std::string short_spec(const std::string& pipeline) {
  constexpr size_t kMax = 80;
  if (pipeline.size() <= kMax) return "gst:" + pipeline;
  return "gst:" + pipeline.substr(0, kMax - 3) + "...";
}

// Only errors, warnings and the end of the stream are kept on the bus (read() pops them); the
// rest (state changes, QoS, stream status ...) is dropped as it is posted, so that the bus never
// fills up while nobody reads it.
GstBusSyncReply keep_errors(GstBus*, GstMessage* msg, gpointer) {
  switch (GST_MESSAGE_TYPE(msg)) {
    case GST_MESSAGE_ERROR:
    case GST_MESSAGE_WARNING:
    case GST_MESSAGE_EOS:
      return GST_BUS_PASS;
    default:
      return GST_BUS_DROP;
  }
}

class GstSource : public CameraSource {
 public:
  GstSource(const std::string& pipeline, const RigCamera& cam, const SourceOptions& opt)
      : spec_(short_spec(pipeline)), cam_id_(cam.id), size_(cam.in.width, cam.in.height), opt_(opt) {
    const std::string desc = pipeline +
                             " ! videoconvert ! video/x-raw,format=BGR ! appsink name=" + kSinkName +
                             " max-buffers=1 drop=true sync=true enable-last-sample=false";
    std::string why;
    GstElement* top = parse_pipeline(desc, &why);  // gst_util.h
    if (!top) throw SourceError("source '" + spec_ + "': the pipeline cannot be built: " + why);
    pipeline_ = top;
    appsink_ = GST_IS_BIN(top) ? gst_bin_get_by_name(GST_BIN(top), kSinkName) : nullptr;
    if (!appsink_) {
      stop_pipeline();
      throw SourceError("source '" + spec_ + "': the pipeline cannot be built (no appsink at its end)");
    }
    bus_ = gst_element_get_bus(pipeline_);
    gst_bus_set_sync_handler(bus_, keep_errors, nullptr, nullptr);
    // A failure to start (e.g. a file that does not exist) is also an ERROR on the bus: read() reports
    // it, so that the engine drops this camera as it would one that fails later.
    if (gst_element_set_state(pipeline_, GST_STATE_PLAYING) == GST_STATE_CHANGE_FAILURE) start_failed_ = true;
    last_frame_ = std::chrono::steady_clock::now();
  }

  ~GstSource() override {
    if (bus_) {
      gst_bus_set_sync_handler(bus_, nullptr, nullptr, nullptr);
      gst_object_unref(bus_);
    }
    if (appsink_) gst_object_unref(appsink_);
    stop_pipeline();
  }

  bool read(cv::Mat& frame) override {
    for (;;) {
      check_bus();
      if (GstSample* sample = gst_app_sink_try_pull_sample(GST_APP_SINK(appsink_), kSlice)) {
        try {
          frame = to_mat(sample);
        } catch (...) {
          gst_sample_unref(sample);
          throw;
        }
        gst_sample_unref(sample);
        last_frame_ = std::chrono::steady_clock::now();
        return true;
      }
      if (start_failed_) {
        check_bus();
        throw SourceError("source '" + spec_ + "': the pipeline cannot be started");
      }
      if (gst_app_sink_is_eos(GST_APP_SINK(appsink_))) {
        check_bus();  // an error that ended the stream is an error, not the end
        if (!opt_.loop) return false;
        restart();
        continue;
      }
      const double waited =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - last_frame_).count();
      if (waited >= opt_.stall_s)
        throw SourceError(fmt::format("source '{}' stalled: no frame for {:g} s", spec_, opt_.stall_s));
    }
  }

  double fps() const override { return fps_.load(); }
  std::string describe() const override { return spec_; }

 private:
  // Throws the first error on the bus; logs warnings; ends on the end of the stream (appsink says so).
  void check_bus() {
    while (GstMessage* msg = gst_bus_pop(bus_)) {
      if (GST_MESSAGE_TYPE(msg) == GST_MESSAGE_ERROR || GST_MESSAGE_TYPE(msg) == GST_MESSAGE_WARNING) {
        const bool error = GST_MESSAGE_TYPE(msg) == GST_MESSAGE_ERROR;
        std::string d;
        std::string text =
            fmt::format("source '{}': GStreamer {} from element '{}': {}", spec_, error ? "error" : "warning",
                        GST_OBJECT_NAME(GST_MESSAGE_SRC(msg)), message_text(msg, &d));  // gst_util.h
        // The debug text's last line is the detail (e.g. 'No such file "/x"'); the rest is source
        // locations and the element's path.
        while (!d.empty() && (d.back() == '\n' || d.back() == ' ')) d.pop_back();
        if (const size_t nl = d.rfind('\n'); nl != std::string::npos) d = d.substr(nl + 1);
        if (!d.empty() && d.size() < 300 && d.find(".c(") == std::string::npos) text += " (" + d + ")";
        gst_message_unref(msg);
        if (error) throw SourceError(text);
        if (warned_.size() < 16 && warned_.insert(text).second) spdlog::warn("{}", text);  // each once
        continue;
      }
      gst_message_unref(msg);  // EOS: appsink's own flag tells
    }
  }

  // Back to the start (SourceOptions::loop): a flushing seek to 0; where that gives no frame (the
  // pipeline cannot seek, or a source such as videotestsrc num-buffers=K stays at its end), a
  // restart from NULL, from then on.
  void restart() {
    if (restarts_without_frame_ > 0) seek_works_ = false;  // the last seek brought no frame
    if (++restarts_without_frame_ > 10)
      throw SourceError("source '" + spec_ + "': ends at once each time it is started again (loop)");
    if (!seek_works_ ||
        !gst_element_seek_simple(pipeline_, GST_FORMAT_TIME,
                                 GstSeekFlags(GST_SEEK_FLAG_FLUSH | GST_SEEK_FLAG_KEY_UNIT), 0)) {
      seek_works_ = false;
      gst_element_set_state(pipeline_, GST_STATE_NULL);  // (READY keeps some sources at their end)
      if (gst_element_set_state(pipeline_, GST_STATE_PLAYING) == GST_STATE_CHANGE_FAILURE)
        start_failed_ = true;
    }
    last_frame_ = std::chrono::steady_clock::now();
  }

  // The sample as a new BGR image; the first sample (and any change of caps) is checked against the
  // rig camera's size.
  cv::Mat to_mat(GstSample* sample) {
    GstCaps* caps = gst_sample_get_caps(sample);
    GstBuffer* buffer = gst_sample_get_buffer(sample);
    if (!caps || !buffer) throw SourceError("source '" + spec_ + "': a sample without caps or data");
    if (!info_ok_ || !gst_caps_is_equal(caps, caps_seen_)) {
      GstVideoInfo info;
      if (!gst_video_info_from_caps(&info, caps) || GST_VIDEO_INFO_FORMAT(&info) != GST_VIDEO_FORMAT_BGR)
        throw SourceError("source '" + spec_ + "': the pipeline delivers frames that are not raw video");
      if (info.width != size_.width || info.height != size_.height)
        throw SourceError(fmt::format(
            "source '{}': the pipeline delivers {}x{} frames, but rig camera {} is {}x{} (end the pipeline "
            "in video/x-raw,width={},height={}, e.g. after videoscale)",
            spec_, info.width, info.height, cam_id_, size_.width, size_.height, size_.width, size_.height));
      info_ = info;
      info_ok_ = true;
      if (caps_seen_) gst_caps_unref(caps_seen_);
      caps_seen_ = gst_caps_ref(caps);
      fps_ = info.fps_n > 0 && info.fps_d > 0 ? double(info.fps_n) / info.fps_d : 0.0;
    }
    restarts_without_frame_ = 0;
    GstVideoFrame vf;
    if (!gst_video_frame_map(&vf, &info_, buffer, GST_MAP_READ))
      throw SourceError("source '" + spec_ + "': cannot map a frame");
    const cv::Mat view(GST_VIDEO_FRAME_HEIGHT(&vf), GST_VIDEO_FRAME_WIDTH(&vf), CV_8UC3,
                       GST_VIDEO_FRAME_PLANE_DATA(&vf, 0), size_t(GST_VIDEO_FRAME_PLANE_STRIDE(&vf, 0)));
    cv::Mat out = view.clone();  // a new buffer: the engine keeps it (sources.h)
    gst_video_frame_unmap(&vf);
    return out;
  }

  // Stops the pipeline (state NULL) and drops it; a pipeline that does not stop within kStopWait
  // (an element stuck in a blocking call) is left to stop in a background thread.
  void stop_pipeline() {
    if (caps_seen_) gst_caps_unref(caps_seen_);
    caps_seen_ = nullptr;
    if (!pipeline_) return;
    struct Done {
      std::mutex m;
      std::condition_variable cv;
      bool done = false;
    };
    auto done = std::make_shared<Done>();
    GstElement* p = pipeline_;
    pipeline_ = nullptr;
    auto stop = [p, done] {
      gst_element_set_state(p, GST_STATE_NULL);
      gst_object_unref(p);
      std::lock_guard<std::mutex> lock(done->m);
      done->done = true;
      done->cv.notify_all();
    };
    try {
      std::thread(stop).detach();
    } catch (const std::system_error&) {
      stop();  // no thread to spare: stop it here
      return;
    }
    std::unique_lock<std::mutex> lock(done->m);
    if (!done->cv.wait_for(lock, kStopWait, [&] { return done->done; }))
      spdlog::warn("source '{}': the pipeline did not stop within {} s; leaving it to stop in the background",
                   spec_, std::chrono::duration_cast<std::chrono::seconds>(kStopWait).count());
  }

  std::string spec_;
  int cam_id_;
  cv::Size size_;
  SourceOptions opt_;
  GstElement* pipeline_ = nullptr;
  GstElement* appsink_ = nullptr;
  GstBus* bus_ = nullptr;
  GstCaps* caps_seen_ = nullptr;
  GstVideoInfo info_{};
  bool info_ok_ = false;
  bool start_failed_ = false;
  bool seek_works_ = true;
  std::set<std::string> warned_;
  int restarts_without_frame_ = 0;
  std::atomic<double> fps_{0.0};
  std::chrono::steady_clock::time_point last_frame_;
};

}  // namespace
#endif

std::unique_ptr<CameraSource> open_gst_source(const std::string& pipeline, const RigCamera& cam,
                                              const SourceOptions& opt) {
  try {
    init_gstreamer();
  } catch (const std::runtime_error& e) {
    throw SourceError("source 'gst:" + pipeline + "': " + e.what());
  }
#if OMMA_HAVE_GSTREAMER
  if (std::string why; !opt.IsValid(&why)) throw SourceError("source options: " + why);
  if (pipeline.find_first_not_of(" \t\r\n") == std::string::npos)
    throw SourceError("source 'gst:': empty pipeline (expected gst:PIPELINE, e.g. gst:videotestsrc)");
  if (cam.in.width <= 0 || cam.in.height <= 0)
    throw SourceError(fmt::format("source '{}': rig camera {} has no size", short_spec(pipeline), cam.id));
  return std::make_unique<GstSource>(pipeline, cam, opt);
#else
  (void)cam;
  (void)opt;
  throw SourceError("source 'gst:" + pipeline + "': built without GStreamer");
#endif
}

}  // namespace omma::live
