// The ommastitch element and the omma plugin (ommastitch.h).
#include "ommastitch.h"

#include <algorithm>
#include <atomic>
#include <cerrno>  // program_invocation_short_name (glibc)
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <gst/video/video.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <spdlog/sinks/base_sink.h>
#include <spdlog/spdlog.h>

#include "omma/core/grid.h"
#include "omma/core/rig.h"
#include "omma/design/prototype.h"
#include "omma/live/engine.h"
#include "omma/live/sinks.h"
#include "omma/live/sources.h"
#include "omma/pano/method.h"

GST_DEBUG_CATEGORY_STATIC(omma_stitch_debug);
#define GST_CAT_DEFAULT omma_stitch_debug

namespace {

using omma::live::Clock;

bool supported_sink_format(GstVideoFormat f) {
  switch (f) {
    case GST_VIDEO_FORMAT_BGR:
    case GST_VIDEO_FORMAT_RGB:
    case GST_VIDEO_FORMAT_BGRx:
    case GST_VIDEO_FORMAT_BGRA:
    case GST_VIDEO_FORMAT_RGBx:
    case GST_VIDEO_FORMAT_RGBA:
    case GST_VIDEO_FORMAT_GRAY8:
    case GST_VIDEO_FORMAT_I420:
    case GST_VIDEO_FORMAT_YV12:
    case GST_VIDEO_FORMAT_NV12:
    case GST_VIDEO_FORMAT_NV21:
    case GST_VIDEO_FORMAT_YUY2:
    case GST_VIDEO_FORMAT_UYVY:
      return true;
    default:
      return false;
  }
}

// A tightly packed BGR image of w x h (the layout of a continuous CV_8UC3 cv::Mat), at the frame rate of
// `like` (GstVideoConverter converts between equal rates only).
GstVideoInfo packed_bgr_info(int w, int h, const GstVideoInfo* like = nullptr) {
  GstVideoInfo info;
  gst_video_info_set_format(&info, GST_VIDEO_FORMAT_BGR, guint(w), guint(h));
  if (like) {
    info.fps_n = like->fps_n;
    info.fps_d = like->fps_d;
  }
  info.stride[0] = w * 3;
  info.size = gsize(w) * 3 * gsize(h);
  return info;
}

// "1", "0.5", "2.25": seconds as a person writes them.
std::string seconds_text(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", s);
  return buf;
}

double ms_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// omma's log (spdlog) into the GStreamer debug log.
class GstLogSink : public spdlog::sinks::base_sink<std::mutex> {
 protected:
  void sink_it_(const spdlog::details::log_msg& msg) override {
    GstDebugLevel level = GST_LEVEL_INFO;
    switch (msg.level) {
      case spdlog::level::trace:
        level = GST_LEVEL_TRACE;
        break;
      case spdlog::level::debug:
        level = GST_LEVEL_DEBUG;
        break;
      case spdlog::level::warn:
        level = GST_LEVEL_WARNING;
        break;
      case spdlog::level::err:
      case spdlog::level::critical:
        level = GST_LEVEL_ERROR;
        break;
      default:
        break;
    }
    GST_CAT_LEVEL_LOG(omma_stitch_debug, level, nullptr, "%.*s", int(msg.payload.size()), msg.payload.data());
  }
  void flush_() override {}
};

}  // namespace

struct OmmaPad;
struct OmmaImpl;

// The element instance.
struct _GstOmmaStitch {
  GstElement parent;
  GstPad* src;
  OmmaImpl* impl;
};

// Per sink pad: the newest converted frame and the pad's stream state.
struct OmmaPad {
  GstPad* pad = nullptr;
  int index = 0;  // rig camera index (from the name sink_I)
  std::mutex m;
  std::condition_variable cv;
  bool have_info = false;
  GstVideoInfo info{};
  GstVideoConverter* conv = nullptr;  // info -> packed BGR
  GstSegment segment{};
  cv::Mat latest;
  bool fresh = false;
  Clock::time_point published;
  bool eos = false;
  bool flushing = false;
  bool released = false;  // released while the engine runs: its camera ends
  GstClockID clock_id = nullptr;
  ~OmmaPad() {
    if (conv) gst_video_converter_free(conv);
  }
};

struct OmmaSettings {
  std::string rig, method = "linear", projection = "vr180", size = "1080x1080", cache_dir;
  bool depth = false, photometric = true, sync = true;
  double fps = 30, first_frame_timeout = 5, stall_timeout = 5;
  int threads = 0;
};

struct OmmaImpl {
  std::mutex settings_mutex;
  OmmaSettings settings;
  // Pads (element lock for the list; the pads' own mutex for their state).
  std::map<GstPad*, std::unique_ptr<OmmaPad>> pads;
  unsigned next_pad = 0;
  // Configured at READY->PAUSED.
  omma::Rig rig;
  OmmaSettings run;  // the settings of this run
  omma::live::EngineOptions eo;
  std::vector<OmmaPad*> by_camera;
  // READY->PAUSED done (element lock): no pads are added from then on, and pads released meanwhile
  // are kept in `released` (the engine may still read them) until PAUSED->READY.
  bool configured = false;
  std::vector<std::unique_ptr<OmmaPad>> released;
  // Running.
  std::thread engine;
  std::atomic<bool> stop{false};
  std::atomic<bool> ending{false};  // the render loop is ending on its own (src flow error): reads end
  std::atomic<bool> playing{false};
  std::atomic<bool> error_posted{false};
  // Src pad (render-loop thread only).
  bool sent_start = false;
  GstVideoInfo out_info{};
  GstVideoConverter* out_conv = nullptr;
  long out_frames = 0;
  Clock::time_point oldest_used;
  double push_ms_sum = 0;
  long push_count = 0;
  std::vector<char> dropped_warned;             // per entry of the engine's dropped_cameras
  std::vector<Clock::time_point> dropped_seen;  // when on_progress first saw that entry
  std::mutex stats_mutex;
  std::string stats_json = "{}";
  ~OmmaImpl() {
    if (out_conv) gst_video_converter_free(out_conv);
  }
};

enum {
  PROP_0,
  PROP_RIG,
  PROP_METHOD,
  PROP_PROJECTION,
  PROP_SIZE,
  PROP_DEPTH,
  PROP_PHOTOMETRIC,
  PROP_FPS,
  PROP_SYNC,
  PROP_FIRST_FRAME_TIMEOUT,
  PROP_STALL_TIMEOUT,
  PROP_THREADS,
  PROP_CACHE_DIR,
  PROP_STATS,
};

