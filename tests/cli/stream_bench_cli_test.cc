// CLI test of `omma bench --stream` (src/omma/bench/stream_bench.h): the flash latency through the
// GStreamer element, through rtsp:// and through the live view's MJPEG stream, and the RTSP readers
// that keep the full rate, measured in one short run.
#include <gtest/gtest.h>

#include "tests/cli/cli_util.h"

#ifndef OMMA_GSTREAMER_BUILT
#define OMMA_GSTREAMER_BUILT 0
#endif

namespace omma::test {
namespace {

// Bounds: a flash sample waits for the next camera frame (20 ms at 50 frames/s) and the next
// panorama tick (33 ms at 30/s), then render, encoding and transport; on this 2-core machine the
// medians measured 12-50 ms (element), 80-105 ms (RTSP, x264 frame threads: two frames) and 17-35 ms
// (MJPEG) at 512x512, with the suite's other tests beside them. The bounds leave a loaded CI
// machine room while still catching a path that queues frames (a second of backlog) or stalls.
TEST(StreamBenchCli, FlashLatencyOfElementRtspAndMjpegAndReaders) {
  if (!OMMA_GSTREAMER_BUILT) GTEST_SKIP() << "built without GStreamer";
  const RunResult r = run_omma("bench --stream --quick --max-readers 2 --json", 180);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = r.json();
  for (const char* path : {"element", "rtsp", "mjpeg"}) {
    SCOPED_TRACE(path);
    ASSERT_TRUE(j.contains(path)) << j.dump(1);
    const auto& p = j[path];
    ASSERT_FALSE(p.contains("error")) << p.dump();
    EXPECT_GE(p.value("samples", 0), 2) << p.dump();  // flashes seen (about one a second for 4 s)
    ASSERT_TRUE(p.contains("median_ms")) << p.dump();
    EXPECT_GT(p["median_ms"].get<double>(), 0.0);
    EXPECT_LT(p["median_ms"].get<double>(), std::string(path) == "element" ? 250.0 : 500.0) << p.dump();
  }
  // The element's own statistics (its omma-stats bus message) came through.
  EXPECT_GT(j["element"]["element_stats"].value("fps", 0.0), 20.0) << j["element"].dump();
  EXPECT_GT(j["engine"].value("fps", 0.0), 20.0);  // the engine kept near its 30 panoramas/s
  ASSERT_TRUE(j["readers"].is_array() && !j["readers"].empty());
  EXPECT_GT(j["readers"][0].value("slowest_fps", 0.0), 20.0) << j["readers"].dump();
  EXPECT_GE(j.value("max_readers_full_rate", 0), 1) << j["readers"].dump();
}

}  // namespace
}  // namespace omma::test
