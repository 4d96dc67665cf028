// Raw recordings (recording.h): HDF5 streams, frame-set matching, crash safety.
#include "omma/io/recording.h"

#include <sys/stat.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <hdf5.h>

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

// Free-running cameras as the thesis's (44-56 fps, each its own phase, 0.5 ms jitter), `seconds` long.
std::vector<std::vector<FrameMeta>> free_running(int cameras, double seconds, uint64_t seed) {
  cv::RNG rng(seed);
  std::vector<std::vector<FrameMeta>> metas(cameras);
  for (int c = 0; c < cameras; ++c) {
    const double fps = c == 0 ? 44 : rng.uniform(44.0, 56.0), phase = rng.uniform(0.0, 1 / fps);
    for (uint64_t k = 0;; ++k) {
      const double t = phase + k / fps + std::clamp(rng.gaussian(0.5e-3), -0.25 / fps, 0.25 / fps);
      if (t > seconds) break;
      metas[c].push_back({k, int64_t(t * 1e9)});
    }
  }
  return metas;
}

TEST(Recording, FreeRunningCamerasOfDifferentRatesGiveCompleteSets) {
  // 24 cameras at 44-56 fps for 3 s. Sets gathered from each set's first frame within half a period
  // (the matcher before the frame-set clock) gave 13 complete sets of 171 for such a recording
  // (`omma record --source sim:colon --duration 3`, 30 fps); on the clock every set is complete, at
  // the derived rate (0.9 x 44 fps) and at 30 fps alike.
  const auto metas = free_running(24, 3, 7);
  for (const double fps : {0.9 * 44, 30.0}) {
    const int64_t period = int64_t(1e9 / fps);
    const MatchResult r = match_frame_sets(metas, period);
    EXPECT_GE(int64_t(r.sets.size()), int64_t(3 * fps) - 2) << fps;
    EXPECT_EQ(r.complete_sets, int64_t(r.sets.size())) << fps;
    for (size_t k = 0; k < r.sets.size(); ++k) {
      if (k > 0) {
        EXPECT_EQ(r.sets[k].t_ns - r.sets[k - 1].t_ns, period);  // one tick apart (no gap)
      }
      for (int c = 0; c < 24; ++c) {
        const int64_t f = r.sets[k].frame[c];
        ASSERT_GE(f, 0);
        EXPECT_LE(std::abs(metas[c][size_t(f)].t_ns - r.sets[k].t_ns), period / 2);
        if (k > 0) {
          EXPECT_GT(f, r.sets[k - 1].frame[c]);  // never the same frame twice
        }
      }
    }
    // Every frame is in a set or counted as left out.
    for (int c = 0; c < 24; ++c)
      EXPECT_EQ(r.cameras[c].frames - r.cameras[c].extra, int64_t(r.sets.size())) << c;
  }
}

