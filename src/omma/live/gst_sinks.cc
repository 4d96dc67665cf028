// rtsp:// and srt:// sinks (gst.h): the panorama encoded by GStreamer's own elements (appsrc !
// videoconvert ! x264enc), served by gst-rtsp-server or sent as MPEG-TS by srtsink. write() never
// blocks the render loop: a panorama the encoder has no room for is dropped (and counted).
#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "omma/live/gst.h"
#include "omma/live/gst_util.h"

#if OMMA_HAVE_GSTREAMER
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gst/app/gstappsrc.h>
#include <gst/gst.h>
#include <gst/rtsp-server/rtsp-server.h>
#include <gst/video/video.h>
#endif

namespace omma::live {

#if OMMA_HAVE_GSTREAMER
namespace {

// What a rtsp:// or srt:// spec says.
struct Endpoint {
  std::string scheme;  // "rtsp" or "srt"
  std::string host;    // as written (IPv6 without its brackets); "localhost" kept
  int port = 0;
  std::string path;   // rtsp: "/PATH"
  std::string query;  // srt: what follows '?' (without it)
};

[[noreturn]] void fail(const std::string& spec, const std::string& why) {
  throw SinkError("sink '" + spec + "': " + why);
}

Endpoint parse_endpoint(const std::string& spec) {
  Endpoint e;
  const size_t sep = spec.find("://");
  e.scheme = spec.substr(0, sep);
  const bool rtsp = e.scheme == "rtsp";
  const std::string form =
      rtsp ? "expected rtsp://HOST:PORT/PATH" : "expected srt://HOST:PORT[?mode=listener|caller]";
  std::string rest = spec.substr(sep + 3);
  if (const size_t q = rest.find('?'); q != std::string::npos) {
    e.query = rest.substr(q + 1);
    rest = rest.substr(0, q);
    if (rtsp) fail(spec, form + " (no query)");
  }
  if (const size_t slash = rest.find('/'); slash != std::string::npos) {
    e.path = rest.substr(slash);
    rest = rest.substr(0, slash);
  }
  if (rtsp && (e.path.size() < 2 || e.path.back() == '/'))
    fail(spec, form + " (a path such as /pano is needed: readers open that URL)");
  if (!rtsp && !e.path.empty() && e.path != "/") fail(spec, form + " (no path)");
  size_t colon = rest.rfind(':');
  if (!rest.empty() && rest.front() == '[') {
    const size_t close = rest.find(']');
    if (close == std::string::npos || close + 1 != colon) fail(spec, form);
    e.host = rest.substr(1, close - 1);
  } else {
    if (colon == std::string::npos) fail(spec, form + " (the port is missing)");
    e.host = rest.substr(0, colon);
  }
  if (colon == std::string::npos) fail(spec, form + " (the port is missing)");
  e.port = parse_port(spec, rest.substr(colon + 1));  // sinks.h
  if (e.host.empty()) fail(spec, form + " (the host is missing: 127.0.0.1 serves this machine only)");
  SinkOptions at;
  at.bind = e.host;
  if (std::string why; !at.IsValid(&why)) fail(spec, why);
  return e;
}

// The address as the socket layer takes it ("localhost" is 127.0.0.1, as the live view's).
std::string numeric_host(const std::string& host) { return host == "localhost" ? "127.0.0.1" : host; }

std::string url_host(const std::string& host) {
  return host.find(':') == std::string::npos ? host : "[" + host + "]";
}

// Whether `type` (SOCK_STREAM, SOCK_DGRAM) can be bound on host:port right now; `why` says why not.
bool can_bind(const std::string& host, int port, int type, std::string* why) {
  sockaddr_storage ss{};
  socklen_t len = 0;
  const std::string h = numeric_host(host);
  if (h.find(':') == std::string::npos) {
    auto* a = reinterpret_cast<sockaddr_in*>(&ss);
    a->sin_family = AF_INET;
    a->sin_port = htons(uint16_t(port));
    if (::inet_pton(AF_INET, h.c_str(), &a->sin_addr) != 1) return *why = "not an address", false;
    len = sizeof(sockaddr_in);
  } else {
    auto* a = reinterpret_cast<sockaddr_in6*>(&ss);
    a->sin6_family = AF_INET6;
    a->sin6_port = htons(uint16_t(port));
    if (::inet_pton(AF_INET6, h.c_str(), &a->sin6_addr) != 1) return *why = "not an address", false;
    len = sizeof(sockaddr_in6);
  }
  const int fd = ::socket(ss.ss_family, type | SOCK_CLOEXEC, 0);
  if (fd < 0) return *why = std::strerror(errno), false;
  if (type == SOCK_STREAM) {
    int yes = 1;  // as the server will: a port in TIME_WAIT is free, one listened on is not
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));
  }
  const bool ok = ::bind(fd, reinterpret_cast<sockaddr*>(&ss), len) == 0;
  if (!ok) *why = std::strerror(errno);
  ::close(fd);
  return ok;
}

