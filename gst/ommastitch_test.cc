// Tests of the GStreamer plugin (ommastitch.h): the plugin as gst-inspect-1.0 sees it, the element's
// panorama against `omma run`'s on the same frames, its errors and warnings on the bus, and stopping.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <gst/app/gstappsink.h>
#include <gst/gst.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

namespace fs = std::filesystem;
using Seconds = std::chrono::duration<double>;

namespace {

constexpr int kCameras = 24;  // thesis-24: 250 x 250 cameras

struct CmdResult {
  int rc = -1;
  std::string out;
};

CmdResult run_cmd(const std::string& cmd) {
  CmdResult r;
  FILE* f = popen((cmd + " 2>&1").c_str(), "r");
  if (!f) return r;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, f)) > 0) r.out.append(buf, n);
  const int status = pclose(f);
  r.rc = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

fs::path tmp_dir(const std::string& tag) {
  const fs::path d = fs::path(OMMA_TEST_TMP) / tag;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// A frames folder of thesis-24 looking at the checker scene (made once).
const fs::path& frames_folder() {
  static const fs::path dir = [] {
    // One folder per process: ctest may run the tests that use it side by side.
    const fs::path d = tmp_dir("frames-" + std::to_string(getpid())) / "f";
    const CmdResult r =
        run_cmd(std::string(OMMA_BINARY) + " simulate --rig thesis-24 --scene checker --out " + d.string() +
                " --no-truth --supersample 1");
    EXPECT_EQ(r.rc, 0) << r.out;
    return d;
  }();
  return dir;
}

// What the bus said while a pipeline ran.
struct BusLog {
  std::vector<std::string> errors, warnings;
  std::vector<nlohmann::json> stats;  // omma-stats messages
  bool eos = false;
};

std::string message_text(GstMessage* m) {
  GError* err = nullptr;
  gchar* debug = nullptr;
  if (GST_MESSAGE_TYPE(m) == GST_MESSAGE_ERROR)
    gst_message_parse_error(m, &err, &debug);
  else
    gst_message_parse_warning(m, &err, &debug);
  std::string s = std::string(GST_OBJECT_NAME(GST_MESSAGE_SRC(m))) + ": " + (err ? err->message : "") +
                  " | " + (debug ? debug : "");
  if (err) g_error_free(err);
  g_free(debug);
  return s;
}

// Pops bus messages until `until` says stop, an error, EOS, or the timeout.
void pump(GstElement* pipeline, BusLog& log, double timeout_s, const std::function<bool()>& until = {}) {
  GstBus* bus = gst_element_get_bus(pipeline);
  const auto t0 = std::chrono::steady_clock::now();
  while (Seconds(std::chrono::steady_clock::now() - t0).count() < timeout_s) {
    if (until && until()) break;
    GstMessage* m = gst_bus_timed_pop(bus, 20 * GST_MSECOND);
    if (!m) continue;
    switch (GST_MESSAGE_TYPE(m)) {
      case GST_MESSAGE_ERROR:
        log.errors.push_back(message_text(m));
        break;
      case GST_MESSAGE_WARNING:
        log.warnings.push_back(message_text(m));
        break;
      case GST_MESSAGE_EOS:
        log.eos = true;
        break;
      case GST_MESSAGE_ELEMENT:
        if (const GstStructure* s = gst_message_get_structure(m);
            s && gst_structure_has_name(s, "omma-stats")) {
          nlohmann::json j;
          for (const char* k : {"fps", "render-ms", "latency-ms", "push-latency-ms"}) {
            double v = 0;
            gst_structure_get_double(s, k, &v);
            j[k] = v;
          }
          for (const char* k : {"cameras-live", "dropped-cameras"}) {
            int v = 0;
            gst_structure_get_int(s, k, &v);
            j[k] = v;
          }
          log.stats.push_back(j);
        }
        break;
      default:
        break;
    }
    gst_message_unref(m);
    if (!log.errors.empty() || log.eos) break;
  }
  gst_object_unref(bus);
}

// Sets NULL and returns how long that took, s.
double stop_pipeline(GstElement* pipeline) {
  const auto t0 = std::chrono::steady_clock::now();
  gst_element_set_state(pipeline, GST_STATE_NULL);
  return Seconds(std::chrono::steady_clock::now() - t0).count();
}

GstElement* parse(const std::string& desc) {
  GError* err = nullptr;
  GstElement* p = gst_parse_launch(desc.c_str(), &err);
  EXPECT_EQ(err, nullptr) << (err ? err->message : "") << "\n" << desc;
  if (err) g_error_free(err);
  return p;
}

// Camera branches: still frames of the frames folder (imagefreeze), `buffers` each at 30 fps.
std::string still_branches(int buffers) {
  std::string d;
  for (int i = 0; i < kCameras; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "cam_%02d.png", i);
    d += " filesrc location=" + (frames_folder() / name).string() +
         " ! pngdec ! imagefreeze num-buffers=" + std::to_string(buffers) + " ! video/x-raw,framerate=30/1" +
         " ! videoconvert ! s.sink_" + std::to_string(i);
  }
  return d;
}

