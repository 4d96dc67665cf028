// Recordings as outside tools read them, and frame sets made honestly: `omma record` of free-running
// simulated cameras gives complete frame sets; each camera's HDF5 stream describes itself (h5dump,
// h5py: units, Bayer pattern, bit depth, rates, the rig); `omma render --incomplete skip|hold|fail`
// never fills a missing camera with black. (Hostile recordings: recording_hostile_cli_test.cc.)
#include <filesystem>
#include <fstream>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "omma/core/frames.h"
#include "omma/core/io.h"
#include "omma/core/rig.h"
#include "omma/design/prototype.h"
#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

bool have(const std::string& command) { return run_command(command + " >/dev/null 2>&1", 30).exit_code == 0; }

// The three-camera rig of these tests: the first cameras of the thesis prototype (250 x 250).
Rig three_cameras() {
  Rig rig = design::thesis_prototype_rig();
  rig.cameras.resize(3);
  rig.name = "three";
  return rig;
}

// Pixels of a panorama (read back with OpenCV) where camera c is the only camera: masks[c] from a
// render of a frames folder where camera c is white and the others black (255 = no other camera's
// weight: a black camera c leaves exactly 0 there).
std::vector<cv::Mat> camera_regions(const fs::path& dir, const Rig& rig, const std::string& render_args) {
  std::vector<cv::Mat> masks;
  for (size_t c = 0; c < rig.cameras.size(); ++c) {
    const fs::path f = dir / ("mask" + std::to_string(c));
    fs::create_directories(f);
    std::ofstream(f / "rig.json") << rig_to_json(rig).dump();
    for (size_t k = 0; k < rig.cameras.size(); ++k)
      write_image(f / frame_filename(rig.cameras[k].id),
                  cv::Mat(rig.cameras[k].in.height, rig.cameras[k].in.width, CV_8UC3,
                          cv::Scalar::all(k == c ? 255 : 0)));
    const RunResult r = run_omma("render " + f.string() + " --no-photometric " + render_args + " --out " +
                                 (f / "m.png").string());
    EXPECT_EQ(r.exit_code, 0) << r.err;
    cv::Mat m = cv::imread((f / "m.png").string(), cv::IMREAD_GRAYSCALE);
    EXPECT_FALSE(m.empty());
    masks.push_back(m == 255);  // where camera c is the only camera (the others' blend weights ~0)
  }
  return masks;
}

// A panorama has a hole where a camera's whole region is black (a camera filled with zeros).
int camera_holes(const fs::path& pano, const std::vector<cv::Mat>& regions) {
  const cv::Mat p = cv::imread(pano.string(), cv::IMREAD_COLOR);
  EXPECT_FALSE(p.empty()) << pano;
  if (p.empty()) return 1;
  cv::Mat any = cv::Mat::zeros(p.size(), CV_8U), channel;
  for (int ch = 0; ch < 3; ++ch) {
    cv::extractChannel(p, channel, ch);
    any |= channel > 0;
  }
  int holes = 0;
  for (const cv::Mat& region : regions) {
    const int area = cv::countNonZero(region);
    EXPECT_GT(area, 20) << "a camera region of the test rig is too small to test";
    holes += cv::countNonZero(any & region) == 0;
  }
  return holes;
}

// One recording of free-running simulated cameras (44-56 fps each, their own phases and jitter),
// made once; the checker scene (fast to pre-render) in place of the colon.
class FreeRunning : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(temp_dir("rec-cli"));
    std::ofstream(*dir_ / "rig.json") << rig_to_json(three_cameras()).dump();
    record_ =
        new RunResult(run_omma("record --rig " + (*dir_ / "rig.json").string() +
                                   " --source sim:checker --duration 1.5 --out " + rec().string() + " --json",
                               120));
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
    delete record_;
  }
  static fs::path rec() { return *dir_ / "rec"; }
  static fs::path* dir_;
  static RunResult* record_;
};
fs::path* FreeRunning::dir_ = nullptr;
RunResult* FreeRunning::record_ = nullptr;