G_DEFINE_TYPE(GstOmmaStitch, gst_omma_stitch, GST_TYPE_ELEMENT)

namespace {

GstStaticPadTemplate g_sink_template = GST_STATIC_PAD_TEMPLATE(
    "sink_%u", GST_PAD_SINK, GST_PAD_REQUEST,
    GST_STATIC_CAPS(GST_VIDEO_CAPS_MAKE("{ BGR, RGB, BGRx, BGRA, RGBx, RGBA, GRAY8, I420, "
                                        "YV12, NV12, NV21, YUY2, UYVY }")));
GstStaticPadTemplate g_src_template = GST_STATIC_PAD_TEMPLATE(
    "src", GST_PAD_SRC, GST_PAD_ALWAYS, GST_STATIC_CAPS(GST_VIDEO_CAPS_MAKE("{ BGR, RGB, I420 }")));

void post_error(GstOmmaStitch* self, const std::string& text) {
  self->impl->error_posted = true;
  GST_ELEMENT_ERROR(self, STREAM, FAILED, ("%s", text.c_str()), (nullptr));
}

// The src caps of this run: the panorama's size and rate, formats BGR/RGB/I420.
GstCaps* run_src_caps(OmmaImpl* impl) {
  const omma::PanoGrid& g = impl->eo.map.grid;
  gint n = 0, d = 1;
  if (impl->run.fps > 0) gst_util_double_to_fraction(impl->run.fps, &n, &d);
  GstCaps* caps = gst_static_caps_get(&g_src_template.static_caps);
  caps = gst_caps_make_writable(caps);
  gst_caps_set_simple(caps, "width", G_TYPE_INT, g.width, "height", G_TYPE_INT, g.height, "framerate",
                      GST_TYPE_FRACTION, n, d, nullptr);
  return caps;
}

// ---- The engine's view of a sink pad (CameraSource) and of the src pad (Sink). ----

class PadSource : public omma::live::CameraSource {
 public:
  PadSource(GstOmmaStitch* self, OmmaPad* p) : self_(self), p_(p) {}
  // The pad's newest buffer; false at its EOS or when the engine stops. Throws (the engine drops the
  // camera with the text as its reason) when the pad stalls, is released, or has no first frame by
  // the first-frame timeout (the engine drops such a camera itself; ending the read as well lets the
  // engine finish without waiting for the pad).
  bool read(cv::Mat& frame) override {
    OmmaImpl* impl = self_->impl;
    std::unique_lock<std::mutex> lock(p_->m);
    auto since = Clock::now();
    if (first_call_ == Clock::time_point{}) first_call_ = since;
    while (true) {
      if (impl->stop || impl->ending) return false;
      if (p_->fresh) {
        frame = p_->latest;
        p_->fresh = false;
        last_ = p_->published;
        delivered_ = true;
        return true;
      }
      if (p_->released) throw omma::live::SourceError("its sink pad was released");
      if (p_->eos) return false;
      const auto now = Clock::now();
      if (!impl->playing) since = now;  // time in PAUSED does not count
      if (std::chrono::duration<double>(now - since).count() > impl->run.stall_timeout)
        throw omma::live::SourceError("stalled: no buffer for " + seconds_text(impl->run.stall_timeout) +
                                      " s");
      if (!delivered_ &&
          std::chrono::duration<double>(now - first_call_).count() > impl->run.first_frame_timeout + 0.2)
        throw omma::live::SourceError("no frame within " + seconds_text(impl->run.first_frame_timeout) +
                                      " s");
      p_->cv.wait_for(lock, std::chrono::milliseconds(50));
    }
  }
  double fps() const override { return 0; }  // read() waits for the pad itself
  Clock::time_point last_capture() const override { return last_; }
  std::string describe() const override { return "ommastitch pad sink_" + std::to_string(p_->index); }

 private:
  GstOmmaStitch* self_;
  OmmaPad* p_;
  Clock::time_point last_, first_call_;
  bool delivered_ = false;
};

class SrcSink : public omma::live::Sink {
 public:
  explicit SrcSink(GstOmmaStitch* self) : self_(self) {}
  void write(const cv::Mat& pano, const omma::render::FrameStore&) override {
    OmmaImpl* impl = self_->impl;
    // Nothing is pushed while PAUSED (a live source): a panorama pushed then would carry a running
    // time beyond the one the pipeline resumes at.
    if (impl->stop || !impl->playing) return;
    GstPad* src = self_->src;
    if (!impl->sent_start) {
      // A fresh stream id (gst_pad_create_stream_id takes at most one sink pad).
      gchar* id = g_strdup_printf("%08x%08x%08x%08x/omma-panorama", g_random_int(), g_random_int(),
                                  g_random_int(), g_random_int());
      gst_pad_push_event(src, gst_event_new_stream_start(id));
      g_free(id);
    }
    if (!impl->sent_start || gst_pad_check_reconfigure(src)) negotiate(pano);
    if (!impl->sent_start) {
      GstSegment seg;
      gst_segment_init(&seg, GST_FORMAT_TIME);
      gst_pad_push_event(src, gst_event_new_segment(&seg));
      impl->sent_start = true;
    }
    GstBuffer* out = gst_buffer_new_allocate(nullptr, impl->out_info.size, nullptr);
    {
      const cv::Mat bgr = pano.isContinuous() ? pano : pano.clone();
      GstVideoInfo in_info = packed_bgr_info(bgr.cols, bgr.rows, &impl->out_info);
      GstBuffer* in = gst_buffer_new_wrapped_full(GstMemoryFlags(GST_MEMORY_FLAG_READONLY), bgr.data,
                                                  in_info.size, 0, in_info.size, nullptr, nullptr);
      GstVideoFrame fin, fout;
      const bool ok = gst_video_frame_map(&fin, &in_info, in, GST_MAP_READ);
      if (ok && gst_video_frame_map(&fout, &impl->out_info, out, GST_MAP_WRITE)) {
        gst_video_converter_frame(impl->out_conv, &fin, &fout);
        gst_video_frame_unmap(&fout);
      }
      if (ok) gst_video_frame_unmap(&fin);
      gst_buffer_unref(in);
    }
    // PTS: the running time now (or the frame number / fps without a clock).
    GstClockTime pts = GST_CLOCK_TIME_NONE;
    if (GstClock* clock = gst_element_get_clock(GST_ELEMENT(self_))) {
      const GstClockTime now = gst_clock_get_time(clock),
                         base = gst_element_get_base_time(GST_ELEMENT(self_));
      pts = now > base ? now - base : 0;
      gst_object_unref(clock);
    } else if (impl->run.fps > 0) {
      pts = GstClockTime(double(impl->out_frames) * GST_SECOND / impl->run.fps);
    }
    GST_BUFFER_PTS(out) = pts;
    GST_BUFFER_DURATION(out) =
        impl->run.fps > 0 ? GstClockTime(double(GST_SECOND) / impl->run.fps) : GST_CLOCK_TIME_NONE;
    GST_BUFFER_OFFSET(out) = guint64(impl->out_frames);
    ++impl->out_frames;
    const GstFlowReturn ret = gst_pad_push(src, out);
    if (impl->oldest_used != Clock::time_point{}) {
      impl->push_ms_sum += ms_between(impl->oldest_used, Clock::now());
      ++impl->push_count;
    }
    if (ret == GST_FLOW_OK || ret == GST_FLOW_FLUSHING) return;
    if (ret == GST_FLOW_EOS) {  // downstream wants no more
      impl->stop = true;
      return;
    }
    if (!impl->stop) {
      impl->error_posted = true;
      GST_ELEMENT_FLOW_ERROR(self_, ret);
    }
    impl->ending = true;
    throw omma::live::SinkError(std::string("ommastitch: pushing the panorama: ") + gst_flow_get_name(ret));
  }
  std::string describe() const override { return "ommastitch src pad"; }