// Moving test-pattern branches at the cameras' size, endless; `special` may give branch i's own source
// ("skip": none).
std::string test_branches(int count, const std::function<std::string(int)>& special = {}) {
  std::string d;
  for (int i = 0; i < count; ++i) {
    const std::string own = special ? special(i) : "";
    if (own == "skip") continue;
    d += own.empty()
             ? " videotestsrc pattern=ball ! video/x-raw,width=250,height=250,framerate=30/1 ! s.sink_" +
                   std::to_string(i)
             : " " + own + " ! s.sink_" + std::to_string(i);
  }
  return d;
}

double psnr(const cv::Mat& a, const cv::Mat& b) { return cv::PSNR(a, b); }

bool has(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += x + "\n";
  return s;
}

}  // namespace

TEST(OmmaStitch, GstInspectListsThePluginAndItsProperties) {
  const CmdResult plugin = run_cmd("gst-inspect-1.0 omma");
  ASSERT_EQ(plugin.rc, 0) << plugin.out;
  EXPECT_TRUE(has(plugin.out, "ommastitch")) << plugin.out;
  EXPECT_TRUE(has(plugin.out, "libgstomma.so")) << plugin.out;
  const CmdResult el = run_cmd("gst-inspect-1.0 ommastitch");
  ASSERT_EQ(el.rc, 0) << el.out;
  for (const char* what : {"Filter/Editor/Video", "sink_%u", "rig", "method", "projection", "size", "depth",
                           "photometric", "fps", "sync", "first-frame-timeout", "stall-timeout", "threads",
                           "cache-dir", "stats", "changeable only in NULL or READY state"})
    EXPECT_TRUE(has(el.out, what)) << what << "\n" << el.out;
}

// The element's panorama equals `omma run`'s on the same frames; the output buffers read back have the
// panorama's size, BGR, PTS about 1/fps apart and DURATION 1/fps; the stream ends with EOS.
TEST(OmmaStitch, MatchesOmmaRunAndTimestampsFollowFps) {
  const fs::path out = tmp_dir("match");
  const CmdResult r =
      run_cmd(std::string(OMMA_BINARY) + " run --rig thesis-24 --source frames:" + frames_folder().string() +
              " --frames 3 --sink png:" + (out / "run").string() + " --size 512x512 --no-cache --json");
  ASSERT_EQ(r.rc, 0) << r.out;
  const cv::Mat ref = cv::imread((out / "run" / "frame_000000.png").string());
  ASSERT_FALSE(ref.empty());

  GstElement* p = parse(
      "ommastitch name=s rig=thesis-24 size=512x512 fps=30 ! video/x-raw,format=BGR ! appsink "
      "name=out sync=false max-buffers=1000 wait-on-eos=false" +
      still_branches(30));
  ASSERT_TRUE(p);
  GstElement* sink = gst_bin_get_by_name(GST_BIN(p), "out");
  gst_element_set_state(p, GST_STATE_PLAYING);
  BusLog log;
  pump(p, log, 8);
  EXPECT_TRUE(log.errors.empty()) << joined(log.errors);
  EXPECT_TRUE(log.eos);
  std::vector<GstClockTime> pts;
  cv::Mat first;
  int w = 0, h = 0;
  std::string format;
  GstClockTime duration = 0;
  while (GstSample* sample = gst_app_sink_try_pull_sample(GST_APP_SINK(sink), 0)) {
    GstBuffer* buf = gst_sample_get_buffer(sample);
    const GstStructure* st = gst_caps_get_structure(gst_sample_get_caps(sample), 0);
    gst_structure_get_int(st, "width", &w);
    gst_structure_get_int(st, "height", &h);
    format = gst_structure_get_string(st, "format");
    pts.push_back(GST_BUFFER_PTS(buf));
    duration = GST_BUFFER_DURATION(buf);
    if (first.empty()) {
      GstMapInfo map;
      ASSERT_TRUE(gst_buffer_map(buf, &map, GST_MAP_READ));
      first = cv::Mat(h, w, CV_8UC3, map.data, size_t(w) * 3).clone();  // 512 * 3: rows 4-byte aligned
      gst_buffer_unmap(buf, &map);
    }
    gst_sample_unref(sample);
  }
  gst_object_unref(sink);
  stop_pipeline(p);
  gst_object_unref(p);
  EXPECT_EQ(w, 512);
  EXPECT_EQ(h, 512);
  EXPECT_EQ(format, "BGR");
  EXPECT_EQ(duration, GST_SECOND / 30);
  // 30 stills at 30 fps played against the clock: about one second of panoramas at 30 fps (less the
  // engine's start-up, while the map compiles).
  ASSERT_GE(pts.size(), 10u);
  EXPECT_LE(pts.size(), 40u);
  for (size_t i = 1; i < pts.size(); ++i) EXPECT_GT(pts[i], pts[i - 1]);
  const double mean_ms = double(pts.back() - pts.front()) / 1e6 / double(pts.size() - 1);
  EXPECT_NEAR(mean_ms, 1000.0 / 30, 5) << pts.size() << " buffers";
  ASSERT_FALSE(first.empty());
  const double db = psnr(first, ref);
  EXPECT_GE(db, 40) << "PSNR against omma run";
  std::printf("ommastitch vs omma run: PSNR %.1f dB, %zu buffers, PTS spacing %.2f ms\n", db, pts.size(),
              mean_ms);
}

