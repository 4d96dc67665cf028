// Raw recordings (recording.h): HDF5 streams, frame-set matching, crash safety.
#include "omma/io/recording.h"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "omma/design/prototype.h"

namespace omma::io {
namespace {

namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("omma_recording_test_" + name);
  fs::remove_all(d);
  return d;
}

Rig small_rig(int cameras = 3) {
  Rig rig = *design::builtin_rig("gigaeye-44-skip5");  // 432 x 324
  rig.cameras.resize(cameras);
  return rig;
}

cv::Mat raw_frame(const Rig& rig, int c, int k) {
  cv::Mat m(rig.cameras[c].in.height, rig.cameras[c].in.width, CV_16UC1);
  cv::randu(m, cv::Scalar(0), cv::Scalar(4096));
  m.at<uint16_t>(0, 0) = static_cast<uint16_t>(100 * c + k);  // a mark to check what comes back
  return m;
}

TEST(Recording, WritesAndReadsTwelveBitFramesExactly) {
  const fs::path dir = fresh_dir("roundtrip");
  const Rig rig = small_rig();
  RecordingManifest m;
  m.rig = rig;
  m.fps = 30;
  std::vector<std::vector<cv::Mat>> written(3);
  {
    RecordingWriter w(dir, m);
    for (int k = 0; k < 4; ++k)
      for (int c = 0; c < 3; ++c) {
        written[c].push_back(raw_frame(rig, c, k));
        w.append(c, written[c].back(), k, k * 33'333'333LL + c * 1'000'000LL);
      }
    w.close();
  }
  RecordingReader r(dir);
  EXPECT_TRUE(r.manifest().complete);
  EXPECT_EQ(r.manifest().bits, 12);
  ASSERT_EQ(r.cameras(), 3);
  ASSERT_EQ(r.frame_sets(), 4);
  EXPECT_EQ(r.match().complete_sets, 4);
  for (int k = 0; k < 4; ++k) {
    const auto set = r.read_frame_set(k);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(cv::norm(set[c], written[c][k], cv::NORM_INF), 0) << c << " " << k;
  }
  // Random access in any order.
  EXPECT_EQ(r.read(2, 1).at<uint16_t>(0, 0), 201);
  EXPECT_THROW(r.read(2, 4), RecordingError);
  fs::remove_all(dir);
}

std::vector<FrameMeta> stream(std::initializer_list<std::pair<uint64_t, double>> frames) {
  std::vector<FrameMeta> v;
  for (auto [s, ms] : frames) v.push_back({s, static_cast<int64_t>(ms * 1e6)});
  return v;
}

TEST(Recording, MatchesFrameSetsWithinHalfAPeriodAndCountsDropsAndDuplicates) {
  const int64_t period = 33'333'333;  // 30 fps
  // Camera 0 on time; camera 1 late by 10 ms and drops its frame 2; camera 2 repeats frame 1.
  const std::vector<std::vector<FrameMeta>> streams = {stream({{0, 0}, {1, 33.3}, {2, 66.7}, {3, 100}}),
                                                       stream({{0, 10}, {1, 43.3}, {3, 110}}),
                                                       stream({{0, 2}, {1, 35}, {1, 40}, {2, 68}, {3, 101}})};
  const auto r = match_frame_sets(streams, period);
  ASSERT_EQ(r.sets.size(), 4u);
  EXPECT_EQ(r.complete_sets, 3);
  EXPECT_EQ(r.sets[2].frame[1], -1);  // camera 1's dropped frame
  EXPECT_EQ(r.cameras[1].dropped, 1);
  EXPECT_EQ(r.cameras[1].missing, 1);
  EXPECT_EQ(r.cameras[2].duplicates, 1);
  EXPECT_EQ(r.cameras[2].extra, 1);  // the repeated frame is left out of its set
  EXPECT_EQ(r.sets[1].frame[2], 1);
  EXPECT_EQ(r.sets[3].frame[2], 4);
  // Every frame of a set lies within half a period of the set's time.
  for (const FrameSet& s : r.sets)
    for (size_t c = 0; c < 3; ++c) {
      if (s.frame[c] < 0) continue;
      EXPECT_LE(std::abs(streams[c][size_t(s.frame[c])].t_ns - s.t_ns), period / 2) << "camera " << c;
    }
  // Timestamps that go backwards are an error naming the stream.
  try {
    match_frame_sets({stream({{0, 0}, {1, 33}}), stream({{0, 40}, {1, 20}})}, period);
    ADD_FAILURE();
  } catch (const RecordingError& e) {
    EXPECT_NE(std::string(e.what()).find("stream 1: timestamps go backwards"), std::string::npos);
  }
}

TEST(Recording, BadRecordingsGiveClearErrors) {
  const fs::path dir = fresh_dir("bad");
  const Rig rig = small_rig(2);
  RecordingManifest m;
  m.rig = rig;
  {
    RecordingWriter w(dir, m);
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 2; ++c) w.append(c, raw_frame(rig, c, k), k, k * 33'000'000LL);
    w.close();
  }
  EXPECT_THROW(RecordingWriter(dir, m), RecordingError);  // exists and is not empty
  auto expect_error = [&](const std::string& what) {
    try {
      RecordingReader r(dir);
      ADD_FAILURE() << "no error, expected " << what;
    } catch (const RecordingError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  // A truncated stream.
  const fs::path s1 = dir / "cam_01.h5";
  fs::copy_file(s1, dir / "keep.h5");
  fs::resize_file(s1, fs::file_size(s1) / 3);
  expect_error("camera 1: stream");
  // A missing stream.
  fs::remove(s1);
  expect_error("is missing");
  fs::rename(dir / "keep.h5", s1);
  // Mismatched sensor mode: the manifest's rig says another size.
  const std::string text = [&] {
    std::ifstream f(dir / "manifest.json");
    return std::string(std::istreambuf_iterator<char>(f), {});
  }();
  {
    auto j = nlohmann::json::parse(text);
    j["rig"]["cameras"][0]["intrinsics"]["width"] = 648;
    std::ofstream(dir / "manifest.json") << j.dump();
  }
  expect_error("mismatched sensor mode");
  std::ofstream(dir / "manifest.json") << "{ not json";
  expect_error("not valid JSON");
  fs::remove(dir / "manifest.json");
  expect_error("no manifest.json");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace omma::io