// The encoder as a gst-launch fragment: x264enc in constant-quality mode (pass=qual, whose
// `quantizer` is x264's CRF, capped at x264enc's 50), zero latency (no B-frames, no lookahead),
// SinkOptions::video's preset and keyframe interval; fed I420 (4:2:0, what every decoder plays).
// appsrc queues at most 3 panoramas; push_panorama drops (and counts) beyond 2. max-bytes=0: appsrc's
// default byte limit (200 kB) is less than one panorama, and with leaky-type it silently dropped
// every queued panorama but the newest, while push_panorama counted them as sent.
std::string encoder_launch(const std::string& spec, cv::Size size, const SinkOptions& opt) {
  if (opt.video.codec == io::VideoCodec::kVp9) fail(spec, "sends H.264 (x264enc): --codec vp9 is for files");
  if (opt.video.ten_bit) fail(spec, "sends 8-bit H.264: --10bit is for files");
  if (size.width <= 0 || size.height <= 0 || size.width % 2 || size.height % 2)
    fail(spec, fmt::format("H.264 needs an even width and height, not {}x{}", size.width, size.height));
  int fps_n = 0, fps_d = 1;
  gst_util_double_to_fraction(opt.fps, &fps_n, &fps_d);
  const int crf = std::clamp(opt.video.crf < 0 ? 20 : opt.video.crf, 0, 50);
  const long gop = std::max(1L, std::lround(opt.video.gop_s * opt.fps));
  return fmt::format(
      "appsrc name=omma_src is-live=true format=time do-timestamp=true block=false max-buffers=3 "
      "max-bytes=0 leaky-type=downstream caps=video/x-raw,format=BGR,width={},height={},framerate={}/{} "
      "! videoconvert ! video/x-raw,format=I420 "
      "! x264enc name=omma_enc tune=zerolatency speed-preset={} key-int-max={} pass=qual quantizer={} "
      "threads={} sliced-threads=false",
      size.width, size.height, fps_n, fps_d, io::to_string(opt.video.preset), gop, crf, opt.video.threads);
}

// Copies the panorama into a buffer and pushes it into `src` unless two panoramas already wait
// there (the encoder is behind): then it is dropped. Returns whether it was pushed.
bool push_panorama(GstAppSrc* src, const cv::Mat& pano) {
  if (gst_app_src_get_current_level_buffers(src) >= 2) return false;
  // GStreamer's layout of video/x-raw,format=BGR without a GstVideoMeta: rows padded to 4 bytes
  // (GstVideoInfo's default stride), so a width that is not a multiple of 4 is read right.
  GstVideoInfo info;
  gst_video_info_set_format(&info, GST_VIDEO_FORMAT_BGR, guint(pano.cols), guint(pano.rows));
  const size_t row = size_t(pano.cols) * 3, stride = size_t(GST_VIDEO_INFO_PLANE_STRIDE(&info, 0));
  GstBuffer* buf = gst_buffer_new_allocate(nullptr, GST_VIDEO_INFO_SIZE(&info), nullptr);
  if (!buf) return false;
  GstMapInfo map;
  if (!gst_buffer_map(buf, &map, GST_MAP_WRITE)) {
    gst_buffer_unref(buf);
    return false;
  }
  for (int y = 0; y < pano.rows; ++y) std::memcpy(map.data + stride * y, pano.ptr(y), row);
  gst_buffer_unmap(buf, &map);
  return gst_app_src_push_buffer(src, buf) == GST_FLOW_OK;  // takes the buffer
}