TEST(OmmaStitch, PadCountMismatchIsAnError) {
  GstElement* p = parse("ommastitch name=s rig=thesis-24 size=128x128 ! fakesink" + test_branches(3));
  ASSERT_TRUE(p);
  EXPECT_EQ(gst_element_set_state(p, GST_STATE_PLAYING), GST_STATE_CHANGE_FAILURE);
  BusLog log;
  pump(p, log, 3);
  ASSERT_FALSE(log.errors.empty());
  EXPECT_TRUE(has(log.errors.front(), "ommastitch: 3 sink pads for a rig of 24 cameras"))
      << log.errors.front();
  EXPECT_LT(stop_pipeline(p), 2.0);
  gst_object_unref(p);
}

TEST(OmmaStitch, MissingRigIsAnError) {
  GstElement* p = parse("ommastitch name=s rig=/no/such/rig.json size=128x128 ! fakesink" + test_branches(3));
  ASSERT_TRUE(p);
  EXPECT_EQ(gst_element_set_state(p, GST_STATE_PLAYING), GST_STATE_CHANGE_FAILURE);
  BusLog log;
  pump(p, log, 3);
  ASSERT_FALSE(log.errors.empty());
  EXPECT_TRUE(has(log.errors.front(), "rig '/no/such/rig.json'")) << log.errors.front();
  EXPECT_LT(stop_pipeline(p), 2.0);
  gst_object_unref(p);
}

// Audio linked to a camera pad cannot be negotiated: not-negotiated on the bus, no hang.
TEST(OmmaStitch, UnconvertibleCapsAreNotNegotiated) {
  // gst_parse_launch refuses the link itself: link audio to sink_4 without the caps check.
  GstElement* p =
      parse("ommastitch name=s rig=thesis-24 size=128x128 ! fakesink audiotestsrc name=a" +
            test_branches(kCameras, [](int i) { return i == 4 ? std::string("skip") : std::string(); }));
  ASSERT_TRUE(p);
  GstElement* s = gst_bin_get_by_name(GST_BIN(p), "s");
  GstElement* a = gst_bin_get_by_name(GST_BIN(p), "a");
  GstPad* sink4 = gst_element_request_pad_simple(s, "sink_4");
  GstPad* asrc = gst_element_get_static_pad(a, "src");
  ASSERT_TRUE(sink4 && asrc);
  EXPECT_EQ(gst_pad_link_full(asrc, sink4, GST_PAD_LINK_CHECK_NOTHING), GST_PAD_LINK_OK);
  gst_object_unref(asrc);
  gst_object_unref(sink4);
  gst_object_unref(a);
  gst_object_unref(s);
  gst_element_set_state(p, GST_STATE_PLAYING);
  BusLog log;
  pump(p, log, 5);
  ASSERT_FALSE(log.errors.empty());
  EXPECT_TRUE(has(joined(log.errors), "not-negotiated")) << joined(log.errors);
  EXPECT_LT(stop_pipeline(p), 2.0);
  gst_object_unref(p);
}

// Frames of another size than the camera's: an error naming the pad, the camera and both sizes.
TEST(OmmaStitch, WrongFrameSizeNamesPadAndCamera) {
  GstElement* p =
      parse("ommastitch name=s rig=thesis-24 size=128x128 ! fakesink" + test_branches(kCameras, [](int i) {
              return i == 5 ? std::string("videotestsrc ! video/x-raw,width=320,height=240") : std::string();
            }));
  ASSERT_TRUE(p);
  gst_element_set_state(p, GST_STATE_PLAYING);
  BusLog log;
  pump(p, log, 5);
  ASSERT_FALSE(log.errors.empty());
  EXPECT_TRUE(has(log.errors.front(), "sink_5 (camera 5) gets 320x240 frames, the rig's camera is 250x250"))
      << joined(log.errors);
  EXPECT_LT(stop_pipeline(p), 2.0);
  gst_object_unref(p);
}

