// CLI tests of gst:PIPELINE cameras in `omma run` (src/omma/live/gst.h): the same panorama as the
// frames folder the pipelines read, many live test sources at their rate, a failing and a stalling
// camera dropped while the run goes on, and a pipeline that does not parse.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "omma/core/frames.h"
#include "omma/core/rig.h"
#include "omma/testing/synthetic.h"
#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {
namespace fs = std::filesystem;

#define SKIP_WITHOUT_GSTREAMER()                          \
  do {                                                    \
    if (!OMMA_GSTREAMER_BUILT) {                          \
      GTEST_SKIP() << "omma was built without GStreamer"; \
    }                                                     \
  } while (0)

// The last file of a png: sink's folder (frame_000000.png ...), read as BGR.
cv::Mat last_png(const fs::path& dir) {
  std::vector<fs::path> files;
  if (fs::is_directory(dir))
    for (const auto& e : fs::directory_iterator(dir)) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files.empty() ? cv::Mat() : cv::imread(files.back().string(), cv::IMREAD_COLOR);
}

fs::path write_rig_24(const fs::path& dir, int size) {
  const fs::path p = dir / "rig.json";
  save_rig(testing::test_rig_24(size, size), p);
  return p;
}

TEST(GstSourceCli, PipelinesReadingAFramesFolderGiveItsPanorama) {
  SKIP_WITHOUT_GSTREAMER();
  const fs::path d = louvre_frames_folder("gst-frames");
  ASSERT_TRUE(fs::exists(d / frame_filename(0))) << "frames.h names cam_XX.png";
  const std::string base =
      "run --rig " + (d / "rig.json").string() + " --size 128x128 --frames 3 --no-cache --json";
  const RunResult a =
      run_omma(base + " --source frames:" + d.string() + " --sink png:" + (d / "a").string(), 60);
  ASSERT_EQ(a.exit_code, 0) << a.err;
  const auto t0 = std::chrono::steady_clock::now();
  const RunResult b = run_omma(base + " --source 'gst:filesrc location=" + d.string() +
                                   "/cam_{id}.png ! pngdec ! imagefreeze num-buffers=30'" +
                                   " --sink png:" + (d / "b").string(),
                               60);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_EQ(b.exit_code, 0) << b.err;
  EXPECT_EQ(b.json()["frames"], 3);
  EXPECT_EQ(b.json()["dropped_cameras"].size(), 0u) << b.out;
  const cv::Mat pa = last_png(d / "a"), pb = last_png(d / "b");
  ASSERT_FALSE(pa.empty());
  ASSERT_EQ(pa.size(), pb.size());
  EXPECT_GT(cv::mean(pa)[1], 20);  // a panorama, not black
  const double db = cv::PSNR(pa, pb);
  std::printf("  frames: vs gst: (%d cameras) PSNR %.1f dB, max difference %.0f, gst run %.2f s\n",
              int(load_rig(d / "rig.json").cameras.size()), db, cv::norm(pa, pb, cv::NORM_INF), s);
  EXPECT_GE(db, 50.0);
  fs::remove_all(d);
}

TEST(GstSourceCli, ManyLiveTestSourcesRunAtTheirRate) {
  SKIP_WITHOUT_GSTREAMER();
  const fs::path d = temp_dir("gst-many");
  const fs::path rig = write_rig_24(d, 48);
  const RunResult r = run_omma("run --rig " + rig.string() +
                                   " --source 'gst:videotestsrc name=cam{id} pattern=ball is-live=true ! "
                                   "video/x-raw,width=48,height=48,framerate=30/1'"
                                   " --size 128x128 --method nn --duration 2 --no-cache --json",
                               60);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = r.json();
  std::printf("  24 videotestsrc cameras: %ld panoramas in %.2f s, cameras %.1f..%.1f fps, %d live\n",
              j["frames"].get<long>(), j["seconds"].get<double>(), j["camera_fps_min"].get<double>(),
              j["camera_fps_max"].get<double>(), j["cameras_live"].get<int>());
  EXPECT_EQ(j["cameras_live"], 24);
  EXPECT_EQ(j["dropped_cameras"].size(), 0u);
  EXPECT_GT(j["frames"].get<long>(), 20);
  EXPECT_GT(j["camera_fps_min"].get<double>(), 25.0);
  EXPECT_LT(j["camera_fps_max"].get<double>(), 35.0);
  fs::remove_all(d);
}

TEST(GstSourceCli, AFailingAndAStallingPipelineAreDroppedAndTheRunGoesOn) {
  SKIP_WITHOUT_GSTREAMER();
  const fs::path d = temp_dir("gst-fail");
  const fs::path rig = write_rig_24(d, 32);
  std::string sources;
  for (int c = 0; c < 24; ++c) {
    std::string p = "videotestsrc is-live=true ! video/x-raw,width=32,height=32,framerate=30/1";
    if (c == 4) p = "filesrc location=/nonexistent/omma.png ! pngdec ! imagefreeze";
    if (c == 9) p = "videotestsrc is-live=true ! video/x-raw,width=32,height=32 ! valve drop=true";
    sources += " --source 'gst:" + p + "'";
  }
  const RunResult r =
      run_omma("run --rig " + rig.string() + sources +
                   " --size 96x96 --method nn --duration 3 --stall-timeout 1 --no-cache --json",
               60);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = r.json();
  EXPECT_EQ(j["cameras_live"], 22);
  EXPECT_GT(j["frames"].get<long>(), 30);
  bool failed = false, stalled = false;
  for (const auto& dc : j["dropped_cameras"]) {
    const std::string why = dc["reason"];
    std::printf("  camera %d dropped at frame %ld: %s\n", dc["id"].get<int>(), dc["at_frame"].get<long>(),
                why.c_str());
    if (dc["index"] == 4) failed = has(why, "No such file") && has(why, "filesrc");
    if (dc["index"] == 9) stalled = has(why, "stalled: no frame for 1 s");
  }
  EXPECT_TRUE(failed) << r.out;
  EXPECT_TRUE(stalled) << r.out;
  fs::remove_all(d);
}

TEST(GstSourceCli, APipelineThatDoesNotParseIsAClearError) {
  SKIP_WITHOUT_GSTREAMER();
  const fs::path d = temp_dir("gst-parse");
  const fs::path rig = write_rig_24(d, 32);
  const RunResult r =
      run_omma("run --rig " + rig.string() +
                   " --source 'gst:videotestsrc name=cam{id} ! nosuchelement42' --duration 1 --no-cache",
               30);
  expect_error(r, "nosuchelement42", "a pipeline naming an element that does not exist");
  fs::remove_all(d);
}

}  // namespace
}  // namespace omma::test
