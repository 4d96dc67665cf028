// The recorder (recorder.h): camera sources into an HDF5 recording (io/recording.h).
#include "omma/live/recorder.h"

#include <filesystem>

#include <gtest/gtest.h>

#include "omma/design/prototype.h"
#include "omma/io/recording.h"

namespace omma::live {
namespace {

namespace fs = std::filesystem;

TEST(Recorder, CountsFramesAndConvertsToTwelveBits) {
  const fs::path dir = fs::temp_directory_path() / "omma_recorder_test";
  fs::remove_all(dir);
  Rig rig = *design::builtin_rig("gigaeye-44-skip5");  // 432 x 324
  rig.cameras.resize(3);
  std::vector<std::unique_ptr<CameraSource>> sources;
  for (int c = 0; c < 3; ++c) {
    cv::Mat bgr(rig.cameras[c].in.height, rig.cameras[c].in.width, CV_8UC3, cv::Scalar(10, 128, 255));
    sources.push_back(still_source(bgr, 100, 0));
  }
  RecordOptions o;
  o.frames = 5;
  o.fps = 100;
  o.progress = false;
  io::RecordingManifest m;
  m.rig = rig;
  const RecordSummary s = record(std::move(sources), dir, m, o);
  EXPECT_TRUE(s.error.empty()) << s.error;
  for (int c = 0; c < 3; ++c) EXPECT_EQ(s.frames[c] + s.dropped[c], 5);
  io::RecordingReader r(dir);
  const cv::Mat f = r.read(0, 0);
  // RGGB: (0,0) R = 255 -> 4095, (0,1) G = 128 -> 2056, (1,1) B = 10 -> 161 (v * 4095 / 255, rounded).
  EXPECT_EQ(f.at<uint16_t>(0, 0), 4095);
  EXPECT_EQ(f.at<uint16_t>(0, 1), 2056);
  EXPECT_EQ(f.at<uint16_t>(1, 1), 161);
  EXPECT_GE(r.frame_sets(), 4);  // 5 frames 10 ms apart on a 10 ms clock: 4 or 5 instants
  fs::remove_all(dir);
}

TEST(Recorder, DerivesTheFrameSetRateFromTheSlowestCamera) {
  EXPECT_DOUBLE_EQ(derived_recording_fps({46, 44, 56}), 0.9 * 44);
  EXPECT_DOUBLE_EQ(derived_recording_fps({0, 0}), kFallbackFps);  // no source knows its rate
  EXPECT_DOUBLE_EQ(derived_recording_fps({0, 50}), 45);
  const fs::path dir = fs::temp_directory_path() / "omma_recorder_test_fps";
  fs::remove_all(dir);
  Rig rig = *design::builtin_rig("gigaeye-44-skip5");
  rig.cameras.resize(2);
  std::vector<std::unique_ptr<CameraSource>> sources;
  for (int c = 0; c < 2; ++c)
    sources.push_back(
        still_source(cv::Mat(rig.cameras[c].in.height, rig.cameras[c].in.width, CV_8UC3, cv::Scalar::all(50)),
                     c ? 50 : 40, 0));
  RecordOptions o;  // fps = 0: derived
  o.frames = 4;
  o.progress = false;
  o.exposure_s = 0.002;
  io::RecordingManifest m;
  m.rig = rig;
  const RecordSummary s = record(std::move(sources), dir, m, o);
  EXPECT_TRUE(s.error.empty()) << s.error;
  EXPECT_DOUBLE_EQ(s.fps, 36);
  io::RecordingReader r(dir);
  EXPECT_DOUBLE_EQ(r.manifest().fps, 36);
  EXPECT_EQ(r.manifest().camera_fps, (std::vector<double>{40, 50}));
  EXPECT_DOUBLE_EQ(r.manifest().exposure_s, 0.002);
  o.exposure_s = -1;
  EXPECT_FALSE(o.IsValid());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace omma::live