// A camera whose stream ends early is dropped with a warning; the panorama goes on with 23 cameras.
TEST(OmmaStitch, EndedCameraIsDroppedAndOutputContinues) {
  GstElement* p = parse(
      "ommastitch name=s rig=thesis-24 size=256x256 ! appsink name=out sync=false max-buffers=2 "
      "drop=true" +
      test_branches(kCameras, [](int i) {
        return i == 7 ? std::string(
                            "videotestsrc num-buffers=5 ! "
                            "video/x-raw,width=250,height=250,framerate=30/1")
                      : std::string();
      }));
  ASSERT_TRUE(p);
  gst_element_set_state(p, GST_STATE_PLAYING);
  BusLog log;
  auto live_after_warning = [&] {
    return !log.warnings.empty() && !log.stats.empty() && log.stats.back()["cameras-live"] == kCameras - 1;
  };
  pump(p, log, 8, live_after_warning);
  EXPECT_TRUE(log.errors.empty()) << joined(log.errors);
  ASSERT_FALSE(log.warnings.empty());
  EXPECT_TRUE(has(log.warnings.front(), "camera 7 (sink_7) dropped: ended")) << joined(log.warnings);
  ASSERT_FALSE(log.stats.empty());
  const nlohmann::json& last = log.stats.back();
  EXPECT_EQ(last["cameras-live"], kCameras - 1);
  EXPECT_EQ(last["dropped-cameras"], 1);
  EXPECT_GT(last["fps"].get<double>(), 5);
  // The stats property says the same.
  GstElement* s = gst_bin_get_by_name(GST_BIN(p), "s");
  gchar* json = nullptr;
  g_object_get(s, "stats", &json, nullptr);
  const nlohmann::json j = nlohmann::json::parse(json);
  g_free(json);
  gst_object_unref(s);
  EXPECT_EQ(j["cameras-live"], kCameras - 1);
  EXPECT_GT(j["push-latency-ms"].get<double>(), 0);
  // Output still flows after the drop.
  GstElement* sink = gst_bin_get_by_name(GST_BIN(p), "out");
  GstSample* sample = gst_app_sink_try_pull_sample(GST_APP_SINK(sink), 2 * GST_SECOND);
  EXPECT_NE(sample, nullptr);
  if (sample) gst_sample_unref(sample);
  gst_object_unref(sink);
  EXPECT_LT(stop_pipeline(p), 2.0);
  gst_object_unref(p);
  std::printf("stats after the drop: %s\n", last.dump().c_str());
}

// Setting NULL while the panorama streams returns within 2 s, again and again.
TEST(OmmaStitch, StopMidStreamReturnsQuickly) {
  for (int round = 0; round < 3; ++round) {
    GstElement* p =
        parse("ommastitch name=s rig=thesis-24 size=256x256 ! appsink name=out sync=true max-buffers=1" +
              test_branches(kCameras));
    ASSERT_TRUE(p);
    gst_element_set_state(p, GST_STATE_PLAYING);
    GstElement* sink = gst_bin_get_by_name(GST_BIN(p), "out");
    GstSample* sample = gst_app_sink_try_pull_sample(GST_APP_SINK(sink), 5 * GST_SECOND);
    EXPECT_NE(sample, nullptr) << "round " << round;
    if (sample) gst_sample_unref(sample);
    gst_object_unref(sink);
    const double s = stop_pipeline(p);
    EXPECT_LT(s, 2.0) << "round " << round;
    std::printf("round %d: NULL in %.3f s\n", round, s);
    gst_object_unref(p);
  }
}

namespace {

// Pulls up to `n` samples within `timeout_s`; their PTS.
std::vector<GstClockTime> pull_pts(GstElement* appsink, size_t n, double timeout_s) {
  std::vector<GstClockTime> pts;
  const auto t0 = std::chrono::steady_clock::now();
  while (pts.size() < n && Seconds(std::chrono::steady_clock::now() - t0).count() < timeout_s) {
    GstSample* sample = gst_app_sink_try_pull_sample(GST_APP_SINK(appsink), 100 * GST_MSECOND);
    if (!sample) continue;
    pts.push_back(GST_BUFFER_PTS(gst_sample_get_buffer(sample)));
    gst_sample_unref(sample);
  }
  return pts;
}

GstElement* by_name(GstElement* pipeline, const char* name) {
  return gst_bin_get_by_name(GST_BIN(pipeline), name);
}

double since(std::chrono::steady_clock::time_point t0) {
  return Seconds(std::chrono::steady_clock::now() - t0).count();
}

const std::string kBall = "videotestsrc pattern=ball ! video/x-raw,width=250,height=250,framerate=30/1";

}  // namespace

// A branch that stops delivering (its valve closes) fails its camera as stalled within stall-timeout
// (+ the half-second statistics interval): a warning names it, cameras-live drops to 23 and the
// panorama goes on.
TEST(OmmaStitch, StalledCameraIsDroppedWithAWarning) {
  GstElement* p = parse(
      "ommastitch name=s rig=thesis-24 size=256x256 stall-timeout=1 ! appsink name=out sync=false "
      "max-buffers=2 drop=true" +
      test_branches(kCameras, [](int i) {
        return i == 3 ? "videotestsrc is-live=true pattern=ball ! "
                        "video/x-raw,width=250,height=250,framerate=30/1 ! valve name=v drop=false"
                      : std::string();
      }));
  ASSERT_TRUE(p);
  gst_element_set_state(p, GST_STATE_PLAYING);
  BusLog log;
  pump(p, log, 5, [&] { return !log.stats.empty() && log.stats.back()["cameras-live"] == kCameras; });
  ASSERT_TRUE(log.errors.empty()) << joined(log.errors);
  ASSERT_FALSE(log.stats.empty());
  GstElement* valve = by_name(p, "v");
  g_object_set(valve, "drop", TRUE, nullptr);
  gst_object_unref(valve);
  const auto t_drop = std::chrono::steady_clock::now();
  pump(p, log, 4, [&] { return !log.warnings.empty(); });
  const double warned_after = since(t_drop);
  EXPECT_TRUE(log.errors.empty()) << joined(log.errors);
  ASSERT_FALSE(log.warnings.empty());
  EXPECT_LT(warned_after, 1.0 + 1.0);
  EXPECT_GT(warned_after, 0.9);
  EXPECT_TRUE(has(log.warnings.front(), "ommastitch: camera 3 (sink_3) dropped: stalled: no buffer for 1 s;"))
      << joined(log.warnings);
  log.stats.clear();
  pump(p, log, 3, [&] { return !log.stats.empty(); });
  ASSERT_FALSE(log.stats.empty());
  EXPECT_EQ(log.stats.back()["cameras-live"], kCameras - 1);
  EXPECT_EQ(log.stats.back()["dropped-cameras"], 1);
  GstElement* sink = by_name(p, "out");
  EXPECT_EQ(pull_pts(sink, 3, 3).size(), 3u) << "output after the stall";
  gst_object_unref(sink);
  EXPECT_LT(stop_pipeline(p), 2.0);
  gst_object_unref(p);
  std::printf("stall warned %.2f s after the valve closed (stall-timeout 1 s)\n", warned_after);
}

