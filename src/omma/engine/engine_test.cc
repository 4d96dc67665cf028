// The live engine: free-running sources, camera drop-out with renormalised weights, sinks
// (issue 5 points 3 and 6).
#include "omma/engine/engine.h"

#include <filesystem>
#include <fstream>
#include <thread>

#include <gtest/gtest.h>
#include <httplib.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "omma/engine/synthetic.h"
#include "omma/isp/isp.h"
#include "omma/isp/photometric.h"
#include "omma/isp/link.h"
#include "omma/sim/render.h"

namespace omma::engine {
namespace {
namespace fs = std::filesystem;

std::unique_ptr<CameraSource> open_one_for_test(const Rig& rig, const std::string& spec) {
  std::vector<std::string> specs(rig.cameras.size(), spec);
  return std::move(open_sources(rig, specs)[0]);
}

struct CaptureSink : Sink {
  cv::Mat last;
  long frames = 0;
  std::vector<cv::Mat> history;
  void write(const cv::Mat& pano, const FrameStore&) override {
    last = pano.clone();
    ++frames;
    if (frames % 5 == 0) history.push_back(last);
  }
  std::string describe() const override { return "capture"; }
};

std::vector<cv::Mat> scene_frames(const Rig& rig) {
  cv::Mat pano = cv::imread(std::string(OMMA_DATA_DIR) + "/lake.jpg", cv::IMREAD_COLOR);
  cv::resize(pano, pano, cv::Size(1440, 720), 0, 0, cv::INTER_AREA);
  return views_of_panorama(rig, pano, 0.0);
}

TEST(EngineRun, KilledCameraIsDroppedAndItsRegionFilledFromNeighbours) {
  const Rig rig = ring_rig_24();
  const auto frames = scene_frames(rig);
  const int victim = 7;
  std::vector<std::unique_ptr<CameraSource>> sources;
  for (size_t c = 0; c < frames.size(); ++c)
    sources.push_back(still_source(frames[c], 200, int(c) == victim ? 20 : 0, /*fail=*/int(c) == victim));
  std::vector<std::unique_ptr<Sink>> sinks;
  sinks.push_back(std::make_unique<CaptureSink>());
  auto* cap = static_cast<CaptureSink*>(sinks[0].get());
  EngineOptions opt;
  opt.map.grid = PanoGrid{Projection::kVr180, 240, 240};
  opt.map.method = pano::Method::kNearest;
  opt.fps = 0;
  opt.duration_s = 2.5;
  const EngineStats st = run_engine(rig, std::move(sources), sinks, opt);
  EXPECT_GT(st.frames, 30);
  ASSERT_EQ(st.dropped_cameras.size(), 1u);
  EXPECT_EQ(st.dropped_cameras[0].index, victim);
  EXPECT_TRUE(st.dropped_cameras[0].remapped);
  EXPECT_NE(st.dropped_cameras[0].reason.find("failure"), std::string::npos);
  // The panorama went on after the drop, and at the end equals the reference without the camera.
  EXPECT_GT(cap->frames, st.dropped_cameras[0].at_frame + 10);
  MapOptions without = opt.map;
  without.active.assign(rig.cameras.size(), true);
  without.active[victim] = false;
  const cv::Mat ref = reference_render(rig, without, frames);
  const double db = psnr_u8(cap->last, ref);
  std::printf("  after dropping camera %d: PSNR vs reference without it %.2f dB, %ld frames, %.0f fps\n",
              victim, db, st.frames, st.fps);
  EXPECT_GE(db, 50.0);
  // The region camera `victim` used to own (nn) is filled, not black.
  MapOptions all = opt.map;
  const CompiledMap full = compile_map(rig, all);
  cv::Mat owned(full.height, full.width, CV_8U, cv::Scalar(0));
  full.visit([&](int col, int row, int n, const MapTap* taps) {
    for (int t = 0; t < n; ++t)
      if (full.layout.camera_at(taps[t].offset) == victim) owned.at<uint8_t>(row, col) = 255;
  });
  ASSERT_GT(cv::countNonZero(owned), 500);
  cv::Mat gray;
  cv::cvtColor(cap->last, gray, cv::COLOR_BGR2GRAY);
  cv::Mat black_in_region = (gray == 0) & owned;
  EXPECT_EQ(cv::countNonZero(black_in_region), 0);
}

// The rig's photometric model is applied as each frame arrives (issue 13 point 5): the panorama
// equals the reference render of the corrected frames, and with photometric = false that of the
// frames as they are.
TEST(EngineRun, PhotometricModelIsAppliedAsFramesArrive) {
  Rig rig = ring_rig_24();
  for (RigCamera& c : rig.cameras) c.photometric = sim::true_photometric(c, sim::CameraEffects{});
  const auto frames = scene_frames(rig);
  for (bool photometric : {true, false}) {
    std::vector<std::unique_ptr<CameraSource>> sources;
    for (const cv::Mat& f : frames) sources.push_back(still_source(f, 100));
    std::vector<std::unique_ptr<Sink>> sinks;
    sinks.push_back(std::make_unique<CaptureSink>());
    auto* cap = static_cast<CaptureSink*>(sinks[0].get());
    EngineOptions opt;
    opt.map.grid = PanoGrid{Projection::kVr180, 200, 200};
    opt.map.method = pano::Method::kLinear;
    opt.fps = 0;
    opt.max_frames = 5;
    opt.photometric = photometric;
    run_engine(rig, std::move(sources), sinks, opt);
    const cv::Mat corrected = reference_render(rig, opt.map, isp::correct_frames(rig, frames));
    const cv::Mat plain = reference_render(rig, opt.map, frames);
    const double db_corrected = psnr_u8(cap->last, corrected), db_plain = psnr_u8(cap->last, plain);
    std::printf("  photometric %d: PSNR vs corrected reference %.2f dB, vs uncorrected %.2f dB\n", int(photometric),
                db_corrected, db_plain);
    EXPECT_GE(photometric ? db_corrected : db_plain, 55.0);
    EXPECT_LT(photometric ? db_plain : db_corrected, 40.0);  // the correction is visible
  }
}

TEST(EngineRun, WrongFrameSizeStopsWithAClearError) {
  const Rig rig = ring_rig_24();
  const auto frames = random_frames(rig);
  std::vector<std::unique_ptr<CameraSource>> sources;
  for (size_t c = 0; c < frames.size(); ++c)
    sources.push_back(still_source(c == 3 ? cv::Mat(100, 120, CV_8UC3, cv::Scalar::all(9)) : frames[c], 100));
  std::vector<std::unique_ptr<Sink>> sinks;
  EngineOptions opt;
  opt.map.grid = PanoGrid{Projection::kVr180, 96, 96};
  opt.duration_s = 5;
  const auto t0 = std::chrono::steady_clock::now();
  try {
    run_engine(rig, std::move(sources), sinks, opt);
    FAIL() << "no error";
  } catch (const SourceError& e) {
    EXPECT_NE(std::string(e.what()).find("120x100"), std::string::npos) << e.what();
  }
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 3.0);
}

TEST(EngineRun, LiveViewServesPageAndMjpegStreamAndRefusesABusyPort) {
  const Rig rig = ring_rig_24();
  const auto frames = random_frames(rig);
  const int port = 18000 + (::getpid() % 1000);
  std::vector<std::unique_ptr<Sink>> sinks;
  sinks.push_back(open_sink("http:" + std::to_string(port), rig, cv::Size(128, 128)));
  EXPECT_THROW(open_sink("http://127.0.0.1:" + std::to_string(port), rig, cv::Size(128, 128)), SinkError);
  std::vector<std::unique_ptr<CameraSource>> sources;
  for (const auto& f : frames) sources.push_back(still_source(f, 50));
  EngineOptions opt;
  opt.map.grid = PanoGrid{Projection::kVr180, 128, 128};
  opt.fps = 25;
  opt.duration_s = 2.0;
  std::thread engine([&] { run_engine(rig, std::move(sources), sinks, opt); });
  httplib::Client cli("127.0.0.1", port);
  cli.set_read_timeout(3, 0);
  auto page = cli.Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("/stream.mjpg"), std::string::npos);
  // Read the MJPEG stream until two complete JPEG parts have arrived.
  std::string body, content_type;
  int parts = 0;
  auto res = cli.Get(
      "/stream.mjpg",
      [&](const httplib::Response& r) {
        content_type = r.get_header_value("Content-Type");
        return true;
      },
      [&](const char* data, size_t len) {
        body.append(data, len);
        parts = 0;
        for (size_t p = 0; (p = body.find("--ommaframe", p)) != std::string::npos; ++p) ++parts;
        return parts < 3;
      });
  EXPECT_NE(content_type.find("multipart/x-mixed-replace"), std::string::npos);
  EXPECT_GE(parts, 3);
  // The first part decodes to a 128x128 JPEG.
  const size_t a = body.find("\r\n\r\n"), b = body.find("\r\n--ommaframe", a);
  ASSERT_NE(a, std::string::npos);
  ASSERT_NE(b, std::string::npos);
  std::vector<uchar> jpg(body.begin() + a + 4, body.begin() + b);
  const cv::Mat img = cv::imdecode(jpg, cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  EXPECT_EQ(img.cols, 128);
  EXPECT_EQ(img.rows, 128);
  engine.join();
}

// Raw sensor-link files -> link decoder -> ISP -> panorama (issue 5 point 5).
TEST(EngineRun, RawSensorLinkFilesGoThroughTheIspIntoThePanorama) {
  const Rig rig = ring_rig_24(64, 64);
  const auto frames = random_frames(rig, 3);
  const fs::path dir = fs::temp_directory_path() / ("omma_engine_link_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::vector<cv::Mat> raws;
  for (size_t c = 0; c < rig.cameras.size(); ++c) {
    cv::Mat raw = sim::bayer_rggb(frames[c]);  // 8-bit mosaic
    raw.convertTo(raw, CV_16U, 4.0);           // 10-bit values
    raws.push_back(raw);
    isp::LinkConfig cfg;
    cfg.width = 64;
    cfg.height = 64;
    const isp::LinkFrame lf = isp::to_link_frame(raw, 10);
    const isp::ChipStream cs = isp::encode_link({lf, lf, lf}, cfg);
    char name[32];
    std::snprintf(name, sizeof name, "cam_%02d.bin", rig.cameras[c].id);
    std::ofstream(dir / name, std::ios::binary).write(reinterpret_cast<const char*>(cs.bytes.data()), cs.bytes.size());
  }
  // The source delivers exactly what the ISP develops from the raw frame.
  {
    auto sources = open_sources(rig, {(dir / "cam_{id}.bin").string()});
    cv::Mat got;
    ASSERT_TRUE(sources[4]->read(got));
    const cv::Mat want = isp::develop(raws[4], isp::IspOptions{});
    EXPECT_EQ(cv::norm(got, want, cv::NORM_INF), 0.0);
  }
  SourceOptions so;
  so.fps = 0;
  so.loop = true;
  std::vector<std::unique_ptr<Sink>> sinks;
  sinks.push_back(std::make_unique<CaptureSink>());
  auto* cap = static_cast<CaptureSink*>(sinks[0].get());
  EngineOptions opt;
  opt.map.grid = PanoGrid{Projection::kVr180, 96, 96};
  opt.fps = 0;
  opt.duration_s = 1.5;
  const EngineStats st = run_engine(rig, open_sources(rig, {(dir / "cam_{id}.bin").string()}, so), sinks, opt);
  std::printf("  link -> ISP -> panorama: %ld panoramas, %.1f fps, %ld camera frames (%.1f per camera per s)\n",
              st.frames, st.fps, st.camera_frames, st.camera_frames / 24.0 / st.seconds);
  EXPECT_GT(st.frames, 5);
  EXPECT_TRUE(st.dropped_cameras.empty());
  EXPECT_GT(st.camera_frames, 24 * 3);
  // The panorama equals the reference render of the developed frames.
  std::vector<cv::Mat> developed;
  for (const auto& r : raws) developed.push_back(isp::develop(r, isp::IspOptions{}));
  EXPECT_GE(psnr_u8(cap->last, reference_render(rig, opt.map, developed)), 50.0);
  // A broken link file is a clear error.
  std::ofstream(dir / "junk.bin") << "not a link stream at all";
  auto bad = open_one_for_test(rig, (dir / "junk.bin").string());
  cv::Mat f;
  EXPECT_THROW(bad->read(f), SourceError);
  fs::remove_all(dir);
}

TEST(EngineSinks, UnwritableSinksAndBadSourcesGiveClearErrors) {
  const Rig rig = ring_rig_24();
  EXPECT_THROW(open_sink("/proc/omma_no/out.mp4", rig, cv::Size(64, 64)), SinkError);
  EXPECT_THROW(open_sink("png:/proc/omma_no_dir", rig, cv::Size(64, 64)), SinkError);
  EXPECT_THROW(open_sink("out.xyz", rig, cv::Size(64, 64)), SinkError);
  EXPECT_THROW(open_sink("cam:99:x.mp4", rig, cv::Size(64, 64)), SinkError);
  EXPECT_THROW(open_sources(rig, {"/nonexistent/video.mp4"}), SourceError);
  EXPECT_THROW(open_sources(rig, {"/dev/video97"}), SourceError);
  EXPECT_THROW(open_sources(rig, {"a", "b"}), SourceError);  // 2 sources for 24 cameras
  EXPECT_THROW(open_sources(rig, {"pano:/nonexistent.jpg"}), SourceError);
}

}  // namespace
}  // namespace omma::engine
