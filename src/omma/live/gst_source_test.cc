// gst:PIPELINE camera sources (gst.h): colours and sizes read back, conversion, the end of the
// stream and looping, parse and runtime errors, stalls, stopping mid-stream, many pipelines at once
// and a failing gst camera dropped by the engine.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "omma/live/engine.h"
#include "omma/live/gst.h"
#include "omma/testing/synthetic.h"

namespace omma::live {
namespace {

using Seconds = std::chrono::duration<double>;

#define SKIP_WITHOUT_GSTREAMER()                 \
  do {                                           \
    if (!OMMA_HAVE_GSTREAMER) {                  \
      GTEST_SKIP() << "built without GStreamer"; \
    }                                            \
  } while (0)

RigCamera camera(int w, int h, int id = 3) {
  RigCamera cam;
  cam.id = id;
  cam.in.width = w;
  cam.in.height = h;
  return cam;
}

SourceOptions quick(bool loop = false) {
  SourceOptions o;
  o.stall_s = 1;
  o.loop = loop;
  return o;
}

std::string what_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const SourceError& e) {
    return e.what();
  }
  return "(no SourceError)";
}

bool has(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

TEST(GstSource, WithoutGStreamerSaysSo) {
  if (OMMA_HAVE_GSTREAMER) GTEST_SKIP() << "built with GStreamer";
  const std::string w = what_of([] { open_gst_source("videotestsrc", camera(8, 8), quick()); });
  EXPECT_TRUE(has(w, "without GStreamer")) << w;
}

TEST(GstSource, SolidColourPipelineGivesBgrFramesOfItsColourAndItsRate) {
  SKIP_WITHOUT_GSTREAMER();
  // foreground-color is 0xAARRGGBB: R = 0x20, G = 0x80, B = 0xE0.
  auto src = open_gst_source(
      "videotestsrc pattern=solid-color foreground-color=0xff2080e0 ! "
      "video/x-raw,width=24,height=16,framerate=25/1",
      camera(24, 16), quick());
  EXPECT_EQ(src->describe().rfind("gst:videotestsrc", 0), 0u) << src->describe();
  for (int i = 0; i < 3; ++i) {
    cv::Mat f;
    ASSERT_TRUE(src->read(f));
    ASSERT_EQ(f.type(), CV_8UC3);
    ASSERT_EQ(f.cols, 24);
    ASSERT_EQ(f.rows, 16);
    const cv::Scalar m = cv::mean(f);
    // videotestsrc draws in I420/AYUV and videoconvert turns it into BGR: a few levels of rounding.
    EXPECT_NEAR(m[0], 0xE0, 3);
    EXPECT_NEAR(m[1], 0x80, 3);
    EXPECT_NEAR(m[2], 0x20, 3);
    const cv::Vec3b corner = f.at<cv::Vec3b>(15, 23);
    EXPECT_NEAR(corner[0], 0xE0, 3);
    EXPECT_NEAR(corner[2], 0x20, 3);
  }
  EXPECT_DOUBLE_EQ(src->fps(), 25.0);
}

TEST(GstSource, OddWidthI420IsConvertedRespectingTheStride) {
  SKIP_WITHOUT_GSTREAMER();
  // 13 px wide BGR rows are 39 bytes, padded to 40 by GStreamer: the copy must follow the stride.
  auto src = open_gst_source(
      "videotestsrc pattern=solid-color foreground-color=0xff00ff00 ! "
      "video/x-raw,format=I420,width=13,height=7",
      camera(13, 7), quick());
  cv::Mat f;
  ASSERT_TRUE(src->read(f));
  ASSERT_EQ(f.size(), cv::Size(13, 7));
  for (int y = 0; y < f.rows; ++y)
    for (int x = 0; x < f.cols; ++x) {
      const cv::Vec3b p = f.at<cv::Vec3b>(y, x);
      ASSERT_LE(p[0], 6) << x << "," << y;
      ASSERT_GE(p[1], 248) << x << "," << y;
      ASSERT_LE(p[2], 6) << x << "," << y;
    }
}

TEST(GstSource, NumBuffersEndsAfterThatManyFrames) {
  SKIP_WITHOUT_GSTREAMER();
  // sync=true paces the appsink: every buffer is kept (max-buffers=1 drops only when late).
  auto src = open_gst_source("videotestsrc num-buffers=7 ! video/x-raw,width=8,height=8,framerate=200/1",
                             camera(8, 8), quick());
  int n = 0;
  cv::Mat f;
  while (n < 100 && src->read(f)) ++n;
  EXPECT_EQ(n, 7);
  EXPECT_FALSE(src->read(f));  // ended stays ended
}

TEST(GstSource, LoopStartsAgainAtTheEnd) {
  SKIP_WITHOUT_GSTREAMER();
  auto src = open_gst_source("videotestsrc num-buffers=5 ! video/x-raw,width=8,height=8,framerate=200/1",
                             camera(8, 8), quick(/*loop=*/true));
  int n = 0;
  cv::Mat f;
  while (n < 17 && src->read(f)) ++n;
  EXPECT_EQ(n, 17);
  // A seekable pipeline (a still image, frozen for 3 frames) goes round by seeking back to 0.
  const std::string png =
      (std::filesystem::temp_directory_path() / ("omma-gst-loop-" + std::to_string(::getpid()) + ".png"))
          .string();
  ASSERT_TRUE(cv::imwrite(png, cv::Mat(6, 10, CV_8UC3, cv::Scalar(10, 200, 30))));
  src = open_gst_source(
      "filesrc location=" + png + " ! pngdec ! imagefreeze num-buffers=3 ! video/x-raw,framerate=100/1",
      camera(10, 6), quick(/*loop=*/true));
  for (n = 0; n < 11 && src->read(f); ++n) {
    ASSERT_EQ(f.size(), cv::Size(10, 6));
    EXPECT_EQ(f.at<cv::Vec3b>(5, 9), cv::Vec3b(10, 200, 30));
  }
  EXPECT_EQ(n, 11);
  src.reset();
  std::filesystem::remove(png);
}

TEST(GstSource, ParseErrorNamesTheElement) {
  SKIP_WITHOUT_GSTREAMER();
  const std::string w =
      what_of([] { open_gst_source("videotestsrc ! nosuchelement42", camera(8, 8), quick()); });
  EXPECT_TRUE(has(w, "nosuchelement42")) << w;
  EXPECT_TRUE(has(w, "gst:videotestsrc")) << w;
  const std::string e = what_of([] { open_gst_source("  ", camera(8, 8), quick()); });
  EXPECT_TRUE(has(e, "empty pipeline")) << e;
}

TEST(GstSource, RuntimeErrorFailsReadWithTheElementAndTheMessage) {
  SKIP_WITHOUT_GSTREAMER();
  auto src =
      open_gst_source("filesrc location=/nonexistent/omma.png ! pngdec ! imagefreeze", camera(8, 8), quick());
  const auto t0 = std::chrono::steady_clock::now();
  const std::string w = what_of([&] {
    cv::Mat f;
    src->read(f);
  });
  EXPECT_LT(Seconds(std::chrono::steady_clock::now() - t0).count(), 0.9);  // the error, not a stall
  EXPECT_TRUE(has(w, "element 'filesrc")) << w;
  EXPECT_TRUE(has(w, "/nonexistent/omma.png")) << w;
}

TEST(GstSource, StallFailsWithinStallTime) {
  SKIP_WITHOUT_GSTREAMER();
  auto src = open_gst_source("videotestsrc is-live=true ! video/x-raw,width=8,height=8 ! valve drop=true",
                             camera(8, 8), quick());
  const auto t0 = std::chrono::steady_clock::now();
  const std::string w = what_of([&] {
    cv::Mat f;
    src->read(f);
  });
  const double s = Seconds(std::chrono::steady_clock::now() - t0).count();
  std::printf("  stall reported after %.2f s (stall_s 1)\n", s);
  EXPECT_TRUE(has(w, "stalled: no frame for 1 s")) << w;
  EXPECT_GE(s, 0.9);
  EXPECT_LT(s, 2.0);
}

TEST(GstSource, WrongSizeNamesBothSizes) {
  SKIP_WITHOUT_GSTREAMER();
  auto src = open_gst_source("videotestsrc ! video/x-raw,width=20,height=10", camera(16, 12, 5), quick());
  const std::string w = what_of([&] {
    cv::Mat f;
    src->read(f);
  });
  EXPECT_TRUE(has(w, "20x10")) << w;
  EXPECT_TRUE(has(w, "16x12")) << w;
  EXPECT_TRUE(has(w, "camera 5")) << w;
}

TEST(GstSource, DestroyingMidStreamReturnsPromptly) {
  SKIP_WITHOUT_GSTREAMER();
  for (const char* p :
       {"videotestsrc is-live=true ! video/x-raw,width=8,height=8,framerate=30/1",
        "videotestsrc is-live=true ! video/x-raw,width=8,height=8 ! valve drop=true",
        "videotestsrc ! video/x-raw,width=8,height=8,framerate=5/1 ! queue ! identity sleep-time=400000"}) {
    auto src = open_gst_source(p, camera(8, 8), quick());
    cv::Mat f;
    if (!has(p, "valve")) {
      ASSERT_TRUE(src->read(f)) << p;
    }
    const auto t0 = std::chrono::steady_clock::now();
    src.reset();
    const double s = Seconds(std::chrono::steady_clock::now() - t0).count();
    std::printf("  stopped in %.3f s: %s\n", s, p);
    EXPECT_LT(s, 1.0) << p;
  }
}

TEST(GstSource, DestroyingAStuckPipelineDoesNotHang) {
  SKIP_WITHOUT_GSTREAMER();
  // The streaming thread sleeps 4 s in identity: the pipeline cannot stop before; the destructor
  // gives up waiting after 2 s and leaves it to stop in the background.
  auto src = open_gst_source("videotestsrc ! video/x-raw,width=8,height=8 ! identity sleep-time=4000000",
                             camera(8, 8), quick());
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const auto t0 = std::chrono::steady_clock::now();
  src.reset();
  const double s = Seconds(std::chrono::steady_clock::now() - t0).count();
  std::printf("  a stuck pipeline: the destructor returned after %.2f s\n", s);
  EXPECT_LT(s, 2.5);
}

TEST(GstSource, TwentyFourPipelinesAtOnce) {
  SKIP_WITHOUT_GSTREAMER();
  init_gstreamer();
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<std::unique_ptr<CameraSource>> srcs;
  for (int c = 0; c < 24; ++c)
    srcs.push_back(open_gst_source(
        "videotestsrc is-live=true pattern=solid-color foreground-color=" + std::to_string(0xff000000u + c) +
            " ! video/x-raw,width=16,height=16,framerate=30/1",
        camera(16, 16, c), quick()));
  const double open_s = Seconds(std::chrono::steady_clock::now() - t0).count();
  for (int c = 0; c < 24; ++c) {
    cv::Mat f;
    ASSERT_TRUE(srcs[c]->read(f)) << c;
    EXPECT_NEAR(cv::mean(f)[0], c, 2) << c;  // each camera its own pipeline: its own colour (blue)
  }
  const double first_s = Seconds(std::chrono::steady_clock::now() - t0).count();
  srcs.clear();
  const double all_s = Seconds(std::chrono::steady_clock::now() - t0).count();
  std::printf("  24 pipelines: opened in %.3f s, a frame from each by %.3f s, stopped by %.3f s\n", open_s,
              first_s, all_s);
  EXPECT_LT(open_s, 3.0);
}

TEST(GstSource, EngineDropsAFailingGstCameraAndGoesOn) {
  SKIP_WITHOUT_GSTREAMER();
  const Rig rig = testing::test_rig_24(32, 32);
  std::vector<std::string> specs;
  const int victim = 5;
  for (size_t c = 0; c < rig.cameras.size(); ++c)
    specs.push_back(int(c) == victim
                        ? "gst:filesrc location=/nonexistent.png ! pngdec ! imagefreeze"
                        : "gst:videotestsrc is-live=true ! video/x-raw,width=32,height=32,framerate=30/1");
  SourceOptions so = quick();
  auto sources = open_sources(rig, specs, so);
  std::vector<std::unique_ptr<Sink>> sinks;
  EngineOptions opt;
  opt.map.grid = PanoGrid{Projection::kVr180, 64, 64};
  opt.map.method = pano::Method::kNearest;
  opt.fps = 30;
  opt.duration_s = 1.5;
  const EngineSummary st = run_engine(rig, std::move(sources), sinks, opt);
  EXPECT_GT(st.frames, 10);
  EXPECT_EQ(st.cameras_live, 23);
  ASSERT_EQ(st.dropped_cameras.size(), 1u);
  EXPECT_EQ(st.dropped_cameras[0].index, victim);
  EXPECT_TRUE(st.dropped_cameras[0].remapped);
  EXPECT_TRUE(has(st.dropped_cameras[0].reason, "No such file")) << st.dropped_cameras[0].reason;
  EXPECT_GT(st.camera_fps_min, 20);
  std::printf("  %ld panoramas, cameras %.1f..%.1f fps\n", st.frames, st.camera_fps_min, st.camera_fps_max);
}

}  // namespace
}  // namespace omma::live