// A camera dropped mid-stream is reported once, also when the stream then ends (EOS on every pad).
TEST(OmmaStitch, DroppedCameraIsReportedOnceAtTheEnd) {
  GstElement* p = parse("ommastitch name=s rig=thesis-24 size=128x128 stall-timeout=0.5 ! fakesink" +
                        test_branches(kCameras, [](int i) {
                          return i == 3 ? kBall + " ! valve name=v drop=false"
                                        : "videotestsrc pattern=ball num-buffers=75 ! "
                                          "video/x-raw,width=250,height=250,framerate=30/1";
                        }));
  ASSERT_TRUE(p);
  gst_element_set_state(p, GST_STATE_PLAYING);
  BusLog log;
  pump(p, log, 5, [&] { return !log.stats.empty(); });
  ASSERT_FALSE(log.stats.empty());
  GstElement* valve = by_name(p, "v");
  g_object_set(valve, "drop", TRUE, nullptr);
  gst_object_unref(valve);
  pump(p, log, 6);
  EXPECT_TRUE(log.eos);
  EXPECT_TRUE(log.errors.empty()) << joined(log.errors);
  ASSERT_EQ(log.warnings.size(), 1u) << joined(log.warnings);
  EXPECT_TRUE(has(log.warnings.front(), "camera 3 (sink_3) dropped: stalled: no buffer for 0.5 s"))
      << joined(log.warnings);
  EXPECT_LT(stop_pipeline(p), 2.0);
  gst_object_unref(p);
}

// The engine failing (no camera ever delivers: no panorama can be rendered) is an error on the bus,
// and the pipeline goes to NULL at once.
TEST(OmmaStitch, EngineFailureIsAnErrorAndStops) {
  GstElement* p = parse("ommastitch name=s rig=thesis-24 size=128x128 first-frame-timeout=0.5 ! fakesink" +
                        test_branches(kCameras, [](int) { return kBall + " ! valve drop=true"; }));
  ASSERT_TRUE(p);
  const auto t0 = std::chrono::steady_clock::now();
  gst_element_set_state(p, GST_STATE_PLAYING);
  BusLog log;
  pump(p, log, 5);
  const double after = since(t0);
  ASSERT_FALSE(log.errors.empty()) << joined(log.warnings);
  EXPECT_TRUE(has(log.errors.front(), "ommastitch: no panorama was rendered: no frame within 0.5"))
      << joined(log.errors);
  EXPECT_LT(after, 3.0);
  EXPECT_LT(stop_pipeline(p), 1.0);
  gst_object_unref(p);
  // A size the projection cannot have: an error when going to PAUSED, naming the setting.
  GstElement* q = parse("ommastitch name=s rig=thesis-24 size=0x0 ! fakesink" + test_branches(kCameras));
  ASSERT_TRUE(q);
  EXPECT_EQ(gst_element_set_state(q, GST_STATE_PLAYING), GST_STATE_CHANGE_FAILURE);
  BusLog qlog;
  pump(q, qlog, 2);
  ASSERT_FALSE(qlog.errors.empty());
  EXPECT_TRUE(has(qlog.errors.front(), "ommastitch: ")) << joined(qlog.errors);
  EXPECT_LT(stop_pipeline(q), 1.0);
  gst_object_unref(q);
  std::printf("engine error after %.2f s; size=0x0: %s\n", after, qlog.errors.front().c_str());
}

