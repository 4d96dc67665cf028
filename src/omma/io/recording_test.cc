// Raw recordings (recording.h): HDF5 streams, frame-set matching, crash safety.
#include "omma/io/recording.h"

#include <sys/stat.h>

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
}

}  // namespace
}  // namespace omma::io