 private:
  void negotiate(const cv::Mat& pano) {
    OmmaImpl* impl = self_->impl;
    GstCaps* ours = run_src_caps(impl);
    GstCaps* peer = gst_pad_peer_query_caps(self_->src, ours);
    gst_caps_unref(ours);
    if (gst_caps_is_empty(peer)) {
      gst_caps_unref(peer);
      impl->error_posted = true;
      impl->ending = true;
      GST_ELEMENT_ERROR(
          self_, CORE, NEGOTIATION,
          ("ommastitch: downstream takes none of BGR, RGB, I420 at %dx%d", pano.cols, pano.rows), (nullptr));
      throw omma::live::SinkError("ommastitch: not-negotiated");
    }
    peer = gst_caps_fixate(peer);
    GstVideoInfo info;
    if (!gst_video_info_from_caps(&info, peer)) {
      gst_caps_unref(peer);
      impl->ending = true;
      throw omma::live::SinkError("ommastitch: downstream caps are not raw video");
    }
    if (!impl->out_conv || !gst_video_info_is_equal(&info, &impl->out_info)) {
      if (impl->out_conv) gst_video_converter_free(impl->out_conv);
      GstVideoInfo in_info = packed_bgr_info(pano.cols, pano.rows, &info);
      impl->out_conv = gst_video_converter_new(&in_info, &info, nullptr);
      impl->out_info = info;
    }
    GST_INFO_OBJECT(self_, "src caps %" GST_PTR_FORMAT, peer);
    gst_pad_push_event(self_->src, gst_event_new_caps(peer));
    gst_caps_unref(peer);
  }
  GstOmmaStitch* self_;
};

// ---- Statistics and warnings (from the engine's render loop). ----

constexpr std::chrono::milliseconds kEndedGrace{1000};

void on_progress(GstOmmaStitch* self, const nlohmann::json& j) {
  OmmaImpl* impl = self->impl;
  const nlohmann::json& w = j.at("window");
  const double push_ms = impl->push_count > 0 ? impl->push_ms_sum / double(impl->push_count) : 0;
  impl->push_ms_sum = 0;
  impl->push_count = 0;
  const int live = j.at("cameras_live").get<int>();
  const nlohmann::json& dropped = j.at("dropped_cameras");
  nlohmann::json s = {{"fps", w.at("fps").get<double>()},
                      {"render-ms", w.at("render_ms").get<double>()},
                      {"latency-ms", w.at("latency_ms").get<double>()},
                      {"push-latency-ms", push_ms},
                      {"cameras-live", live},
                      {"dropped-cameras", int(dropped.size())},
                      {"frames", j.at("frames").get<long>()}};
  {
    std::lock_guard<std::mutex> lock(impl->stats_mutex);
    impl->stats_json = s.dump();
  }
  GstStructure* st = gst_structure_new(
      "omma-stats", "fps", G_TYPE_DOUBLE, s["fps"].get<double>(), "render-ms", G_TYPE_DOUBLE,
      s["render-ms"].get<double>(), "latency-ms", G_TYPE_DOUBLE, s["latency-ms"].get<double>(),
      "push-latency-ms", G_TYPE_DOUBLE, push_ms, "cameras-live", G_TYPE_INT, live, "dropped-cameras",
      G_TYPE_INT, int(dropped.size()), "frames", G_TYPE_INT64, gint64(s["frames"].get<long>()), nullptr);
  gst_element_post_message(GST_ELEMENT(self), gst_message_new_element(GST_OBJECT(self), st));
  // A drop is warned at once, except a camera whose stream simply ended: that waits kEndedGrace with
  // other cameras still live, because the end of a whole stream reaches the pads one by one (on a
  // loaded machine across progress ticks) and is no camera lost; the last pads' end stops the engine.
  const Clock::time_point now = Clock::now();
  impl->dropped_seen.resize(dropped.size(), now);
  impl->dropped_warned.resize(dropped.size(), 0);
  for (size_t i = 0; i < dropped.size(); ++i) {
    const nlohmann::json& d = dropped[i];
    if (impl->dropped_warned[i]) continue;
    if (d.at("reason") == "ended" && (live == 0 || now - impl->dropped_seen[i] < kEndedGrace)) continue;
    impl->dropped_warned[i] = 1;
    const std::string text = "ommastitch: camera " + std::to_string(d.at("id").get<int>()) + " (sink_" +
                             std::to_string(d.at("index").get<int>()) +
                             ") dropped: " + d.at("reason").get<std::string>() +
                             "; the map is recompiled without it and the panorama continues";
    GST_ELEMENT_WARNING(self, STREAM, FAILED, ("%s", text.c_str()), (nullptr));
  }
}

void engine_main(GstOmmaStitch* self) {
  OmmaImpl* impl = self->impl;
  try {
    std::vector<std::unique_ptr<omma::live::CameraSource>> sources;
    for (size_t c = 0; c < impl->rig.cameras.size(); ++c)
      sources.push_back(std::make_unique<PadSource>(self, impl->by_camera[c]));
    std::vector<std::unique_ptr<omma::live::Sink>> sinks;
    sinks.push_back(std::make_unique<SrcSink>(self));
    omma::live::EngineOptions eo = impl->eo;
    eo.stop = &impl->stop;
    eo.on_progress = [self](const nlohmann::json& j) { on_progress(self, j); };
    eo.on_panorama = [impl](const cv::Mat&, const omma::live::PanoramaInfo& info) {
      Clock::time_point oldest{};
      for (const auto& t : info.captured)
        if (t != Clock::time_point{} && (oldest == Clock::time_point{} || t < oldest)) oldest = t;
      impl->oldest_used = oldest;
    };
    const omma::live::EngineSummary st = omma::live::run_engine(impl->rig, std::move(sources), sinks, eo);
    GST_INFO_OBJECT(self, "engine ended: %ld panoramas", st.frames);
    if (!impl->stop) {
      // Cameras that failed (not those that simply ended) and were not reported yet by on_progress.
      for (size_t i = 0; i < st.dropped_cameras.size(); ++i)
        if (const auto& d = st.dropped_cameras[i];
            d.reason != "ended" && (i >= impl->dropped_warned.size() || !impl->dropped_warned[i])) {
          const std::string text = "ommastitch: camera " + std::to_string(d.id) + " (sink_" +
                                   std::to_string(d.index) + ") dropped: " + d.reason;
          GST_ELEMENT_WARNING(self, STREAM, FAILED, ("%s", text.c_str()), (nullptr));
        }
      GST_INFO_OBJECT(self, "every sink pad has ended: EOS");
      gst_pad_push_event(self->src, gst_event_new_eos());
    }
  } catch (const std::exception& e) {
    if (!impl->stop && !impl->error_posted) post_error(self, std::string("ommastitch: ") + e.what());
    GST_INFO_OBJECT(self, "engine stopped: %s", e.what());
  }
}

// ---- Sink pads. ----

OmmaPad* pad_state(GstPad* pad) { return static_cast<OmmaPad*>(gst_pad_get_element_private(pad)); }

// Wakes every waiter of a pad (frame readers, clock waits).
void wake_pad(OmmaPad* p, bool flushing) {
  std::lock_guard<std::mutex> lock(p->m);
  if (flushing) p->flushing = true;
  if (p->clock_id) gst_clock_id_unschedule(p->clock_id);
  p->cv.notify_all();
}

// The rig camera a pad stands for ("" before the rig is loaded).
std::string camera_name(GstOmmaStitch* self, OmmaPad* p) {
  const omma::Rig& rig = self->impl->rig;
  if (p->index < int(rig.cameras.size())) return "camera " + std::to_string(rig.cameras[p->index].id);
  return "no camera";
}

gboolean sink_setcaps(GstOmmaStitch* self, GstPad* pad, GstCaps* caps) {
  OmmaPad* p = pad_state(pad);
  GstVideoInfo info;
  if (!gst_video_info_from_caps(&info, caps) || !supported_sink_format(GST_VIDEO_INFO_FORMAT(&info))) {
    gchar* s = gst_caps_to_string(caps);
    GST_ELEMENT_ERROR(self, CORE, NEGOTIATION,
                      ("ommastitch: %s (%s): caps %s cannot be converted to BGR (not-negotiated)",
                       GST_PAD_NAME(pad), camera_name(self, p).c_str(), s),
                      (nullptr));
    g_free(s);
    return FALSE;
  }
  const omma::Rig& rig = self->impl->rig;
  if (p->index < int(rig.cameras.size())) {
    const auto& in = rig.cameras[p->index].in;
    if (GST_VIDEO_INFO_WIDTH(&info) != in.width || GST_VIDEO_INFO_HEIGHT(&info) != in.height) {
      GST_ELEMENT_ERROR(self, CORE, NEGOTIATION,
                        ("ommastitch: %s (%s) gets %dx%d frames, the rig's camera is %dx%d",
                         GST_PAD_NAME(pad), camera_name(self, p).c_str(), GST_VIDEO_INFO_WIDTH(&info),
                         GST_VIDEO_INFO_HEIGHT(&info), in.width, in.height),
                        (nullptr));
      return FALSE;
    }
  }
  GstVideoInfo bgr = packed_bgr_info(GST_VIDEO_INFO_WIDTH(&info), GST_VIDEO_INFO_HEIGHT(&info), &info);
  GstVideoConverter* conv = gst_video_converter_new(&info, &bgr, nullptr);
  if (!conv) return FALSE;
  std::lock_guard<std::mutex> lock(p->m);
  if (p->conv) gst_video_converter_free(p->conv);
  p->conv = conv;
  p->info = info;
  p->have_info = true;
  return TRUE;
}

gboolean sink_event(GstPad* pad, GstObject* parent, GstEvent* event) {
  GstOmmaStitch* self = GST_OMMA_STITCH(parent);
  OmmaPad* p = pad_state(pad);
  gboolean ret = TRUE;
  switch (GST_EVENT_TYPE(event)) {
    case GST_EVENT_CAPS: {
      GstCaps* caps;
      gst_event_parse_caps(event, &caps);
      ret = sink_setcaps(self, pad, caps);
      break;
    }
    case GST_EVENT_SEGMENT: {
      const GstSegment* seg;
      gst_event_parse_segment(event, &seg);
      std::lock_guard<std::mutex> lock(p->m);
      if (seg->format == GST_FORMAT_TIME)
        gst_segment_copy_into(seg, &p->segment);
      else
        gst_segment_init(&p->segment, GST_FORMAT_TIME);
      break;
    }
    case GST_EVENT_EOS: {
      GST_DEBUG_OBJECT(pad, "EOS");
      std::lock_guard<std::mutex> lock(p->m);
      p->eos = true;
      p->cv.notify_all();
      break;
    }
    case GST_EVENT_FLUSH_START:
      wake_pad(p, true);
      break;
    case GST_EVENT_FLUSH_STOP: {
      std::lock_guard<std::mutex> lock(p->m);
      p->flushing = false;
      p->eos = false;
      p->fresh = false;
      gst_segment_init(&p->segment, GST_FORMAT_TIME);
      break;
    }
    default:
      break;  // stream-start, tags, ...: the panorama has its own
  }
  gst_event_unref(event);
  return ret;
}

gboolean sink_query(GstPad* pad, GstObject* parent, GstQuery* query) {
  if (GST_QUERY_TYPE(query) == GST_QUERY_CAPS) {
    GstCaps* filter;
    gst_query_parse_caps(query, &filter);
    GstCaps* caps = gst_pad_get_pad_template_caps(pad);
    if (filter) {
      GstCaps* c = gst_caps_intersect_full(filter, caps, GST_CAPS_INTERSECT_FIRST);
      gst_caps_unref(caps);
      caps = c;
    }
    gst_query_set_caps_result(query, caps);
    gst_caps_unref(caps);
    return TRUE;
  }
  return gst_pad_query_default(pad, parent, query);
}

// Waits until the buffer's running time on the pipeline clock (sync); false if flushing or stopped.
bool wait_for_running_time(GstOmmaStitch* self, OmmaPad* p, GstClockTime rt) {
  OmmaImpl* impl = self->impl;
  while (true) {
    {
      std::unique_lock<std::mutex> lock(p->m);
      p->cv.wait(lock, [&] { return impl->playing || p->flushing || impl->stop; });
      if (p->flushing || impl->stop) return false;
    }
    GstClock* clock = gst_element_get_clock(GST_ELEMENT(self));
    if (!clock) return true;
    const GstClockTime base = gst_element_get_base_time(GST_ELEMENT(self));
    GstClockID id = gst_clock_new_single_shot_id(clock, base + rt);
    gst_object_unref(clock);
    {
      std::lock_guard<std::mutex> lock(p->m);
      if (p->flushing || impl->stop || !impl->playing) {
        gst_clock_id_unref(id);
        continue;
      }
      p->clock_id = id;
    }
    const GstClockReturn r = gst_clock_id_wait(id, nullptr);
    {
      std::lock_guard<std::mutex> lock(p->m);
      p->clock_id = nullptr;
    }
    gst_clock_id_unref(id);
    if (r != GST_CLOCK_UNSCHEDULED) return true;
    // Unscheduled: flushing, stopping or paused (then wait again for PLAYING).
  }
}

GstFlowReturn sink_chain(GstPad* pad, GstObject* parent, GstBuffer* buf) {
  GstOmmaStitch* self = GST_OMMA_STITCH(parent);
  OmmaImpl* impl = self->impl;
  OmmaPad* p = pad_state(pad);
  GstVideoInfo info;
  GstClockTime rt = GST_CLOCK_TIME_NONE;
  {
    std::lock_guard<std::mutex> lock(p->m);
    if (p->flushing) {
      gst_buffer_unref(buf);
      return GST_FLOW_FLUSHING;
    }
    if (!p->have_info) {
      gst_buffer_unref(buf);
      return GST_FLOW_NOT_NEGOTIATED;
    }
    info = p->info;
    if (GST_BUFFER_PTS_IS_VALID(buf))
      rt = gst_segment_to_running_time(&p->segment, GST_FORMAT_TIME, GST_BUFFER_PTS(buf));
  }
  // Converted to BGR (the engine keeps a reference to the frame: a new image per buffer).
  cv::Mat bgr(GST_VIDEO_INFO_HEIGHT(&info), GST_VIDEO_INFO_WIDTH(&info), CV_8UC3);
  GstVideoInfo out_info = packed_bgr_info(bgr.cols, bgr.rows, &info);
  GstBuffer* out = gst_buffer_new_wrapped_full(GstMemoryFlags(0), bgr.data, out_info.size, 0, out_info.size,
                                               nullptr, nullptr);
  GstVideoFrame fin, fout;
  bool ok = false;
  if (gst_video_frame_map(&fin, &info, buf, GST_MAP_READ)) {
    if (gst_video_frame_map(&fout, &out_info, out, GST_MAP_WRITE)) {
      gst_video_converter_frame(p->conv, &fin, &fout);
      gst_video_frame_unmap(&fout);
      ok = true;
    }
    gst_video_frame_unmap(&fin);
  }
  gst_buffer_unref(out);
  gst_buffer_unref(buf);
  if (!ok) {
    GST_ELEMENT_ERROR(self, STREAM, DECODE, ("ommastitch: %s: cannot map a buffer", GST_PAD_NAME(pad)),
                      (nullptr));
    return GST_FLOW_ERROR;
  }
  bool sync;
  {
    std::lock_guard<std::mutex> lock(impl->settings_mutex);
    sync = impl->run.sync;
  }
  if (sync && GST_CLOCK_TIME_IS_VALID(rt) && !wait_for_running_time(self, p, rt)) return GST_FLOW_FLUSHING;
  std::lock_guard<std::mutex> lock(p->m);
  if (p->flushing) return GST_FLOW_FLUSHING;
  p->latest = bgr;
  p->fresh = true;
  p->published = Clock::now();
  p->cv.notify_all();
  return GST_FLOW_OK;
}

// ---- Src pad. ----

gboolean src_query(GstPad* pad, GstObject* parent, GstQuery* query) {
  GstOmmaStitch* self = GST_OMMA_STITCH(parent);
  OmmaImpl* impl = self->impl;
  switch (GST_QUERY_TYPE(query)) {
    case GST_QUERY_CAPS: {
      GstCaps* filter;
      gst_query_parse_caps(query, &filter);
      GstCaps* caps = GST_STATE(self) >= GST_STATE_PAUSED && !impl->rig.cameras.empty()
                          ? run_src_caps(impl)
                          : gst_pad_get_pad_template_caps(pad);
      if (filter) {
        GstCaps* c = gst_caps_intersect_full(filter, caps, GST_CAPS_INTERSECT_FIRST);
        gst_caps_unref(caps);
        caps = c;
      }
      gst_query_set_caps_result(query, caps);
      gst_caps_unref(caps);
      return TRUE;
    }
    case GST_QUERY_LATENCY: {
      const GstClockTime min = impl->run.fps > 0 ? GstClockTime(double(GST_SECOND) / impl->run.fps) : 0;
      gst_query_set_latency(query, TRUE, min, GST_CLOCK_TIME_NONE);
      return TRUE;
    }
    default:
      return gst_pad_query_default(pad, parent, query);
  }
}

gboolean src_event(GstPad* pad, GstObject* parent, GstEvent* event) {
  // Reconfigure is noted by the pad itself (gst_pad_check_reconfigure); seeks and QoS are not taken.
  const bool ok = GST_EVENT_TYPE(event) == GST_EVENT_RECONFIGURE;
  gst_event_unref(event);
  return ok;
}

// ---- Element. ----

GstPad* request_new_pad(GstElement* element, GstPadTemplate* templ, const gchar* name, const GstCaps*) {
  GstOmmaStitch* self = GST_OMMA_STITCH(element);
  OmmaImpl* impl = self->impl;
  GST_OBJECT_LOCK(self);
  unsigned index = impl->next_pad;
  GST_OBJECT_UNLOCK(self);
  if (name && std::sscanf(name, "sink_%u", &index) != 1) {
    GST_WARNING_OBJECT(self, "no sink pad named %s: sink pads are sink_0, sink_1, ...", name);
    return nullptr;
  }
  const std::string pad_name = "sink_" + std::to_string(index);
  GstPad* pad = gst_pad_new_from_template(templ, pad_name.c_str());
  auto st = std::make_unique<OmmaPad>();
  st->pad = pad;
  st->index = int(index);
  gst_segment_init(&st->segment, GST_FORMAT_TIME);
  gst_pad_set_element_private(pad, st.get());
  gst_pad_set_chain_function(pad, sink_chain);
  gst_pad_set_event_function(pad, sink_event);
  gst_pad_set_query_function(pad, sink_query);
  // The check and the insertion under one lock: READY->PAUSED (configure) takes the pad list under
  // it too, so a pad is either part of the run or refused.
  std::string refused;
  GST_OBJECT_LOCK(self);
  if (impl->configured)
    refused = "ommastitch: " + pad_name +
              " refused: sink pads can be requested in NULL or READY only (the rig's pads are fixed "
              "while the element runs)";
  for (const auto& [other, ost] : impl->pads)
    if (refused.empty() && ost->index == int(index))
      refused = "ommastitch: pad " + pad_name + " exists already";
  if (refused.empty()) {
    impl->pads[pad] = std::move(st);
    impl->next_pad = std::max(impl->next_pad, index + 1);
  }
  GST_OBJECT_UNLOCK(self);
  if (!refused.empty()) {
    gst_object_unref(gst_object_ref_sink(pad));
    GST_ELEMENT_WARNING(self, CORE, PAD, ("%s", refused.c_str()), (nullptr));
    return nullptr;
  }
  gst_element_add_pad(element, pad);
  return pad;
}

// While the engine may read the pad (PAUSED or PLAYING), its camera ends ("its sink pad was
// released": dropped, a warning) and its state is kept until PAUSED->READY; before, it is freed.
void release_pad(GstElement* element, GstPad* pad) {
  GstOmmaStitch* self = GST_OMMA_STITCH(element);
  OmmaImpl* impl = self->impl;
  OmmaPad* p = pad_state(pad);
  gst_object_ref(pad);
  {
    std::lock_guard<std::mutex> lock(p->m);
    p->released = true;
  }
  // Wakes a chain call waiting for its running time: removing the pad deactivates it, which waits for
  // the chain function to return.
  wake_pad(p, true);
  gst_element_remove_pad(element, pad);
  std::unique_ptr<OmmaPad> gone;
  GST_OBJECT_LOCK(self);
  if (auto it = impl->pads.find(pad); it != impl->pads.end()) {
    gone = std::move(it->second);
    impl->pads.erase(it);
  }
  if (impl->configured && gone) impl->released.push_back(std::move(gone));
  GST_OBJECT_UNLOCK(self);
  gone.reset();
  gst_object_unref(pad);
}

// READY->PAUSED: the rig, the pads and the options; false (error posted) if anything is wrong.
bool configure(GstOmmaStitch* self) {
  OmmaImpl* impl = self->impl;
  {
    std::lock_guard<std::mutex> lock(impl->settings_mutex);
    impl->run = impl->settings;
  }
  const OmmaSettings& s = impl->run;
  try {
    if (s.rig.empty())
      throw std::invalid_argument("no rig: set the property rig (a rig file or built-in name)");
    impl->rig = omma::design::load_rig_or_builtin(s.rig);
  } catch (const std::exception& e) {
    impl->rig = {};
    GST_ELEMENT_ERROR(self, RESOURCE, NOT_FOUND, ("ommastitch: rig '%s': %s", s.rig.c_str(), e.what()),
                      (nullptr));
    return false;
  }
  const size_t n = impl->rig.cameras.size();
  impl->by_camera.assign(n, nullptr);
  GST_OBJECT_LOCK(self);
  const size_t npads = impl->pads.size();
  std::string missing;
  for (auto& [pad, st] : impl->pads)
    if (st->index < int(n)) impl->by_camera[st->index] = st.get();
  impl->configured = true;  // (cleared again if this fails: see change_state)
  GST_OBJECT_UNLOCK(self);
  for (size_t c = 0; c < n && missing.empty(); ++c)
    if (!impl->by_camera[c]) missing = "sink_" + std::to_string(c);
  if (npads != n || !missing.empty()) {
    std::string text =
        "ommastitch: " + std::to_string(npads) + " sink pads for a rig of " + std::to_string(n) + " cameras";
    if (npads == n)
      text += " (pads must be sink_0 .. sink_" + std::to_string(n - 1) + "; " + missing + " is missing)";
    GST_ELEMENT_ERROR(self, CORE, PAD, ("%s", text.c_str()), (nullptr));
    return false;
  }
  try {
    omma::live::EngineOptions eo;
    eo.map.method = omma::pano::parse_method(s.method);
    const omma::Size2 size = omma::parse_size(s.size);
    eo.map.grid = omma::PanoGrid{omma::parse_projection(s.projection), size.width, size.height};
    eo.cache_dir = s.cache_dir;
    eo.fps = s.fps;
    eo.threads = s.threads;
    eo.depth = s.depth;
    eo.photometric = s.photometric;
    eo.first_frame_timeout_s = s.first_frame_timeout;
    eo.max_camera_threads = int(n);  // every pad its own thread: read() blocks on the pad
    if (std::string why; !eo.IsValid(&why)) throw std::invalid_argument(why);
    if (!(s.stall_timeout > 0)) throw std::invalid_argument("stall-timeout must be > 0 s");
    impl->eo = eo;
  } catch (const std::exception& e) {
    GST_ELEMENT_ERROR(self, RESOURCE, SETTINGS, ("ommastitch: %s", e.what()), (nullptr));
    return false;
  }
  for (OmmaPad* p : impl->by_camera) {
    std::lock_guard<std::mutex> lock(p->m);
    p->eos = p->fresh = p->flushing = p->released = false;
    p->latest = cv::Mat();
  }
  impl->stop = false;
  impl->ending = false;
  impl->error_posted = false;
  impl->sent_start = false;
  impl->out_frames = 0;
  impl->push_ms_sum = 0;
  impl->push_count = 0;
  impl->dropped_warned.clear();
  impl->dropped_seen.clear();
  impl->oldest_used = {};
  {
    std::lock_guard<std::mutex> lock(impl->stats_mutex);
    impl->stats_json = "{}";
  }
  return true;
}

void stop_engine(GstOmmaStitch* self) {
  OmmaImpl* impl = self->impl;
  impl->stop = true;
  impl->playing = false;
  GST_OBJECT_LOCK(self);
  for (auto& [pad, st] : impl->pads) wake_pad(st.get(), true);
  GST_OBJECT_UNLOCK(self);
}

// After a run (the engine joined) or a failed READY->PAUSED: pads may be requested again, released
// pads are freed.
void forget_run(GstOmmaStitch* self) {
  OmmaImpl* impl = self->impl;
  std::vector<std::unique_ptr<OmmaPad>> released;
  GST_OBJECT_LOCK(self);
  impl->configured = false;
  released.swap(impl->released);
  impl->by_camera.clear();
  GST_OBJECT_UNLOCK(self);
}

GstStateChangeReturn change_state(GstElement* element, GstStateChange transition) {
  GstOmmaStitch* self = GST_OMMA_STITCH(element);
  OmmaImpl* impl = self->impl;
  switch (transition) {
    case GST_STATE_CHANGE_READY_TO_PAUSED:
      if (!configure(self)) {
        forget_run(self);
        return GST_STATE_CHANGE_FAILURE;
      }
      break;
    case GST_STATE_CHANGE_PAUSED_TO_PLAYING:
      impl->playing = true;
      GST_OBJECT_LOCK(self);
      for (auto& [pad, st] : impl->pads) wake_pad(st.get(), false);
      GST_OBJECT_UNLOCK(self);
      if (!impl->engine.joinable()) impl->engine = std::thread(engine_main, self);
      break;
    case GST_STATE_CHANGE_PLAYING_TO_PAUSED:
      impl->playing = false;
      GST_OBJECT_LOCK(self);
      for (auto& [pad, st] : impl->pads) wake_pad(st.get(), false);  // clock waits start again
      GST_OBJECT_UNLOCK(self);
      break;
    case GST_STATE_CHANGE_PAUSED_TO_READY:
      stop_engine(self);
      break;
    default:
      break;
  }
  GstStateChangeReturn ret =
      GST_ELEMENT_CLASS(gst_omma_stitch_parent_class)->change_state(element, transition);
  switch (transition) {
    case GST_STATE_CHANGE_PAUSED_TO_READY:
      if (impl->engine.joinable()) impl->engine.join();
      if (impl->out_conv) {
        gst_video_converter_free(impl->out_conv);
        impl->out_conv = nullptr;
      }
      forget_run(self);
      break;
    case GST_STATE_CHANGE_READY_TO_PAUSED:
    case GST_STATE_CHANGE_PLAYING_TO_PAUSED:
      if (ret == GST_STATE_CHANGE_SUCCESS) ret = GST_STATE_CHANGE_NO_PREROLL;  // live towards downstream
      break;
    default:
      break;
  }
  return ret;
}

void set_property(GObject* object, guint id, const GValue* value, GParamSpec* pspec) {
  GstOmmaStitch* self = GST_OMMA_STITCH(object);
  OmmaImpl* impl = self->impl;
  std::lock_guard<std::mutex> lock(impl->settings_mutex);
  OmmaSettings& s = impl->settings;
  auto str = [value] {
    const gchar* v = g_value_get_string(value);
    return std::string(v ? v : "");
  };
  switch (id) {
    case PROP_RIG:
      s.rig = str();
      break;
    case PROP_METHOD:
      s.method = str();
      break;
    case PROP_PROJECTION:
      s.projection = str();
      break;
    case PROP_SIZE:
      s.size = str();
      break;
    case PROP_DEPTH:
      s.depth = g_value_get_boolean(value);
      break;
    case PROP_PHOTOMETRIC:
      s.photometric = g_value_get_boolean(value);
      break;
    case PROP_FPS:
      s.fps = g_value_get_double(value);
      break;
    case PROP_SYNC:
      s.sync = g_value_get_boolean(value);
      break;
    case PROP_FIRST_FRAME_TIMEOUT:
      s.first_frame_timeout = g_value_get_double(value);
      break;
    case PROP_STALL_TIMEOUT:
      s.stall_timeout = g_value_get_double(value);
      break;
    case PROP_THREADS:
      s.threads = g_value_get_int(value);
      break;
    case PROP_CACHE_DIR:
      s.cache_dir = str();
      break;
    default:
      G_OBJECT_WARN_INVALID_PROPERTY_ID(object, id, pspec);
  }
}

void get_property(GObject* object, guint id, GValue* value, GParamSpec* pspec) {
  GstOmmaStitch* self = GST_OMMA_STITCH(object);
  OmmaImpl* impl = self->impl;
  if (id == PROP_STATS) {
    std::lock_guard<std::mutex> lock(impl->stats_mutex);
    g_value_set_string(value, impl->stats_json.c_str());
    return;
  }
  std::lock_guard<std::mutex> lock(impl->settings_mutex);
  const OmmaSettings& s = impl->settings;
  switch (id) {
    case PROP_RIG:
      g_value_set_string(value, s.rig.c_str());
      break;
    case PROP_METHOD:
      g_value_set_string(value, s.method.c_str());
      break;
    case PROP_PROJECTION:
      g_value_set_string(value, s.projection.c_str());
      break;
    case PROP_SIZE:
      g_value_set_string(value, s.size.c_str());
      break;
    case PROP_DEPTH:
      g_value_set_boolean(value, s.depth);
      break;
    case PROP_PHOTOMETRIC:
      g_value_set_boolean(value, s.photometric);
      break;
    case PROP_FPS:
      g_value_set_double(value, s.fps);
      break;
    case PROP_SYNC:
      g_value_set_boolean(value, s.sync);
      break;
    case PROP_FIRST_FRAME_TIMEOUT:
      g_value_set_double(value, s.first_frame_timeout);
      break;
    case PROP_STALL_TIMEOUT:
      g_value_set_double(value, s.stall_timeout);
      break;
    case PROP_THREADS:
      g_value_set_int(value, s.threads);
      break;
    case PROP_CACHE_DIR:
      g_value_set_string(value, s.cache_dir.c_str());
      break;
    default:
      G_OBJECT_WARN_INVALID_PROPERTY_ID(object, id, pspec);
  }
}

void finalize(GObject* object) {
  GstOmmaStitch* self = GST_OMMA_STITCH(object);
  if (self->impl->engine.joinable()) {  // (never: PAUSED->READY joins it)
    stop_engine(self);
    self->impl->engine.join();
  }
  delete self->impl;
  self->impl = nullptr;
  G_OBJECT_CLASS(gst_omma_stitch_parent_class)->finalize(object);
}

}  // namespace