// PLAYING -> PAUSED -> PLAYING: output resumes, PTS keep increasing, nothing is pushed while paused.
TEST(OmmaStitch, PauseAndResumeKeepsPtsIncreasing) {
  GstElement* p =
      parse("ommastitch name=s rig=thesis-24 size=256x256 ! appsink name=out sync=false max-buffers=1000" +
            test_branches(kCameras));
  ASSERT_TRUE(p);
  GstElement* sink = by_name(p, "out");
  gst_element_set_state(p, GST_STATE_PLAYING);
  std::vector<GstClockTime> pts = pull_pts(sink, 10, 5);
  ASSERT_EQ(pts.size(), 10u);
  for (int round = 0; round < 2; ++round) {
    EXPECT_NE(gst_element_set_state(p, GST_STATE_PAUSED), GST_STATE_CHANGE_FAILURE);
    EXPECT_NE(gst_element_get_state(p, nullptr, nullptr, 2 * GST_SECOND), GST_STATE_CHANGE_FAILURE);
    g_usleep(500000);
    // At most the one panorama that was on its way when the pause came.
    const std::vector<GstClockTime> during = pull_pts(sink, 100, 0.2);
    EXPECT_LE(during.size(), 2u) << "round " << round;
    pts.insert(pts.end(), during.begin(), during.end());
    EXPECT_NE(gst_element_set_state(p, GST_STATE_PLAYING), GST_STATE_CHANGE_FAILURE);
    const std::vector<GstClockTime> after = pull_pts(sink, 10, 5);
    EXPECT_EQ(after.size(), 10u) << "round " << round;
    pts.insert(pts.end(), after.begin(), after.end());
  }
  BusLog log;
  pump(p, log, 0.1);
  EXPECT_TRUE(log.errors.empty()) << joined(log.errors);
  for (size_t i = 1; i < pts.size(); ++i) EXPECT_GT(pts[i], pts[i - 1]) << "buffer " << i;
  gst_object_unref(sink);
  EXPECT_LT(stop_pipeline(p), 2.0);
  gst_object_unref(p);
}

// A flushing seek of one camera's source (flush-start/flush-stop through its sink pad) and a
// flushing seek of the whole pipeline (refused: the panorama is live) neither block nor fail.
TEST(OmmaStitch, FlushingSeeksDoNotBlock) {
  GstElement* p = parse(
      "ommastitch name=s rig=thesis-24 size=256x256 stall-timeout=2 ! appsink name=out sync=false "
      "max-buffers=2 drop=true" +
      test_branches(kCameras, [](int i) {
        return i == 6 ? "videotestsrc name=v6 pattern=ball ! video/x-raw,width=250,height=250,framerate=30/1"
                      : std::string();
      }));
  ASSERT_TRUE(p);
  GstElement* sink = by_name(p, "out");
  gst_element_set_state(p, GST_STATE_PLAYING);
  ASSERT_EQ(pull_pts(sink, 3, 5).size(), 3u);
  GstElement* v6 = by_name(p, "v6");
  for (int i = 0; i < 3; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    EXPECT_TRUE(gst_element_seek_simple(v6, GST_FORMAT_TIME,
                                        GstSeekFlags(GST_SEEK_FLAG_FLUSH | GST_SEEK_FLAG_KEY_UNIT), 0));
    EXPECT_LT(since(t0), 1.0) << "camera seek " << i;
    g_usleep(200000);
  }
  gst_object_unref(v6);
  // Flush events straight into a sink pad (as an upstream flushing seek sends them).
  GstElement* s = by_name(p, "s");
  GstPad* sink9 = gst_element_get_static_pad(s, "sink_9");
  ASSERT_TRUE(sink9);
  EXPECT_TRUE(gst_pad_send_event(sink9, gst_event_new_flush_start()));
  EXPECT_TRUE(gst_pad_send_event(sink9, gst_event_new_flush_stop(TRUE)));
  gst_object_unref(sink9);
  gst_object_unref(s);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_FALSE(gst_element_seek_simple(p, GST_FORMAT_TIME, GST_SEEK_FLAG_FLUSH, 0));
  EXPECT_LT(since(t0), 1.0) << "pipeline seek";
  EXPECT_EQ(pull_pts(sink, 5, 3).size(), 5u) << "output after the seeks";
  BusLog log;
  pump(p, log, 1);
  EXPECT_TRUE(log.errors.empty()) << joined(log.errors);
  EXPECT_TRUE(log.warnings.empty()) << joined(log.warnings);
  ASSERT_FALSE(log.stats.empty());
  EXPECT_EQ(log.stats.back()["cameras-live"], kCameras);
  gst_object_unref(sink);
  EXPECT_LT(stop_pipeline(p), 2.0);
  gst_object_unref(p);
}