TEST_F(FreeRunning, DefaultsGiveCompleteFrameSetsAndRenderWithoutHoles) {
  ASSERT_EQ(record_->exit_code, 0) << record_->err;
  const json rj = record_->json();
  // The frame-set rate: 0.9 x the slowest camera's own rate.
  double slowest = 1e9;
  for (const auto& f : rj["camera_fps"]) slowest = std::min(slowest, f.get<double>());
  EXPECT_GE(slowest, 44);
  EXPECT_NEAR(rj["fps"].get<double>(), 0.9 * slowest, 1e-9);
  const RunResult c = run_omma("recording check " + rec().string() + " --json");
  ASSERT_EQ(c.exit_code, 0) << c.err;
  const json cj = c.json();
  const int sets = cj["frame_sets"], complete = cj["complete_sets"];
  std::cerr << "recording check: " << complete << " of " << sets << " frame sets complete\n";
  EXPECT_GE(sets, 50);  // 1.5 s at 0.9 x 44..56 fps
  // Complete by construction; a frame the simulator skips on a busy machine may leave a set short.
  EXPECT_GE(complete, sets - sets / 20);
  // Every set rendered (default --incomplete hold), no camera region black in any panorama.
  const std::string size = "--size 128x64 --projection equirect-full --method linear --no-cache";
  const fs::path out = *dir_ / "p";
  const RunResult r = run_omma("render " + rec().string() + " " + size + " --out " +
                               (out / "p_{set}.png").string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json fj = r.json()["frame_sets"];
  EXPECT_EQ(fj["policy"], "hold");
  EXPECT_EQ(fj["frame_sets"], sets);
  EXPECT_EQ(fj["complete"], complete);
  EXPECT_EQ(fj["holes"], 0);
  EXPECT_EQ(fj["rendered"].get<int>() + fj["skipped"].get<int>(), sets);
  EXPECT_LE(fj["skipped"].get<int>(), sets / 20);
  const std::vector<cv::Mat> regions = camera_regions(*dir_, three_cameras(), size);
  int rendered = 0, holes = 0;
  for (const auto& e : fs::directory_iterator(out))
    if (e.path().extension() == ".png") {
      ++rendered;
      holes += camera_holes(e.path(), regions);
    }
  EXPECT_EQ(rendered, fj["rendered"].get<int>());
  EXPECT_EQ(holes, 0);
}

TEST_F(FreeRunning, EachStreamDescribesItselfToH5dumpAndH5py) {
  ASSERT_EQ(record_->exit_code, 0) << record_->err;
  const json manifest = json::parse(slurp(rec() / "manifest.json"));
  const fs::path s1 = rec() / "cam_01.h5";
  if (!have("h5dump --version"))
    GTEST_SKIP() << "h5dump not installed (hdf5-tools: scripts/install-deps.sh --test)";
  // h5dump: the attributes of the timestamps and of the file.
  const RunResult d = run_command("h5dump -A " + s1.string());
  ASSERT_EQ(d.exit_code, 0) << d.err;
  for (const char* part : {"DATASET \"t_ns\"", "ATTRIBUTE \"units\"", "\"ns\"", "ATTRIBUTE \"bayer_pattern\"",
                           "\"RGGB\"", "ATTRIBUTE \"rig\"", "ATTRIBUTE \"frame_set_rate_hz\""})
    EXPECT_TRUE(has(d.out, part)) << part;
  if (!have("/usr/bin/python3 -c 'import h5py'"))
    GTEST_SKIP() << "h5py not installed (python3-h5py: scripts/install-deps.sh --test)";
  // h5py: the values, and a frame with its timestamp in three lines (docs/guide/recording-and-render.md).
  const std::string py = R"(
import h5py, json, sys
f = h5py.File(sys.argv[1], "r")
frame, t = f["frames"][10], f["t_ns"][10]
a, ta = f.attrs, f["t_ns"].attrs
print(json.dumps({"shape": list(frame.shape), "dtype": str(frame.dtype), "t": int(t), "max": int(frame.max()),
  "units": ta["units"], "start": ta["start"], "start_unix_ns": int(ta["start_unix_ns"]),
  "frames_units": f["frames"].attrs["units"], "bits": int(a["bits"]), "depth": int(a["bit_depth_readout"]),
  "bayer": a["bayer_pattern"], "cfa": [int(v) for v in a["cfa_pattern"]], "camera": int(a["camera"]),
  "index": int(a["camera_index"]), "rate": float(a["frame_rate_hz"]), "set_rate": float(a["frame_set_rate_hz"]),
  "mode": a["sensor_mode"], "w": int(a["sensor_width"]), "time_base": a["time_base"], "rig": json.loads(a["rig"])}))
)";
  const fs::path script = rec().parent_path() / "read.py";
  std::ofstream(script) << py;
  const RunResult p = run_command("/usr/bin/python3 " + script.string() + " " + s1.string());
  ASSERT_EQ(p.exit_code, 0) << p.err;
  const json j = p.json();
  EXPECT_EQ(j["shape"], json({250, 250}));
  EXPECT_EQ(j["dtype"], "uint16");
  EXPECT_GT(j["t"].get<int64_t>(), 0);
  EXPECT_LE(j["max"].get<int>(), 4095);
  EXPECT_EQ(j["units"], "ns");
  EXPECT_EQ(j["start_unix_ns"], manifest["start_unix_ns"]);
  EXPECT_EQ(j["start"].get<std::string>().substr(0, 2), "20");  // ISO 8601, e.g. 2026-12-03T18:26:04.1...Z
  EXPECT_EQ(j["start"].get<std::string>().back(), 'Z');
  EXPECT_EQ(j["frames_units"], "counts");
  EXPECT_EQ(j["bits"], 12);
  EXPECT_EQ(j["depth"], 12);
  EXPECT_EQ(j["bayer"], "RGGB");
  EXPECT_EQ(j["cfa"], json({0, 1, 1, 2}));
  EXPECT_EQ(j["camera"], manifest["streams"][1]["camera"]);
  EXPECT_EQ(j["index"], 1);
  EXPECT_EQ(j["rate"], manifest["streams"][1]["fps"]);
  EXPECT_GE(j["rate"].get<double>(), 44);
  EXPECT_EQ(j["set_rate"], manifest["fps"]);
  EXPECT_EQ(j["mode"], "three");
  EXPECT_EQ(j["w"], 250);
  EXPECT_TRUE(has(j["time_base"].get<std::string>(), "steady clock"));
  EXPECT_EQ(j["rig"], manifest["rig"]);  // the rig round-trips: one stream alone is unambiguous
  EXPECT_EQ(j["rig"]["cameras"].size(), 3u);
}

