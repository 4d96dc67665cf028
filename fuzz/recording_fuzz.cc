// libFuzzer target for the recording reader (io/recording.h): a valid recording of two small
// cameras (written once per process by RecordingWriter) with one of its files replaced by the input.
// The first byte chooses how (byte % 5): 0 = the rest is manifest.json; 1, 2 = the rest is cam_00.h5,
// cam_01.h5; 3, 4 = the rest overwrites the start of cam_00.h5, cam_01.h5 (where HDF5 keeps its
// superblock, object headers and chunk indexes: short inputs that reach the metadata). Reading the
// recording and every frame and frame set must either succeed with frames of the manifest's sizes
// within its bit depth, or throw RecordingError: no other exception, no crash, no undefined
// behaviour, no hang, no unbounded allocation, no HDF5 object left open. Build and run with
// fuzz/run.sh.
//   RECORDING_FUZZ_SEEDS=DIR ./recording_fuzz   writes the five seeds (one per mode) to DIR and exits.
//   RECORDING_FUZZ_STREAMS=1 ./recording_fuzz   replaces only streams (modes 1-4 from byte % 4 + 1):
//   libFuzzer sees no coverage inside HDF5 (not instrumented), and manifest inputs otherwise fill the
//   corpus.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <hdf5.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "omma/core/rig.h"
#include "omma/io/recording.h"

namespace {

namespace fs = std::filesystem;

const char* const kFiles[3] = {"manifest.json", "cam_00.h5", "cam_01.h5"};
std::string g_seed[3];  // the valid recording's files
fs::path g_root;        // this process's temporary folder (removed at exit)
fs::path g_work;        // the recording read for each input
int g_changed = -1;     // the file the last input replaced
bool g_streams_only = false;

std::string slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

void put(const fs::path& p, const char* data, size_t n) {
  std::ofstream(p, std::ios::binary | std::ios::trunc).write(data, std::streamsize(n));
}

// Two cameras of 8 x 6 and 6 x 4 pixels, three 12-bit frames each (one dropped by camera 1).
void write_seed_recording(const fs::path& dir) {
  const char* rig_json = R"({"format": "omma-rig", "version": 1, "name": "fuzz",
    "dome": {"radius_mm": 5, "sphere": false, "method": "x"}, "cameras": [
    {"id": 0, "t": [0,0,1], "u": [0,1,0], "v": [-1,0,0], "position_mm": [0,0,5],
     "intrinsics": {"width": 8, "height": 6, "fu": 6, "fv": 6, "cu": 4, "cv": 3, "aov_deg": 70}},
    {"id": 1, "ypr_deg": [40, 60, 10], "position_mm": [1,2,4],
     "intrinsics": {"width": 6, "height": 4, "fu": 5, "fv": 5, "cu": 3, "cv": 2, "aov_deg": 60}}]})";
  omma::io::RecordingManifest m;
  m.rig = omma::rig_from_json(nlohmann::json::parse(rig_json));
  m.fps = 30;
  m.clock_mhz = 66;
  omma::io::RecordingWriter w(dir, m);
  cv::RNG rng(7);
  for (int k = 0; k < 3; ++k)
    for (int c = 0; c < 2; ++c) {
      if (c == 1 && k == 1) continue;
      cv::Mat raw(m.rig.cameras[c].in.height, m.rig.cameras[c].in.width, CV_16UC1);
      rng.fill(raw, cv::RNG::UNIFORM, 0, 4096);
      w.append(c, raw, uint64_t(k), k * 33'333'333LL + c * 1'000'000LL);
    }
  w.close();
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  char tmpl[] = "/tmp/omma-recording-fuzz-XXXXXX";
  if (!mkdtemp(tmpl)) abort();
  const fs::path root = tmpl;
  write_seed_recording(root / "seed");
  for (int f = 0; f < 3; ++f) g_seed[f] = slurp(root / "seed" / kFiles[f]);
  if (const char* out = std::getenv("RECORDING_FUZZ_SEEDS")) {
    for (int mode = 0; mode < 5; ++mode) {
      const std::string& file = g_seed[mode < 3 ? mode : mode - 2];
      const std::string s = std::string(1, char(mode)) + (mode < 3 ? file : file.substr(0, 2048));
      put(fs::path(out) / ("seed_" + std::to_string(mode)), s.data(), s.size());
    }
    fs::remove_all(root);
    std::exit(0);
  }
  g_root = root;
  std::atexit([] {
    std::error_code ec;
    fs::remove_all(g_root, ec);
  });
  g_streams_only = std::getenv("RECORDING_FUZZ_STREAMS") != nullptr;
  g_work = root / "rec";
  fs::create_directories(g_work);
  for (int f = 0; f < 3; ++f) put(g_work / kFiles[f], g_seed[f].data(), g_seed[f].size());
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const int mode = g_streams_only ? 1 + data[0] % 4 : data[0] % 5, f = mode < 3 ? mode : mode - 2;
  if (g_changed >= 0 && g_changed != f)
    put(g_work / kFiles[g_changed], g_seed[g_changed].data(), g_seed[g_changed].size());
  std::string content(reinterpret_cast<const char*>(data + 1), size - 1);
  if (mode >= 3 && content.size() < g_seed[f].size()) content += g_seed[f].substr(content.size());
  put(g_work / kFiles[f], content.data(), content.size());
  g_changed = f;
  try {
    const omma::io::RecordingReader r(g_work);
    const omma::io::RecordingManifest& m = r.manifest();
    if (r.cameras() != int(m.rig.cameras.size()) || !m.IsValid()) abort();
    const int top = (1 << m.bits) - 1;
    for (int c = 0; c < r.cameras(); ++c)
      for (int64_t i = 0; i < r.frames(c); ++i) {
        const cv::Mat frame = r.read(c, i);
        double mx = 0;
        cv::minMaxLoc(frame, nullptr, &mx);
        if (frame.type() != CV_16UC1 || frame.cols != m.rig.cameras[c].in.width ||
            frame.rows != m.rig.cameras[c].in.height || mx > top)
          abort();
      }
    for (int64_t s = 0; s < r.frame_sets(); ++s) {
      const auto set = r.read_frame_set(s);
      if (int(set.size()) != r.cameras()) abort();
    }
  } catch (const omma::io::RecordingError&) {
  }
  // The reader closed every HDF5 object it opened, also on every error.
  if (H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL) != 0) abort();
  return 0;
}