// Caps changing mid-stream: another format (BGR -> I420) is converted on; another size is an error
// naming the pad, the camera and both sizes.
TEST(OmmaStitch, CapsChangeMidStream) {
  GstElement* p = parse(
      "ommastitch name=s rig=thesis-24 size=256x256 ! appsink name=out sync=false max-buffers=2 drop=true" +
      test_branches(kCameras, [](int i) {
        return i == 2 ? "videotestsrc pattern=ball ! capsfilter name=cf "
                        "caps=video/x-raw,format=BGR,width=250,height=250,framerate=30/1"
                      : std::string();
      }));
  ASSERT_TRUE(p);
  GstElement* sink = by_name(p, "out");
  GstElement* cf = by_name(p, "cf");
  GstElement* s = by_name(p, "s");
  GstPad* sink2 = gst_element_get_static_pad(s, "sink_2");
  auto format_of_sink2 = [&] {
    std::string f;
    if (GstCaps* c = gst_pad_get_current_caps(sink2)) {
      if (const char* v = gst_structure_get_string(gst_caps_get_structure(c, 0), "format")) f = v;
      gst_caps_unref(c);
    }
    return f;
  };
  gst_element_set_state(p, GST_STATE_PLAYING);
  ASSERT_EQ(pull_pts(sink, 3, 5).size(), 3u);
  EXPECT_EQ(format_of_sink2(), "BGR");
  GstCaps* i420 = gst_caps_from_string("video/x-raw,format=I420,width=250,height=250,framerate=30/1");
  g_object_set(cf, "caps", i420, nullptr);
  gst_caps_unref(i420);
  BusLog log;
  pump(p, log, 1.5);
  EXPECT_TRUE(log.errors.empty()) << joined(log.errors);
  EXPECT_TRUE(log.warnings.empty()) << joined(log.warnings);
  EXPECT_EQ(format_of_sink2(), "I420");
  EXPECT_EQ(pull_pts(sink, 3, 3).size(), 3u) << "output after the format change";
  ASSERT_FALSE(log.stats.empty());
  EXPECT_EQ(log.stats.back()["cameras-live"], kCameras);
  GstCaps* small = gst_caps_from_string("video/x-raw,format=I420,width=320,height=240,framerate=30/1");
  g_object_set(cf, "caps", small, nullptr);
  gst_caps_unref(small);
  pump(p, log, 3);
  ASSERT_FALSE(log.errors.empty());
  EXPECT_TRUE(has(log.errors.front(), "sink_2 (camera 2) gets 320x240 frames, the rig's camera is 250x250"))
      << joined(log.errors);
  gst_object_unref(sink2);
  gst_object_unref(s);
  gst_object_unref(cf);
  gst_object_unref(sink);
  EXPECT_LT(stop_pipeline(p), 2.0);
  gst_object_unref(p);
}

// fps=0: a panorama whenever a camera has a new frame; caps framerate 0/1, no DURATION; EOS at the
// end of every camera.
TEST(OmmaStitch, FpsZeroRendersOnNewFrames) {
  GstElement* p = parse(
      "ommastitch name=s rig=thesis-24 size=128x128 fps=0 ! appsink name=out sync=false max-buffers=1000 "
      "wait-on-eos=false" +
      still_branches(60));
  ASSERT_TRUE(p);
  GstElement* sink = by_name(p, "out");
  gst_element_set_state(p, GST_STATE_PLAYING);
  BusLog log;
  pump(p, log, 6);
  EXPECT_TRUE(log.errors.empty()) << joined(log.errors);
  EXPECT_TRUE(log.eos);
  std::vector<GstClockTime> pts;
  gint fps_n = -1, fps_d = -1;
  GstClockTime duration = 0;
  while (GstSample* sample = gst_app_sink_try_pull_sample(GST_APP_SINK(sink), 0)) {
    gst_structure_get_fraction(gst_caps_get_structure(gst_sample_get_caps(sample), 0), "framerate", &fps_n,
                               &fps_d);
    pts.push_back(GST_BUFFER_PTS(gst_sample_get_buffer(sample)));
    duration = GST_BUFFER_DURATION(gst_sample_get_buffer(sample));
    gst_sample_unref(sample);
  }
  gst_object_unref(sink);
  EXPECT_LT(stop_pipeline(p), 2.0);
  gst_object_unref(p);
  // 60 stills per camera at 30/1, two seconds (less the map compile): many panoramas, at most one
  // per camera frame.
  EXPECT_GE(pts.size(), 10u);
  EXPECT_LE(pts.size(), 60u * kCameras);
  EXPECT_EQ(fps_n, 0);
  EXPECT_EQ(fps_d, 1);
  EXPECT_EQ(duration, GST_CLOCK_TIME_NONE);
  for (size_t i = 1; i < pts.size(); ++i) EXPECT_GT(pts[i], pts[i - 1]);
  std::printf("fps=0: %zu panoramas\n", pts.size());
}

// Pads while the element runs: a request is refused with a warning saying why; a released pad ends
// its camera (a warning, the panorama goes on with 23) and the pipeline still stops at once.
TEST(OmmaStitch, PadsRequestedOrReleasedWhileRunning) {
  GstElement* p = parse(
      "ommastitch name=s rig=thesis-24 size=256x256 ! appsink name=out sync=false max-buffers=2 drop=true" +
      test_branches(kCameras, [](int i) { return i == 11 ? kBall + " ! queue name=q11" : std::string(); }));
  ASSERT_TRUE(p);
  GstElement* sink = by_name(p, "out");
  GstElement* s = by_name(p, "s");
  gst_element_set_state(p, GST_STATE_PLAYING);
  ASSERT_EQ(pull_pts(sink, 3, 5).size(), 3u);
  EXPECT_EQ(gst_element_request_pad_simple(s, "sink_24"), nullptr);
  BusLog log;
  pump(p, log, 1, [&] { return !log.warnings.empty(); });
  ASSERT_FALSE(log.warnings.empty());
  EXPECT_TRUE(has(log.warnings.front(),
                  "ommastitch: sink_24 refused: sink pads can be requested in NULL or "
                  "READY only"))
      << joined(log.warnings);
  log.warnings.clear();
  GstPad* sink11 = gst_element_get_static_pad(s, "sink_11");
  ASSERT_TRUE(sink11);
  GstElement* q11 = by_name(p, "q11");
  GstPad* q11src = gst_element_get_static_pad(q11, "src");
  gst_pad_unlink(q11src, sink11);
  const auto t0 = std::chrono::steady_clock::now();
  gst_element_release_request_pad(s, sink11);
  EXPECT_LT(since(t0), 1.0);
  gst_object_unref(sink11);
  pump(p, log, 3, [&] {
    return !log.warnings.empty() && !log.stats.empty() && log.stats.back()["cameras-live"] == kCameras - 1;
  });
  ASSERT_FALSE(log.warnings.empty());
  EXPECT_TRUE(has(log.warnings.front(), "ommastitch: camera 11 (sink_11) dropped: its sink pad was released"))
      << joined(log.warnings);
  ASSERT_FALSE(log.stats.empty());
  EXPECT_EQ(log.stats.back()["cameras-live"], kCameras - 1);
  EXPECT_EQ(pull_pts(sink, 3, 3).size(), 3u) << "output after the release";
  // (The branch's source now pushes into an unlinked pad: not-linked, an error from it.)
  gst_object_unref(q11src);
  gst_object_unref(q11);
  gst_object_unref(s);
  gst_object_unref(sink);
  EXPECT_LT(stop_pipeline(p), 2.0);
  gst_object_unref(p);
}