// Asks x264enc (named omma_enc in `bin`) for a keyframe with SPS and PPS now (a new reader starts
// decoding at once instead of at the next keyframe interval).
void force_keyframe(GstElement* bin) {
  GstElement* enc = gst_bin_get_by_name_recurse_up(GST_BIN(bin), "omma_enc");
  if (!enc) return;
  if (GstPad* pad = gst_element_get_static_pad(enc, "src")) {
    gst_pad_send_event(pad, gst_video_event_new_upstream_force_key_unit(GST_CLOCK_TIME_NONE, TRUE, 0));
    gst_object_unref(pad);
  }
  gst_object_unref(enc);
}

void check_panorama(const cv::Mat& pano, cv::Size size, const std::string& name) {
  if (pano.type() != CV_8UC3 || pano.size() != size)
    throw SinkError(fmt::format("{}: expected {}x{} BGR panoramas, got {}x{} of type {}", name, size.width,
                                size.height, pano.cols, pano.rows, pano.type()));
}

void note_network(const std::string& host, const std::string& url) {
  if (!is_loopback_address(host))
    spdlog::warn("{}: the panorama is visible to the network: anyone who can reach this port can watch it",
                 url);
}

void note_spherical(const SinkOptions& opt, const std::string& url) {
  if (opt.spherical_metadata)
    spdlog::info(
        "{}: RTSP's SDP and MPEG-TS carry no Spherical Video metadata: players are told the "
        "projection some other way",
        url);
}

// rtsp://HOST:PORT/PATH: gst-rtsp-server in its own GMainLoop thread, one shared media (one
// encoder) for every reader, made when the first reader comes and released when the last leaves.
class RtspSink : public Sink {
 public:
  RtspSink(const std::string& spec, const Endpoint& e, cv::Size size, const SinkOptions& opt)
      : size_(size), url_(fmt::format("rtsp://{}:{}{}", url_host(e.host), e.port, e.path)) {
    const std::string launch =
        "( " + encoder_launch(spec, size, opt) + " ! rtph264pay name=pay0 pt=96 config-interval=-1 )";
    if (std::string why; !can_bind(e.host, e.port, SOCK_STREAM, &why))
      fail(spec, fmt::format("cannot serve RTSP on {}:{}: {} (port in use, address not of this machine, or "
                             "not permitted)",
                             e.host, e.port, why));
    server_ = gst_rtsp_server_new();
    gst_rtsp_server_set_address(server_, numeric_host(e.host).c_str());
    gst_rtsp_server_set_service(server_, std::to_string(e.port).c_str());
    GstRTSPMediaFactory* factory = gst_rtsp_media_factory_new();
    factory_ = GST_RTSP_MEDIA_FACTORY(g_object_ref(factory));
    gst_rtsp_media_factory_set_launch(factory, launch.c_str());
    gst_rtsp_media_factory_set_shared(factory, TRUE);
    g_signal_connect(factory, "media-configure", G_CALLBACK(&RtspSink::on_configure), this);
    g_signal_connect(server_, "client-connected", G_CALLBACK(&RtspSink::on_client), this);
    GstRTSPMountPoints* mounts = gst_rtsp_server_get_mount_points(server_);
    gst_rtsp_mount_points_add_factory(mounts, e.path.c_str(), factory);  // takes the factory
    g_object_unref(mounts);
    context_ = g_main_context_new();
    loop_ = g_main_loop_new(context_, FALSE);
    GError* err = nullptr;
    source_ = gst_rtsp_server_create_source(server_, nullptr, &err);
    if (!source_) {
      const std::string why = err ? err->message : "unknown error";
      if (err) g_error_free(err);
      release();
      fail(spec, fmt::format("cannot serve RTSP on {}:{}: {}", e.host, e.port, why));
    }
    g_source_attach(source_, context_);
    thread_ = std::thread([this] {
      g_main_context_push_thread_default(context_);
      g_main_loop_run(loop_);
      g_main_context_pop_thread_default(context_);
    });
    spdlog::info("RTSP: {} (H.264, {}x{})", url_, size.width, size.height);
    note_network(e.host, url_);
    note_spherical(opt, url_);
  }
  ~RtspSink() override { stop(); }

  void write(const cv::Mat& pano, const render::FrameStore&) override {
    check_panorama(pano, size_, url_);
    std::lock_guard<std::mutex> lock(mutex_);
    if (media_.empty()) return;  // no reader: nothing to encode
    for (const Media& m : media_) {
      if (push_panorama(m.src, pano))
        ++sent_;
      else
        ++dropped_;
    }
  }
  void finish() override { stop(); }
  void abort() override { stop(); }
  std::string describe() const override { return url_; }