TEST(Recording, ACameraThatStartsLateOrStopsEarlyIsMissingHonestly) {
  const int64_t period = 25'000'000;
  auto at = [](double first_ms, int n, double step_ms) {
    std::vector<FrameMeta> v;
    for (int k = 0; k < n; ++k) v.push_back({uint64_t(k), int64_t((first_ms + k * step_ms) * 1e6)});
    return v;
  };
  // Camera 1 starts 100 ms late (4 sets without it); camera 2 stops after 200 ms.
  const auto r = match_frame_sets({at(0, 40, 20), at(100, 35, 20), at(5, 10, 20)}, period);
  EXPECT_EQ(r.sets.front().t_ns, 0);
  EXPECT_EQ(r.cameras[1].missing, 4);
  EXPECT_GT(r.cameras[2].missing, 20);
  EXPECT_EQ(r.complete_sets, int64_t(r.sets.size()) - 4 - r.cameras[2].missing);
  // The frame sets plan: skip, hold (with an age limit), fail.
  const std::vector<std::vector<FrameMeta>> metas = {at(0, 40, 20), at(100, 35, 20), at(5, 10, 20)};
  const int64_t last = int64_t(r.sets.size()) - 1;
  FrameSetPlanOptions o;
  o.policy = IncompletePolicy::kSkip;
  const FrameSetPlan skip = plan_frame_sets(r, metas, 0, last, period, o);
  EXPECT_EQ(skip.considered, int64_t(r.sets.size()));
  EXPECT_EQ(skip.incomplete, skip.considered - r.complete_sets);
  EXPECT_EQ(skip.skipped, skip.incomplete);
  EXPECT_EQ(int64_t(skip.sets.size()), r.complete_sets);
  o.policy = IncompletePolicy::kHold;
  o.max_hold_age_ns = 60'000'000;  // camera 2's last frame (185 ms) is held until 245 ms: 2 more sets
  const FrameSetPlan hold = plan_frame_sets(r, metas, 0, last, period, o);
  EXPECT_EQ(hold.held_sets, 2);
  EXPECT_EQ(hold.held_frames, 2);
  EXPECT_LE(hold.max_held_age_ns, 60'000'000);
  EXPECT_EQ(hold.skipped, hold.incomplete - 2);  // camera 1 has nothing to hold before it starts
  EXPECT_EQ(hold.skipped_sets.front(), 0);
  for (const PlannedSet& ps : hold.sets)
    for (int c = 0; c < 3; ++c) {
      ASSERT_GE(ps.frame[c], 0);
      EXPECT_LE(metas[c][size_t(ps.frame[c])].t_ns, r.sets[ps.set].t_ns + period / 2);
    }
  o.max_hold_age_ns = 0;  // two periods
  EXPECT_EQ(plan_frame_sets(r, metas, 0, last, period, o).max_hold_age_ns, 2 * period);
  o.policy = IncompletePolicy::kFail;
  try {
    plan_frame_sets(r, metas, 0, last, period, o, {7, 8, 9});
    ADD_FAILURE();
  } catch (const RecordingError& e) {
    EXPECT_NE(std::string(e.what()).find("frame set 0 lacks camera(s) 8;"), std::string::npos) << e.what();
  }
  EXPECT_EQ(plan_frame_sets(r, metas, 4, 4, period, o).sets.size(), 1u);  // a complete range passes
  EXPECT_EQ(parse_incomplete_policy("hold"), IncompletePolicy::kHold);
  EXPECT_THROW(parse_incomplete_policy("zero"), std::invalid_argument);
  o.max_hold_age_ns = -1;
  EXPECT_FALSE(o.IsValid());
}

// A string attribute of `obj` ("" if missing).
std::string string_attr(hid_t obj, const char* name) {
  if (H5Aexists(obj, name) <= 0) return "";
  const hid_t a = H5Aopen(obj, name, H5P_DEFAULT), type = H5Aget_type(a);
  std::string out;
  if (H5Tis_variable_str(type) > 0) {
    char* p = nullptr;
    H5Aread(a, type, &p);
    out = p ? p : "";
    H5free_memory(p);
  }
  H5Tclose(type);
  H5Aclose(a);
  return out;
}