static void gst_omma_stitch_class_init(GstOmmaStitchClass* klass) {
  GObjectClass* gobject_class = G_OBJECT_CLASS(klass);
  GstElementClass* element_class = GST_ELEMENT_CLASS(klass);
  gobject_class->set_property = set_property;
  gobject_class->get_property = get_property;
  gobject_class->finalize = finalize;
  const auto rw = GParamFlags(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS | GST_PARAM_MUTABLE_READY);
  g_object_class_install_property(
      gobject_class, PROP_RIG,
      g_param_spec_string("rig", "Rig", "Rig file (JSON) or built-in rig name (thesis-24, gigaeye-44, ...)",
                          nullptr, rw));
  g_object_class_install_property(
      gobject_class, PROP_METHOD,
      g_param_spec_string("method", "Method", "Blend method, as omma run --method (linear, nearest, ...)",
                          "linear", rw));
  g_object_class_install_property(
      gobject_class, PROP_PROJECTION,
      g_param_spec_string("projection", "Projection", "Panorama projection: vr180, equirect, equirect-full",
                          "vr180", rw));
  g_object_class_install_property(
      gobject_class, PROP_SIZE,
      g_param_spec_string("size", "Size", "Panorama size WxH, pixels", "1080x1080", rw));
  g_object_class_install_property(
      gobject_class, PROP_DEPTH,
      g_param_spec_boolean("depth", "Depth", "Depth-adaptive rendering (depth estimated every panorama)",
                           FALSE, rw));
  g_object_class_install_property(
      gobject_class, PROP_PHOTOMETRIC,
      g_param_spec_boolean("photometric", "Photometric",
                           "Apply the rig's photometric model (vignetting, colour gains) to every frame",
                           TRUE, rw));
  g_object_class_install_property(
      gobject_class, PROP_FPS,
      g_param_spec_double(
          "fps", "Frame rate",
          "Panorama rate, frames/s (0: render whenever a camera has a new frame; else 0.001..10000)", 0,
          omma::live::kMaxRate, 30, rw));
  g_object_class_install_property(
      gobject_class, PROP_SYNC,
      g_param_spec_boolean(
          "sync", "Sync",
          "Publish each camera buffer at its running time on the pipeline clock (as a sink with "
          "sync=true); off: at once",
          TRUE, rw));
  g_object_class_install_property(
      gobject_class, PROP_FIRST_FRAME_TIMEOUT,
      g_param_spec_double("first-frame-timeout", "First-frame timeout",
                          "A camera without a first frame after this many seconds is dropped", 0.001, 1e6, 5,
                          rw));
  g_object_class_install_property(
      gobject_class, PROP_STALL_TIMEOUT,
      g_param_spec_double(
          "stall-timeout", "Stall timeout",
          "A sink pad without a buffer for this many seconds (while PLAYING) drops its camera", 0.001, 1e6, 5,
          rw));
  g_object_class_install_property(
      gobject_class, PROP_THREADS,
      g_param_spec_int("threads", "Threads", "Renderer threads (0: all)", 0, 1024, 0, rw));
  g_object_class_install_property(
      gobject_class, PROP_CACHE_DIR,
      g_param_spec_string("cache-dir", "Cache folder",
                          "Map cache folder (empty: no cache, the map is compiled)", nullptr, rw));
  g_object_class_install_property(
      gobject_class, PROP_STATS,
      g_param_spec_string(
          "stats", "Statistics",
          "JSON of the latest omma-stats figures: fps, render-ms, latency-ms, push-latency-ms, "
          "cameras-live, dropped-cameras, frames",
          "{}", GParamFlags(G_PARAM_READABLE | G_PARAM_STATIC_STRINGS)));
  gst_element_class_add_static_pad_template(element_class, &g_sink_template);
  gst_element_class_add_static_pad_template(element_class, &g_src_template);
  gst_element_class_set_static_metadata(
      element_class, "omma panorama stitcher", "Filter/Editor/Video",
      "Stitches the N camera streams of a compound-eye rig into one 360-degree panorama (omma's live engine)",
      "the omma authors");
  element_class->request_new_pad = request_new_pad;
  element_class->release_pad = release_pad;
  element_class->change_state = change_state;
}

