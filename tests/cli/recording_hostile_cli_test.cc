// Hostile recordings on the command line: `omma recording check` and `omma render` refuse recordings
// that are damaged or lie, within seconds, with exit status 1 and an error naming the camera and the
// file; `omma record` refuses the options whose recording its reader would refuse. Each case used to
// hang, exhaust memory, or pass with exit status 0. (Forged HDF5 streams: io/recording_test.cc.)
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "omma/core/frames.h"
#include "omma/core/io.h"
#include "omma/core/rig.h"
#include "omma/design/prototype.h"
#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {
namespace fs = std::filesystem;

// Camera 1's frames are one grey (8-bit 100 -> 12-bit 1606 = bytes 46 06): found in its stream.
constexpr uint8_t kGrey = 100;
const std::string kGreyRun = [] {
  std::string s;
  for (int i = 0; i < 64; ++i) s += "\x46\x06";
  return s;
}();

// One recording (two 250 x 250 cameras of the thesis prototype, three frames each) made by `omma
// record`, copied by each test.
class HostileRecording : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    base_ = new fs::path(temp_dir("hostile-rec"));
    Rig rig = design::thesis_prototype_rig();
    rig.cameras.resize(2);
    std::ofstream(*base_ / "rig.json") << rig_to_json(rig).dump();
    fs::create_directories(*base_ / "f");
    cv::Mat noise(rig.cameras[0].in.height, rig.cameras[0].in.width, CV_8UC3);
    cv::randu(noise, 0, 256);
    write_image(*base_ / "f" / frame_filename(rig.cameras[0].id), noise);
    write_image(*base_ / "f" / frame_filename(rig.cameras[1].id),
                cv::Mat(rig.cameras[1].in.height, rig.cameras[1].in.width, CV_8UC3, cv::Scalar::all(kGrey)));
    const RunResult r = run_omma(record_args("--fps 100", (*base_ / "rec").string()));
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  static void TearDownTestSuite() {
    fs::remove_all(*base_);
    delete base_;
  }
  static std::string record_args(const std::string& options, const std::string& out,
                                 const std::string& source = "") {
    return "record --rig " + (*base_ / "rig.json").string() + " --source " +
           (source.empty() ? "frames:" + (*base_ / "f").string() : source) + " --source-fps 0 --frames 3 " +
           options + " --out " + out;
  }
  // A fresh copy of the recording.
  static fs::path copy(const std::string& tag) {
    const fs::path d = temp_dir(tag) / "rec";
    fs::copy(*base_ / "rec", d);
    return d;
  }
  static fs::path* base_;
};
fs::path* HostileRecording::base_ = nullptr;

// `omma recording check DIR`, its seconds into *seconds.
RunResult check(const fs::path& dir, double* seconds = nullptr) {
  const auto t0 = std::chrono::steady_clock::now();
  RunResult r = run_omma("recording check " + dir.string(), 60);
  if (seconds) *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

void expect_refused(const RunResult& r, const std::string& part, const std::string& what) {
  EXPECT_EQ(r.exit_code, 1) << what << "\n" << r.err;
  EXPECT_TRUE(has(r.err, "omma: error: ")) << what << "\n" << r.err;
  EXPECT_TRUE(has(r.err, part)) << what << ": no '" << part << "' in\n" << r.err;
}

void write_bytes(const fs::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary | std::ios::trunc) << bytes;
}

TEST_F(HostileRecording, FlippedBitsInAStreamEndInSecondsNamingTheCamera) {
  // One flipped bit in HDF5 metadata used to retry (SWMR reads) for more than 590 s.
  const fs::path rec = copy("hostile-flip");
  const fs::path s1 = rec / "cam_01.h5";
  const std::string good = slurp(s1);
  std::vector<size_t> offsets;  // inside each object header and extensible-array header
  for (const char* sig : {"OHDR", "EAHD"})
    for (size_t at = good.find(sig); at != std::string::npos; at = good.find(sig, at + 1))
      offsets.push_back(at + 9);
  ASSERT_GE(offsets.size(), 4u);
  for (const size_t at : offsets) {
    std::string bad = good;
    bad[at] = char(bad[at] ^ 0x08);
    write_bytes(s1, bad);
    double s = 0;
    const RunResult r = check(rec, &s);
    expect_refused(r, "camera 1: stream '" + s1.string() + "'", "bit 3 of byte " + std::to_string(at));
    EXPECT_LT(s, 10) << "byte " << at;
  }
  // The renderer reads it the same way.
  const auto t0 = std::chrono::steady_clock::now();
  const RunResult r = run_omma(
      "render " + rec.string() + " --size 64x32 --no-cache --out " + (rec.parent_path() / "x.tif").string(),
      60);
  expect_refused(r, "camera 1: stream '" + s1.string() + "'", "render");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 10);
  EXPECT_FALSE(fs::exists(rec.parent_path() / "x.tif"));
  fs::remove_all(rec.parent_path());
}