 private:
  struct Media {
    GstRTSPMedia* media;
    GstAppSrc* src;
  };
  // A reader asked for the stream and the shared media was made: feed its appsrc from now on.
  static void on_configure(GstRTSPMediaFactory*, GstRTSPMedia* media, gpointer self_ptr) {
    auto* self = static_cast<RtspSink*>(self_ptr);
    GstElement* bin = gst_rtsp_media_get_element(media);
    GstElement* src = gst_bin_get_by_name_recurse_up(GST_BIN(bin), "omma_src");
    gst_object_unref(bin);
    if (!src) return;
    std::lock_guard<std::mutex> lock(self->mutex_);
    if (self->stopping_) {  // no handler then: it would outlive the sink
      gst_object_unref(src);
      return;
    }
    g_signal_connect(media, "unprepared", G_CALLBACK(&RtspSink::on_unprepared), self);
    self->media_.push_back({GST_RTSP_MEDIA(g_object_ref(media)), GST_APP_SRC(src)});
    spdlog::debug("{}: a reader opened the stream", self->url_);
  }
  // A reader connected. Its "drop-backlog" stays TRUE (the default): a reader over TCP that does
  // not keep up loses RTP packets once its backlog is full. With FALSE the server waits for that
  // reader, and in gst-rtsp-server 1.22 one shared media sends to all its TCP readers from one
  // thread: a reader that stopped reading stalled every other one (and its corrupt frames are the
  // price of the others' stream).
  static void on_client(GstRTSPServer*, GstRTSPClient* client, gpointer self) {
    g_signal_connect(client, "play-request", G_CALLBACK(&RtspSink::on_play), self);
  }
  // A reader starts playing (the shared media may have sent its first keyframe before): a keyframe.
  static void on_play(GstRTSPClient*, GstRTSPContext* ctx, gpointer self_ptr) {
    auto* self = static_cast<RtspSink*>(self_ptr);
    if (!ctx || !ctx->media) return;
    GstElement* bin = gst_rtsp_media_get_element(ctx->media);
    force_keyframe(bin);
    gst_object_unref(bin);
    spdlog::debug("{}: a reader plays the stream", self->url_);
  }
  // The last reader left (or the server stops): the media and its encoder are gone.
  static void on_unprepared(GstRTSPMedia* media, gpointer self_ptr) {
    auto* self = static_cast<RtspSink*>(self_ptr);
    std::lock_guard<std::mutex> lock(self->mutex_);
    self->forget(media);
    spdlog::debug("{}: no reader left", self->url_);
  }
  void forget(GstRTSPMedia* media) {  // mutex_ held
    for (auto it = media_.begin(); it != media_.end(); ++it)
      if (it->media == media) {
        g_signal_handlers_disconnect_by_data(it->media, this);
        gst_object_unref(it->src);
        g_object_unref(it->media);
        media_.erase(it);
        return;
      }
  }
  static GstRTSPFilterResult remove_client(GstRTSPServer*, GstRTSPClient* client, gpointer self) {
    g_signal_handlers_disconnect_by_data(client, self);
    return GST_RTSP_FILTER_REMOVE;
  }
  static GstRTSPFilterResult remove_session(GstRTSPSessionPool*, GstRTSPSession*, gpointer) {
    return GST_RTSP_FILTER_REMOVE;
  }
  void stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (stopping_) return;
      stopping_ = true;
    }
    if (loop_ && thread_.joinable()) {
      // Close every reader from the server's own thread, then end its loop.
      g_main_context_invoke(
          context_,
          [](gpointer p) -> gboolean {
            auto* self = static_cast<RtspSink*>(p);
            gst_rtsp_server_client_filter(self->server_, &RtspSink::remove_client, self);
            g_main_loop_quit(self->loop_);
            return G_SOURCE_REMOVE;
          },
          this);
      thread_.join();
    }
    // A client's thread (gst-rtsp-server's thread pool) may still make a media: not for this sink.
    if (factory_) g_signal_handlers_disconnect_by_data(factory_, this);
    if (server_) g_signal_handlers_disconnect_by_data(server_, this);
    if (server_) {
      GstRTSPSessionPool* pool = gst_rtsp_server_get_session_pool(server_);
      g_list_free(gst_rtsp_session_pool_filter(pool, &RtspSink::remove_session, nullptr));
      g_object_unref(pool);
    }
    std::vector<Media> left;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      left.swap(media_);
    }
    for (const Media& m : left) {  // media a reader still held: stop their pipelines
      g_signal_handlers_disconnect_by_data(m.media, this);
      gst_rtsp_media_unprepare(m.media);
      gst_object_unref(m.src);
      g_object_unref(m.media);
    }
    spdlog::debug("{}: {} panoramas sent, {} dropped (encoder behind)", url_, sent_, dropped_);
    release();
  }
  void release() {
    if (factory_) {
      g_signal_handlers_disconnect_by_data(factory_, this);
      g_object_unref(factory_);
      factory_ = nullptr;
    }
    if (source_) {
      g_source_destroy(source_);
      g_source_unref(source_);
      source_ = nullptr;
    }
    if (server_) g_object_unref(server_);
    server_ = nullptr;
    if (loop_) g_main_loop_unref(loop_);
    loop_ = nullptr;
    if (context_) g_main_context_unref(context_);
    context_ = nullptr;
  }

  cv::Size size_;
  std::string url_;
  GstRTSPServer* server_ = nullptr;
  GstRTSPMediaFactory* factory_ = nullptr;  // a reference of ours (the mount points hold it)
  GMainContext* context_ = nullptr;
  GMainLoop* loop_ = nullptr;
  GSource* source_ = nullptr;
  std::thread thread_;
  std::mutex mutex_;
  std::vector<Media> media_;  // the prepared media (one: it is shared), with their appsrc
  bool stopping_ = false;
  long sent_ = 0, dropped_ = 0;
};