TEST(RecordingCli, IncompleteFrameSetsAreSkippedHeldOrRefusedNeverBlack) {
  // Two cameras from image sequences at 10 fps: camera 1's sequence ends after 3 frames, camera 0's
  // after 6, so frame sets 3, 4 and 5 lack camera 1.
  const fs::path dir = temp_dir("rec-incomplete");
  Rig rig = three_cameras();
  rig.cameras.resize(2);
  std::ofstream(dir / "rig.json") << rig_to_json(rig).dump();
  for (int c = 0; c < 2; ++c) {
    fs::create_directories(dir / ("s" + std::to_string(c)));
    for (int k = 0; k < (c == 0 ? 6 : 3); ++k)
      write_image(dir / ("s" + std::to_string(c)) / ("f" + std::to_string(k) + ".png"),
                  cv::Mat(250, 250, CV_8UC3, cv::Scalar(40 + 20 * k, 100, 200 - 30 * c)));
  }
  const fs::path rec = dir / "rec";
  const RunResult r =
      run_omma("record --rig " + (dir / "rig.json").string() + " --source " + (dir / "s0").string() +
               " --source " + (dir / "s1").string() + " --fps 10 --frames 6 --out " + rec.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json cj = run_omma("recording check " + rec.string() + " --json").json();
  ASSERT_EQ(cj["frame_sets"], 6);
  ASSERT_EQ(cj["complete_sets"], 3);
  const std::string size = "--size 128x64 --projection equirect-full --method linear --no-cache";
  const std::vector<cv::Mat> regions = camera_regions(dir, rig, size);
  // The check sees a hole: camera 0 white, camera 1 black (camera_regions' first panorama).
  EXPECT_EQ(camera_holes(dir / "mask0" / "m.png", regions), 1);
  auto render = [&](const std::string& policy) {
    return run_omma("render " + rec.string() + " " + size + " --incomplete " + policy +
                    " --hold-max-age-ms 150 --out " + (dir / policy / "p_{set}.png").string() + " --json");
  };
  struct Expect {
    const char* policy;
    int held, skipped;
    std::vector<int> sets;
  };
  double held_age = 0;
  for (const Expect& e : {Expect{"skip", 0, 3, {0, 1, 2}}, Expect{"hold", 1, 2, {0, 1, 2, 3}}}) {
    const RunResult p = render(e.policy);
    ASSERT_EQ(p.exit_code, 0) << e.policy << "\n" << p.err;
    const json fj = p.json()["frame_sets"];
    EXPECT_EQ(fj["policy"], e.policy);
    EXPECT_EQ(fj["incomplete"], 3);
    EXPECT_EQ(fj["held_sets"], e.held);
    EXPECT_EQ(fj["skipped"], e.skipped);
    EXPECT_EQ(fj["rendered"], e.sets.size());
    // Warned with the counts on stderr; stated in the output manifest.
    EXPECT_TRUE(
        has(p.err, fmt::format("3 of 6 frame sets lack cameras (--incomplete {}): {} completed with held "
                               "frames",
                               e.policy, e.held)))
        << p.err;
    EXPECT_TRUE(has(p.err, fmt::format("{} skipped", e.skipped))) << p.err;
    const json m = json::parse(slurp(dir / e.policy / "render-manifest.json"));
    EXPECT_EQ(m["input"]["policy"], e.policy);
    EXPECT_EQ(m["input"]["skipped"], e.skipped);
    EXPECT_EQ(m["parameters"]["incomplete"], e.policy);
    // The panoramas made, named after their frame sets, none with a black camera.
    std::vector<int> made;
    for (int s = 0; s < 6; ++s)
      if (fs::exists(dir / e.policy / fmt::format("p_{:05d}.png", s))) {
        made.push_back(s);
        EXPECT_EQ(camera_holes(dir / e.policy / fmt::format("p_{:05d}.png", s), regions), 0) << e.policy << s;
      }
    EXPECT_EQ(made, e.sets) << e.policy;
    if (e.held > 0) held_age = fj["max_held_age_s"];
  }
  EXPECT_GT(held_age, 0.05);  // camera 1's last frame, about one period (100 ms) before set 3
  EXPECT_LE(held_age, 0.15);
  const RunResult f = render("fail");
  expect_error(f, "frame set 3 lacks camera(s) 1; 3 of 6 frame sets are incomplete", "fail");
  EXPECT_FALSE(fs::exists(dir / "fail" / "p_00000.png"));
  expect_error(render("zero"), "--incomplete must be skip, hold or fail", "bad policy");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace omma::test