TEST_F(HostileRecording, OnlyRegularFilesAreRead) {
  // A FIFO in place of a stream used to block forever.
  const fs::path rec = copy("hostile-fifo");
  const fs::path s1 = rec / "cam_01.h5";
  fs::rename(s1, rec.parent_path() / "cam_01.h5");
  ASSERT_EQ(mkfifo(s1.c_str(), 0600), 0);
  double s = 0;
  expect_refused(check(rec, &s), "camera 1: stream '" + s1.string() + "' is a FIFO, not a regular file",
                 "FIFO");
  EXPECT_LT(s, 10);
  fs::remove(s1);
  fs::create_symlink(rec.parent_path() / "cam_01.h5", s1);
  expect_refused(check(rec), "is a symbolic link out of the recording's folder", "symlink");
  fs::remove_all(rec.parent_path());
}

TEST_F(HostileRecording, ManifestsThatLieAreRefused) {
  const fs::path rec = copy("hostile-manifest");
  const nlohmann::json good = nlohmann::json::parse(slurp(rec / "manifest.json"));
  auto refused = [&](const nlohmann::json& j, const std::string& part, const std::string& what) {
    write_bytes(rec / "manifest.json", j.dump());
    expect_refused(check(rec), part, what);
  };
  // Swapped file names fed each camera the other's frames; the streams' own camera attribute tells.
  nlohmann::json j = good;
  std::swap(j["streams"][0]["file"], j["streams"][1]["file"]);
  refused(j, "camera 0: stream '" + (rec / "cam_01.h5").string() + "' holds the frames of camera 1",
          "swapped");
  j = good;
  std::swap(j["rig"]["cameras"][0], j["rig"]["cameras"][1]);
  std::swap(j["streams"][0]["camera"], j["streams"][1]["camera"]);
  refused(j, "holds the frames of camera", "cameras reordered");
  j = good;
  j["streams"][1]["file"] = j["streams"][0]["file"];
  refused(j, "'cam_00.h5' is named twice", "duplicated");
  j = good;
  j["streams"][1]["file"] = std::string("cam_00.h5\0.h5", 13);
  refused(j, "control characters (NUL included)", "NUL");
  // Integers that wrapped or had another type.
  j = good;
  j["bits"] = (int64_t(1) << 32) + 12;
  refused(j, "'bits' = 4294967308 is out of range (8..16)", "bits 2^32 + 12");
  j["bits"] = 12.7;
  refused(j, "'bits' must be an integer", "bits 12.7");
  j = good;
  j["version"] = true;
  refused(j, "'version' must be an integer", "version true");
  j = good;
  j["streams"][1]["height"] = (int64_t(1) << 32) + 250;
  refused(j, "'height' = 4294967546 is out of range", "height 2^32 + 250");
  write_bytes(rec / "manifest.json", good.dump());
  EXPECT_EQ(check(rec).exit_code, 0);
  fs::remove_all(rec.parent_path());
}

TEST_F(HostileRecording, FramesAboveTheBitDepthAreRefusedByCheckAsByRender) {
  // `recording check` passed a frame that `render` then refused.
  const fs::path rec = copy("hostile-bits");
  const fs::path s1 = rec / "cam_01.h5";
  std::string bytes = slurp(s1);
  const size_t at = bytes.find(kGreyRun);
  ASSERT_NE(at, std::string::npos);
  bytes[at] = bytes[at + 1] = '\xff';
  write_bytes(s1, bytes);
  const std::string why = "camera 1: stream '" + s1.string() +
                          "': frame 0 has values up to 65535, more than the recording's 12 bits allow";
  expect_refused(check(rec), why, "check");
  const fs::path out = rec.parent_path() / "x.tif";
  expect_refused(run_omma("render " + rec.string() + " --size 64x32 --no-cache --out " + out.string(), 60),
                 why, "render");
  fs::remove_all(rec.parent_path());
}

TEST_F(HostileRecording, RecordRefusesWhatItsReaderWouldBeforeStarting) {
  // These used to exit 0 with a recording that every reader refused.
  const fs::path dir = temp_dir("hostile-record");
  for (const char* options : {"--fps 100000", "--fps inf", "--fps 1e-12", "--fps 30 --clock nan",
                              "--fps 30 --clock inf", "--fps 30 --clock -1"}) {
    const fs::path out = dir / "rec";
    const RunResult r = run_omma(record_args(options, out.string()), 60);
    // (inf and nan may be refused by the option parser already: "--fps: must be a finite number")
    expect_refused(r, std::string(options).find("clock") != std::string::npos ? "clock" : "fps", options);
    EXPECT_FALSE(fs::exists(out)) << options;
  }
  // Refused before the sources start (the simulator of a large rig takes tens of seconds).
  const auto t0 = std::chrono::steady_clock::now();
  expect_refused(run_omma(record_args("--fps 1e-12", (dir / "sim").string(), "sim:colon"), 60),
                 "fps must be in", "sim");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 10);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace omma::test