// srt://HOST:PORT[?QUERY]: appsrc ! videoconvert ! x264enc ! h264parse ! mpegtsmux alignment=7 ! srtsink, one
// pipeline for the whole run; srtsink never waits for a reader (wait-for-connection=false).
class SrtSink : public Sink {
 public:
  SrtSink(const std::string& spec, const Endpoint& e, cv::Size size, const SinkOptions& opt)
      : size_(size), url_(fmt::format("srt://{}:{}", url_host(e.host), e.port)) {
    std::string mode = "listener", query;
    for (size_t at = 0; at < e.query.size();) {
      size_t amp = e.query.find('&', at);
      if (amp == std::string::npos) amp = e.query.size();
      const std::string kv = e.query.substr(at, amp - at);
      at = amp + 1;
      if (kv.empty()) continue;
      const size_t eq = kv.find('=');
      const std::string key = kv.substr(0, eq), value = eq == std::string::npos ? "" : kv.substr(eq + 1);
      if (kv.find_first_of(" \"'!\\") != std::string::npos) fail(spec, "'" + kv + "': not a URI parameter");
      if (key == "mode") {
        if (value != "listener" && value != "caller")
          fail(spec, "mode '" + value +
                         "': expected mode=listener (readers call this address) or mode=caller "
                         "(push to a listener there)");
        mode = value;
      } else {
        query += "&" + kv;  // srtsink's own URI parameters: latency, passphrase, streamid, ...
      }
    }
    listener_ = mode == "listener";
    url_ += "?mode=" + mode + query;
    if (std::string why; listener_ && !can_bind(e.host, e.port, SOCK_DGRAM, &why))
      fail(spec, fmt::format("cannot listen for SRT on {}:{} (UDP): {} (port in use, address not of this "
                             "machine, or not permitted)",
                             e.host, e.port, why));
    const std::string uri =
        fmt::format("srt://{}:{}?mode={}{}", url_host(numeric_host(e.host)), e.port, mode, query);
    const std::string launch =
        encoder_launch(spec, size, opt) +
        " ! h264parse config-interval=-1 ! mpegtsmux alignment=7 ! srtsink name=omma_srt uri=\"" + uri +
        "\" wait-for-connection=false sync=false async=false";
    std::string why;
    pipeline_ = parse_pipeline(launch, &why);  // gst_util.h
    if (!pipeline_) fail(spec, "cannot build the SRT pipeline: " + why);
    src_ = GST_APP_SRC(gst_bin_get_by_name(GST_BIN(pipeline_), "omma_src"));
    GstElement* srt = gst_bin_get_by_name(GST_BIN(pipeline_), "omma_srt");
    g_signal_connect(srt, "caller-added", G_CALLBACK(&SrtSink::on_caller_added), this);
    g_signal_connect(srt, "caller-removed", G_CALLBACK(&SrtSink::on_caller_removed), this);
    gst_object_unref(srt);
    if (gst_element_set_state(pipeline_, GST_STATE_PLAYING) == GST_STATE_CHANGE_FAILURE) {
      const std::string why = bus_error();
      release();
      fail(spec, fmt::format("cannot {} SRT on {}:{}: {}", listener_ ? "listen for" : "send", e.host, e.port,
                             why.empty() ? "the pipeline did not start" : why));
    }
    spdlog::info("SRT: {} (H.264 in MPEG-TS, {}x{}{})", url_, size.width, size.height,
                 listener_ ? fmt::format("; read it with ffplay srt://{}:{}", url_host(e.host), e.port) : "");
    note_network(e.host, url_);
    note_spherical(opt, url_);
  }
  ~SrtSink() override { release(); }