TEST(Recording, StreamsDescribeThemselvesAndOldStreamsStillRead) {
  const fs::path dir = fresh_dir("describe");
  const Rig rig = small_rig(2);
  RecordingManifest m;
  m.rig = rig;
  m.fps = 40;
  m.camera_fps = {47, 0};
  m.exposure_s = 0.004;
  m.sensor_mode = "skip5";
  {
    RecordingWriter w(dir, m);
    for (int k = 0; k < 2; ++k)
      for (int c = 0; c < 2; ++c) w.append(c, raw_frame(rig, c, k), k, k * 25'000'000LL);
    w.close();
  }
  {
    const hid_t f = H5Fopen((dir / "cam_01.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    const hid_t t = H5Dopen2(f, "t_ns", H5P_DEFAULT);
    EXPECT_EQ(string_attr(t, "units"), "ns");
    EXPECT_EQ(string_attr(t, "start").size(), 30u);  // 2026-12-03T18:26:04.123456789Z
    EXPECT_EQ(string_attr(f, "bayer_pattern"), "RGGB");
    EXPECT_EQ(string_attr(f, "sensor_mode"), "skip5");
    EXPECT_EQ(rig_from_json(nlohmann::json::parse(string_attr(f, "rig"))).cameras.size(), 2u);
    H5Dclose(t);
    H5Fclose(f);
  }
  RecordingReader r(dir);
  EXPECT_EQ(r.manifest().camera_fps, (std::vector<double>{47, 0}));
  EXPECT_DOUBLE_EQ(r.manifest().exposure_s, 0.004);
  // A stream of the first version (camera, width, height, bits only) and a manifest without the
  // per-camera rates: read as before.
  for (const char* s : {"cam_00.h5", "cam_01.h5"}) {
    const hid_t f = H5Fopen((dir / s).c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    std::vector<std::string> names;
    H5Aiterate2(
        f, H5_INDEX_NAME, H5_ITER_INC, nullptr,
        [](hid_t, const char* name, const H5A_info_t*, void* out) -> herr_t {
          static_cast<std::vector<std::string>*>(out)->push_back(name);
          return 0;
        },
        &names);
    for (const std::string& n : names)
      if (n != "camera" && n != "width" && n != "height" && n != "bits") {
        EXPECT_GE(H5Adelete(f, n.c_str()), 0);
      }
    for (const char* d : {"frames", "seq", "t_ns"}) {
      const hid_t ds = H5Dopen2(f, d, H5P_DEFAULT);
      for (const char* a : {"units", "long_name", "bayer_pattern", "start", "start_unix_ns", "time_base"})
        if (H5Aexists(ds, a) > 0) H5Adelete(ds, a);
      H5Dclose(ds);
    }
    H5Fclose(f);
  }
  auto j = nlohmann::json::parse(std::ifstream(dir / "manifest.json"));
  for (auto& st : j["streams"]) st.erase("fps"), st.erase("exposure_s");
  std::ofstream(dir / "manifest.json") << j.dump();
  RecordingReader old(dir);
  EXPECT_TRUE(old.manifest().camera_fps.empty());
  EXPECT_EQ(old.frame_sets(), 2);
  EXPECT_EQ(old.read(1, 1).at<uint16_t>(0, 0), 101);  // the mark of camera 1's frame 1
  fs::remove_all(dir);
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

// ---- hostile recordings: each case used to be read as true, hang, or exhaust memory ------------

// A complete recording of `cameras` cameras of the small rig, 3 frames each.
fs::path small_recording(const std::string& name, int cameras = 2, int bits = 12) {
  const fs::path dir = fresh_dir(name);
  const Rig rig = small_rig(cameras);
  RecordingManifest m;
  m.rig = rig;
  m.bits = bits;
  RecordingWriter w(dir, m);
  for (int k = 0; k < 3; ++k)
    for (int c = 0; c < cameras; ++c) w.append(c, raw_frame(rig, c, k), k, k * 33'000'000LL + c);
  w.close();
  return dir;
}

// The RecordingError of reading `dir` (and every frame of it), or "" if it reads.
std::string read_error(const fs::path& dir) {
  try {
    RecordingReader r(dir);
    for (int c = 0; c < r.cameras(); ++c)
      for (int64_t i = 0; i < r.frames(c); ++i) r.read(c, i);
    return "";
  } catch (const RecordingError& e) {
    return e.what();
  }
}

// Reading `dir` is refused with an error that holds `part`.
void expect_refused(const fs::path& dir, const std::string& part, const std::string& what = "") {
  const std::string err = read_error(dir);
  EXPECT_NE(err.find(part), std::string::npos) << what << ": expected '" << part << "', got '" << err << "'";
}

// Opens a closed stream for editing with the HDF5 library (as a forger would).
struct Edit {
  hid_t file;
  explicit Edit(const fs::path& p) : file(H5Fopen(p.c_str(), H5F_ACC_RDWR, H5P_DEFAULT)) {
    EXPECT_GE(file, 0) << p;
  }
  ~Edit() { H5Fclose(file); }
  void set_int_attr(const char* name, int64_t v) {
    const hid_t a = H5Aopen(file, name, H5P_DEFAULT);
    EXPECT_GE(H5Awrite(a, H5T_NATIVE_INT64, &v), 0);
    H5Aclose(a);
  }
  void set_frames(hsize_t n) {
    for (const char* name : {"frames", "seq", "t_ns"}) {
      const hid_t d = H5Dopen2(file, name, H5P_DEFAULT);
      hsize_t dims[3] = {0, 0, 0};
      const hid_t sp = H5Dget_space(d);
      H5Sget_simple_extent_dims(sp, dims, nullptr);
      H5Sclose(sp);
      dims[0] = n;
      EXPECT_GE(H5Dset_extent(d, dims), 0) << name;
      H5Dclose(d);
    }
  }
};

TEST(RecordingHostile, DeclaredFrameCountsBeyondTheFileAreRefusedBeforeAllocating) {
  // 10^9 frames used to allocate 16 GB of timestamps (killed at 23 GB); 10^12 threw bad_alloc.
  const fs::path dir = small_recording("huge");
  const fs::path keep = dir / "keep.h5";
  fs::copy_file(dir / "cam_01.h5", keep);
  for (const hsize_t n : {hsize_t(1'000'000'000), hsize_t(1'000'000'000'000)}) {
    Edit(dir / "cam_01.h5").set_frames(n);
    EXPECT_LT(fs::file_size(dir / "cam_01.h5"), 2'000'000u);
    expect_refused(dir,
                   fmt::format("camera 1: stream '{}' declares {} frames", (dir / "cam_01.h5").string(), n));
    fs::copy_file(keep, dir / "cam_01.h5", fs::copy_options::overwrite_existing);
  }
  EXPECT_EQ(read_error(dir), "");
  fs::remove_all(dir);
}

TEST(RecordingHostile, StreamsMustBeTheirCamerasAndHoldOnlyTheirDatasets) {
  const fs::path dir = small_recording("lies");
  const fs::path s1 = dir / "cam_01.h5", keep = dir / "keep.h5";
  fs::copy_file(s1, keep);
  auto restore = [&] { fs::copy_file(keep, s1, fs::copy_options::overwrite_existing); };
  // Its camera attribute names another camera: the manifest placed another camera's stream here.
  Edit(s1).set_int_attr("camera", 0);
  expect_refused(dir, "camera 1: stream '" + s1.string() + "' holds the frames of camera 0");
  restore();
  Edit(s1).set_int_attr("bits", 16);
  expect_refused(dir, "its attributes say 16 bits, the manifest 12");
  restore();
  // An external link to another camera's frames (around the manifest's plain file names).
  {
    Edit e(s1);
    H5Ldelete(e.file, "frames", H5P_DEFAULT);
    EXPECT_GE(H5Lcreate_external("cam_00.h5", "frames", e.file, "frames", H5P_DEFAULT, H5P_DEFAULT), 0);
  }
  expect_refused(dir, "camera 1: stream '" + s1.string() + "': 'frames' is a link");
  restore();
  // A fourth object.
  {
    Edit e(s1);
    const hsize_t one[1] = {1};
    const hid_t sp = H5Screate_simple(1, one, nullptr);
    H5Dclose(H5Dcreate2(e.file, "extra", H5T_NATIVE_INT64, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    H5Sclose(sp);
  }
  expect_refused(dir, "holds 4 objects");
  restore();
  EXPECT_EQ(read_error(dir), "");
  fs::remove_all(dir);
}

// A stream written from scratch: frames of dims {n, h, w} (chunks {1, ch, cw}), seq and t_ns of n,
// with storage given by `dcpl_frames` (chunked when negative).
void forge_stream(const fs::path& p, int camera, hsize_t n, hsize_t h, hsize_t w, hsize_t ch, hsize_t cw,
                  hid_t dcpl_frames = -1) {
  const hid_t f = H5Fcreate(p.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  const hsize_t fd[3] = {n, h, w}, fc[3] = {1, ch, cw}, d1[1] = {n}, c1[1] = {16};
  hid_t dcpl = dcpl_frames;
  if (dcpl < 0) {
    dcpl = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_chunk(dcpl, 3, fc);
  }
  const hsize_t m3[3] = {H5S_UNLIMITED, h, w}, m1[1] = {H5S_UNLIMITED};
  const hid_t s3 = H5Screate_simple(3, fd, m3), s1 = H5Screate_simple(1, d1, m1);
  H5Dclose(H5Dcreate2(f, "frames", H5T_NATIVE_UINT16, s3, H5P_DEFAULT, dcpl, H5P_DEFAULT));
  const hid_t dc1 = H5Pcreate(H5P_DATASET_CREATE);
  H5Pset_chunk(dc1, 1, c1);
  std::vector<int64_t> t(n, 0);
  std::vector<uint64_t> seq(n, 0);
  const hid_t ds = H5Dcreate2(f, "seq", H5T_NATIVE_UINT64, s1, H5P_DEFAULT, dc1, H5P_DEFAULT);
  const hid_t dt = H5Dcreate2(f, "t_ns", H5T_NATIVE_INT64, s1, H5P_DEFAULT, dc1, H5P_DEFAULT);
  H5Dwrite(ds, H5T_NATIVE_UINT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, seq.data());
  H5Dwrite(dt, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, t.data());
  const hid_t sc = H5Screate(H5S_SCALAR);
  const int64_t attrs[4] = {camera, int64_t(w), int64_t(h), 12};
  const char* names[4] = {"camera", "width", "height", "bits"};
  for (int k = 0; k < 4; ++k) {
    const hid_t a = H5Acreate2(f, names[k], H5T_NATIVE_INT64, sc, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(a, H5T_NATIVE_INT64, &attrs[k]);
    H5Aclose(a);
  }
  for (hid_t id : {ds, dt}) H5Dclose(id);
  for (hid_t id : {s3, s1, sc}) H5Sclose(id);
  for (hid_t id : {dc1, dcpl}) H5Pclose(id);
  H5Fclose(f);
}

TEST(RecordingHostile, SizesAreReadAs64BitAndStorageMustBeInTheFile) {
  const fs::path dir = small_recording("sizes");
  const fs::path s1 = dir / "cam_01.h5";
  // 432 x (324 + 2^32): used to be narrowed to 432 x 324 and read as black frames.
  const hsize_t tall = 324 + (hsize_t(1) << 32);
  forge_stream(s1, 1, 1, tall, 432, 1, 432);
  expect_refused(dir, fmt::format("camera 1: stream '{}': frames are 432x{} but the rig's camera is 432x324",
                                  s1.string(), tall));
  // The right size, with its pixels in an external raw file (around the plain file names).
  std::ofstream(dir / "outside.raw") << std::string(432 * 324 * 2, '\x7f');
  const hid_t ext = H5Pcreate(H5P_DATASET_CREATE);
  H5Pset_external(ext, (dir / "outside.raw").c_str(), 0, H5F_UNLIMITED);
  forge_stream(s1, 1, 1, 324, 432, 1, 432, ext);
  expect_refused(dir, "'frames' is not chunked in the file");
  // A compressed stream could expand without bound.
  const hid_t deflate = H5Pcreate(H5P_DATASET_CREATE);
  const hsize_t fc[3] = {1, 324, 432};
  H5Pset_chunk(deflate, 3, fc);
  H5Pset_deflate(deflate, 1);
  forge_stream(s1, 1, 1, 324, 432, 324, 432, deflate);
  expect_refused(dir, "'frames' is filtered");
  // Chunks other than one frame.
  forge_stream(s1, 1, 1, 324, 432, 1, 432);
  expect_refused(dir, "one frame per chunk");
  // The right layout, but the frame was never written: it would read as zeros.
  forge_stream(s1, 1, 1, 324, 432, 324, 432);
  expect_refused(dir, "camera 1: stream '" + s1.string() + "': frame 0 is not stored in the file");
  fs::remove_all(dir);
}

TEST(RecordingHostile, OnlyRegularFilesInTheFolder) {
  const fs::path dir = small_recording("files");
  const fs::path s1 = dir / "cam_01.h5", other = fresh_dir("files_other");
  fs::create_directories(other);
  fs::rename(s1, other / "cam_01.h5");
  // A symbolic link out of the folder; one within it is followed.
  fs::create_symlink(other / "cam_01.h5", s1);
  expect_refused(dir,
                 "camera 1: stream '" + s1.string() + "' is a symbolic link out of the recording's folder");
  fs::remove(s1);
  fs::rename(other / "cam_01.h5", dir / "real_01.h5");
  fs::create_symlink("real_01.h5", s1);
  EXPECT_EQ(read_error(dir), "");
  fs::remove(s1);
  // A FIFO used to block forever; a folder.
  ASSERT_EQ(mkfifo(s1.c_str(), 0600), 0);
  expect_refused(dir, "camera 1: stream '" + s1.string() + "' is a FIFO, not a regular file");
  fs::remove(s1);
  fs::create_directory(s1);
  expect_refused(dir, "is a folder, not a regular file");
  fs::remove_all(dir);
  fs::remove_all(other);
}

TEST(RecordingHostile, FramesAboveTheBitDepthAreRefusedByTheReader) {
  // An 8-bit recording whose frames hold 12-bit values: `recording check` read them, the renderer
  // refused them.
  const fs::path dir = small_recording("bits", 2, 8);
  expect_refused(dir, "camera 0: stream '" + (dir / "cam_00.h5").string() + "': frame 0 has values up to");
  expect_refused(dir, "more than the recording's 8 bits allow");
  fs::remove_all(dir);
}

TEST(RecordingHostile, ManifestFieldsAreStrict) {
  const fs::path dir = small_recording("manifest");
  const nlohmann::json good = [&] {
    std::ifstream f(dir / "manifest.json");
    return nlohmann::json::parse(f);
  }();
  struct Case {
    const char* what;
    void (*edit)(nlohmann::json&);
    const char* error;
  };
  const Case cases[] = {
      {"bits 2^32 + 12", [](nlohmann::json& j) { j["bits"] = (int64_t(1) << 32) + 12; },
       "'bits' = 4294967308 is out of range"},
      {"bits 12.7", [](nlohmann::json& j) { j["bits"] = 12.7; }, "'bits' must be an integer"},
      {"bits true", [](nlohmann::json& j) { j["bits"] = true; }, "'bits' must be an integer"},
      {"bits 2^64", [](nlohmann::json& j) { j["bits"] = nlohmann::json::parse("18446744073709551628"); },
       "'bits' must be an integer"},
      {"version true", [](nlohmann::json& j) { j["version"] = true; }, "'version' must be an integer"},
      {"version 1.0", [](nlohmann::json& j) { j["version"] = 1.0; }, "'version' must be an integer"},
      {"fps text", [](nlohmann::json& j) { j["fps"] = "30"; }, "'fps' must be a number"},
      {"fps 1e-12", [](nlohmann::json& j) { j["fps"] = 1e-12; }, "fps must be in [0.001, 10000]"},
      {"fps 1e5", [](nlohmann::json& j) { j["fps"] = 1e5; }, "fps must be in"},
      {"clock -1", [](nlohmann::json& j) { j["clock_mhz"] = -1; }, "clock must be in [0, 100000] MHz"},
      {"clock null", [](nlohmann::json& j) { j["clock_mhz"] = nullptr; }, "'clock_mhz' must be a number"},
      {"start -5", [](nlohmann::json& j) { j["start_unix_ns"] = -5; },
       "'start_unix_ns' = -5 is out of range"},
      {"complete 1", [](nlohmann::json& j) { j["complete"] = 1; }, "'complete' must be true or false"},
      {"sensor mode 7", [](nlohmann::json& j) { j["sensor_mode"] = 7; }, "'sensor_mode' must be a string"},
      {"width 2^32 + 432", [](nlohmann::json& j) { j["streams"][0]["width"] = (int64_t(1) << 32) + 432; },
       "'width' = 4294967728 is out of range"},
      {"camera id", [](nlohmann::json& j) { j["streams"][1]["camera"] = 0; },
       "stream 1 is of camera 0, but camera 1 of the rig is 1"},
      {"file twice", [](nlohmann::json& j) { j["streams"][1]["file"] = "cam_00.h5"; },
       "'cam_00.h5' is named twice"},
      {"file NUL", [](nlohmann::json& j) { j["streams"][1]["file"] = std::string("cam_00.h5\0x", 11); },
       "control characters (NUL included)"},
      {"file ..", [](nlohmann::json& j) { j["streams"][1]["file"] = ".."; }, "is not a plain name"},
      {"file path", [](nlohmann::json& j) { j["streams"][1]["file"] = "../x/cam_01.h5"; },
       "is not a plain name"},
      {"container", [](nlohmann::json& j) { j["container"] = "mkv"; }, "'container' must be \"hdf5\""},
  };
  for (const Case& c : cases) {
    nlohmann::json j = good;
    c.edit(j);
    std::ofstream(dir / "manifest.json") << j.dump();
    expect_refused(dir, c.error, c.what);
  }
  // Swapped file names: each stream's own camera attribute shows it.
  nlohmann::json j = good;
  std::swap(j["streams"][0]["file"], j["streams"][1]["file"]);
  std::ofstream(dir / "manifest.json") << j.dump();
  expect_refused(dir, "camera 0: stream '" + (dir / "cam_01.h5").string() + "' holds the frames of camera 1");
  // The cameras reordered in the rig and the streams alike: the same.
  j = good;
  std::swap(j["rig"]["cameras"][0], j["rig"]["cameras"][1]);
  std::swap(j["streams"][0]["camera"], j["streams"][1]["camera"]);
  std::ofstream(dir / "manifest.json") << j.dump();
  expect_refused(dir, "camera 1: stream '" + (dir / "cam_00.h5").string() + "' holds the frames of camera 0");
  std::ofstream(dir / "manifest.json") << good.dump();
  EXPECT_EQ(read_error(dir), "");
  fs::remove_all(dir);
}

TEST(RecordingHostile, TheWriterRefusesWhatTheReaderWould) {
  // fps 10^5, infinity or 10^-12 and a NaN clock used to be written, and every reader refused them.
  for (auto edit : std::vector<void (*)(RecordingManifest&)>{
           [](RecordingManifest& m) { m.fps = 1e5; }, [](RecordingManifest& m) { m.fps = INFINITY; },
           [](RecordingManifest& m) { m.fps = 1e-12; }, [](RecordingManifest& m) { m.clock_mhz = NAN; },
           [](RecordingManifest& m) { m.clock_mhz = INFINITY; }, [](RecordingManifest& m) { m.bits = 17; },
           [](RecordingManifest& m) { m.sensor_mode = std::string("a\0b", 3); }}) {
    const fs::path dir = fresh_dir("writer");
    RecordingManifest m;
    m.rig = small_rig(2);
    edit(m);
    EXPECT_FALSE(m.IsValid());
    EXPECT_THROW(RecordingWriter(dir, m), std::invalid_argument);
    EXPECT_FALSE(fs::exists(dir));
  }
  std::string why;
  EXPECT_TRUE(valid_recording_fps(kMinRecordingFps) && valid_recording_fps(kMaxRecordingFps));
  EXPECT_FALSE(valid_recording_fps(std::nan(""), &why));
  EXPECT_NE(why.find("fps must be in"), std::string::npos);
  EXPECT_FALSE(valid_stream_file_name(std::string(256, 'a')));
}

TEST(RecordingHostile, MatchingSaturatesDropsAndBoundsItsSets) {
  // Sequence numbers from 0 to 2^64 - 1 (twice) used to overflow the dropped count.
  const auto r = match_frame_sets({{{0, 0}, {UINT64_MAX / 2, 10}, {UINT64_MAX, 20}}}, 1000);
  EXPECT_EQ(r.cameras[0].dropped, INT64_MAX);
  // Timestamps 2^62 ns apart on the shortest and longest periods: two sets at once; at the end of
  // the clock's range (2^63 - 1 ns) no overflow (the last instants are not representable: one set).
  for (const int64_t period : {int64_t(100'000), int64_t(1'000'000'000'000)}) {
    const int64_t t = int64_t(1) << 62;
    const auto far = match_frame_sets({{{0, 0}, {1, t}}, {{0, 1}, {1, t + 1}}}, period);
    EXPECT_EQ(far.sets.size(), 2u) << period;
    EXPECT_EQ(far.complete_sets, 2) << period;
    const auto end = match_frame_sets({{{0, 0}, {1, INT64_MAX}}, {{0, 1}, {1, INT64_MAX - 1}}}, period);
    EXPECT_GE(end.sets.size(), 1u) << period;
  }
  EXPECT_THROW(match_frame_sets({{{0, -5}}}, 1000), RecordingError);
}

}  // namespace
}  // namespace omma::io