static void gst_omma_stitch_init(GstOmmaStitch* self) {
  self->impl = new OmmaImpl();
  self->src = gst_pad_new_from_static_template(&g_src_template, "src");
  gst_pad_set_query_function(self->src, src_query);
  gst_pad_set_event_function(self->src, src_event);
  gst_element_add_pad(GST_ELEMENT(self), self->src);
  GST_OBJECT_FLAG_SET(self, GST_ELEMENT_FLAG_REQUIRE_CLOCK);
}

// Whether omma's log goes to the GStreamer debug log (ommastitch.h, "Logging"). spdlog's registry is
// the process's (libspdlog is a shared library): replacing its default logger changes the logging of
// the whole process, so it is done only where no one else has a say in it.
bool redirect_omma_log() {
  const char* how = g_getenv("OMMA_GST_LOG");
  if (how && g_str_equal(how, "gst")) return true;
  if (how && g_str_equal(how, "keep")) return false;
  if (how && *how) g_warning("OMMA_GST_LOG=%s: expected gst or keep; taken as unset", how);
  // omma itself (omma bench --stream loads the plugin) logs where its options say.
  if (g_str_equal(program_invocation_short_name, "omma")) return false;
  // A host that installed a default logger of its own (spdlog's own is unnamed) keeps it.
  const std::shared_ptr<spdlog::logger> current = spdlog::default_logger();
  return current && current->name().empty();
}

static gboolean plugin_init(GstPlugin* plugin) {
  GST_DEBUG_CATEGORY_INIT(omma_stitch_debug, "ommastitch", 0, "omma panorama stitcher");
  if (redirect_omma_log()) {
    spdlog::set_default_logger(std::make_shared<spdlog::logger>("omma", std::make_shared<GstLogSink>()));
    spdlog::set_level(spdlog::level::debug);
    GST_INFO("omma's log (spdlog) goes to the debug category ommastitch");
  } else {
    GST_INFO("omma's log (spdlog) left to the host process");
  }
  return gst_element_register(plugin, "ommastitch", GST_RANK_NONE, GST_TYPE_OMMA_STITCH);
}

#define PACKAGE "omma"
GST_PLUGIN_DEFINE(GST_VERSION_MAJOR, GST_VERSION_MINOR, omma, "omma: compound-eye panorama stitching",
                  plugin_init, OMMA_VERSION, "BSD", "omma", "https://omma.invalid/")