  void write(const cv::Mat& pano, const render::FrameStore&) override {
    check_panorama(pano, size_, url_);
    if (!src_) return;
    if (const std::string why = bus_error(); !why.empty()) {
      spdlog::warn("{}: {}: the panorama is no longer sent", url_, why);
      release();
      return;
    }
    if (push_panorama(src_, pano))
      ++sent_;
    else
      ++dropped_;
  }
  void finish() override { release(); }
  void abort() override { release(); }
  std::string describe() const override { return url_; }

 private:
  // A reader called: it gets a keyframe (with SPS and PPS) now instead of at the next interval.
  static void on_caller_added(GstElement*, gint, GSocketAddress*, gpointer self_ptr) {
    auto* self = static_cast<SrtSink*>(self_ptr);
    spdlog::debug("{}: a reader connected", self->url_);
    force_keyframe(self->pipeline_);
  }
  static void on_caller_removed(GstElement*, gint, GSocketAddress*, gpointer self_ptr) {
    spdlog::debug("{}: a reader left", static_cast<SrtSink*>(self_ptr)->url_);
  }
  // The first error on the pipeline's bus ("" if none), without waiting. The other messages are
  // dropped (left there, they would pile up for the whole run).
  std::string bus_error() {
    if (!pipeline_) return "";
    GstBus* bus = gst_element_get_bus(pipeline_);
    GstMessage* msg = nullptr;
    while (GstMessage* m = gst_bus_pop(bus)) {
      if (GST_MESSAGE_TYPE(m) == GST_MESSAGE_ERROR) {
        msg = m;
        break;
      }
      gst_message_unref(m);
    }
    gst_object_unref(bus);
    if (!msg) return "";
    std::string debug;
    const std::string why = message_text(msg, &debug);  // gst_util.h
    if (!debug.empty()) spdlog::debug("{}: {}", url_, debug);
    gst_message_unref(msg);
    return why;
  }
  void release() {
    if (src_) gst_object_unref(src_);
    src_ = nullptr;
    if (pipeline_) {
      gst_element_set_state(pipeline_, GST_STATE_NULL);
      gst_object_unref(pipeline_);
      pipeline_ = nullptr;
      spdlog::debug("{}: {} panoramas sent, {} dropped (encoder behind)", url_, sent_, dropped_);
    }
  }

  cv::Size size_;
  std::string url_;
  bool listener_ = true;
  GstElement* pipeline_ = nullptr;
  GstAppSrc* src_ = nullptr;
  long sent_ = 0, dropped_ = 0;
};

}  // namespace

std::unique_ptr<Sink> open_gst_sink(const std::string& spec, cv::Size pano_size, const SinkOptions& opt) {
  if (spec.rfind("rtsp://", 0) != 0 && spec.rfind("srt://", 0) != 0)
    fail(spec, "expected rtsp://HOST:PORT/PATH or srt://HOST:PORT");
  const Endpoint e = parse_endpoint(spec);
  try {
    init_gstreamer();
  } catch (const std::exception& ex) {
    fail(spec, ex.what());
  }
  if (e.scheme == "rtsp") return std::make_unique<RtspSink>(spec, e, pano_size, opt);
  return std::make_unique<SrtSink>(spec, e, pano_size, opt);
}

#else

std::unique_ptr<Sink> open_gst_sink(const std::string& spec, cv::Size, const SinkOptions&) {
  try {
    init_gstreamer();
  } catch (const std::exception& ex) {
    throw SinkError("sink '" + spec + "': " + ex.what());
  }
  throw SinkError("sink '" + spec + "': this omma was built without GStreamer");
}

#endif

}  // namespace omma::live