// NULL right after PLAYING (the engine compiling its map) and PLAYING -> READY -> PLAYING: no hang,
// output again after the restart.
TEST(OmmaStitch, StateChangesWhileTheMapCompiles) {
  GstElement* p = parse(
      "ommastitch name=s rig=thesis-24 size=1024x1024 ! appsink name=out sync=false max-buffers=2 drop=true" +
      test_branches(kCameras));
  ASSERT_TRUE(p);
  gst_element_set_state(p, GST_STATE_PLAYING);
  const double to_null = stop_pipeline(p);
  EXPECT_LT(to_null, 5.0);
  gst_element_set_state(p, GST_STATE_PLAYING);
  g_usleep(100000);
  const auto t0 = std::chrono::steady_clock::now();
  gst_element_set_state(p, GST_STATE_READY);
  const double to_ready = since(t0);
  EXPECT_LT(to_ready, 5.0);
  gst_element_set_state(p, GST_STATE_PLAYING);
  GstElement* sink = by_name(p, "out");
  EXPECT_EQ(pull_pts(sink, 3, 8).size(), 3u) << "output after READY -> PLAYING";
  gst_object_unref(sink);
  BusLog log;
  pump(p, log, 0.1);
  EXPECT_TRUE(log.errors.empty()) << joined(log.errors);
  EXPECT_LT(stop_pipeline(p), 2.0);
  gst_object_unref(p);
  std::printf("1024x1024: NULL during the map compile in %.2f s, READY in %.2f s\n", to_null, to_ready);
}

// omma's log: into the GStreamer debug log in gst-launch-1.0 (stdout stays the pipeline's), left on
// stdout with OMMA_GST_LOG=keep and in a process named omma.
TEST(OmmaStitch, LogRedirectOnlyWhereTheHostHasNoSay) {
  const fs::path dir = tmp_dir("log");
  const std::string launch =
      "gst-launch-1.0 -q ommastitch name=s rig=thesis-24 size=128x128 ! fakesink" + still_branches(3);
  std::error_code ec;
  fs::create_symlink(g_find_program_in_path("gst-launch-1.0"), dir / "omma", ec);
  ASSERT_FALSE(ec) << ec.message();
  auto stdout_of = [&](const std::string& cmd) {
    const CmdResult r = run_cmd("{ " + cmd + " 2>/dev/null; }");
    EXPECT_EQ(r.rc, 0) << cmd << "\n" << r.out;
    return r.out;
  };
  const std::string plain = stdout_of("env -u OMMA_GST_LOG " + launch);
  EXPECT_FALSE(has(plain, "map 128x128")) << plain;
  const std::string keep = stdout_of("OMMA_GST_LOG=keep " + launch);
  EXPECT_TRUE(has(keep, "map 128x128 linear")) << keep;
  const std::string as_omma = stdout_of("env -u OMMA_GST_LOG " + (dir / "omma").string() + launch.substr(14));
  EXPECT_TRUE(has(as_omma, "map 128x128 linear")) << as_omma;
  const CmdResult gst_log = run_cmd("{ OMMA_GST_LOG=gst GST_DEBUG=ommastitch:4 " + (dir / "omma").string() +
                                    launch.substr(14) + " 2>&1 >/dev/null; }");
  EXPECT_TRUE(has(gst_log.out, "map 128x128 linear")) << gst_log.out;
}

int main(int argc, char** argv) {
  // The build's plugin, and a registry in the build folder (never $HOME's).
  setenv("GST_PLUGIN_PATH", OMMA_GST_PLUGIN_DIR, 0);
  setenv("GST_REGISTRY", OMMA_GST_REGISTRY, 0);
  gst_init(&argc, &argv);
  testing::InitGoogleTest(&argc, argv);
  const int rc = RUN_ALL_TESTS();
  std::error_code ec;
  fs::remove_all(fs::path(OMMA_TEST_TMP) / ("frames-" + std::to_string(getpid())), ec);
  return rc;
}
