// CLI tests of the Giga-Eye (thesis ch. 7): plan, coverage, simulate, render, record.
#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include <gtest/gtest.h>

#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {

namespace fs = std::filesystem;
std::string lake() { return data_dir() + "/lake.jpg"; }

// One simulation of the Giga-Eye (the skip-5 sensor mode, 432 x 324 per camera: a test size) of a
// far scene, shared by the render and record tests: cam_XX.png, 12-bit cam_XX_raw.png, a 720 x 200
// equirect-100 truth.
class GigaSim : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(temp_dir("giga-sim"));
    const auto s =
        run_omma("simulate --rig gigaeye-44-skip5 --scene photo:" + lake() + " --out " + frames() +
                 " --projection equirect-100 --truth-size 720x200 --raw --bits 12 --supersample 2 --json");
    ASSERT_EQ(s.exit_code, 0) << s.err;
    ASSERT_EQ(s.json()["cameras"], 44);
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
  }
  static std::string frames() { return (*dir_ / "f").string(); }
  static fs::path* dir_;
};
fs::path* GigaSim::dir_ = nullptr;

TEST(GigaPlanCli, Table71AndConstraints) {
  const auto t = run_omma("plan --table71 --json");
  ASSERT_EQ(t.exit_code, 0) << t.err;
  const auto j = t.json();
  ASSERT_EQ(j["rows"].size(), 8u);
  for (int i = 0; i < 7; ++i) EXPECT_TRUE(j["rows"][i]["matches"].get<bool>()) << i + 1;
  EXPECT_FALSE(j["rows"][7]["matches"].get<bool>());
  EXPECT_EQ(j["rows"][7]["fits_bits"], 8);
  EXPECT_NEAR(j["five_tb"]["tib"].get<double>(), 7.62, 0.005);
  EXPECT_NEAR(j["five_tb"]["tib_for_30_cameras"].get<double>(), 5.20, 0.005);
  // Table 7.2 (option 5): holds; option 1 fails on the clock and the SSD's write rate, named.
  const auto ok = run_omma("plan --row 5 --json");
  ASSERT_EQ(ok.exit_code, 0) << ok.err;
  EXPECT_TRUE(ok.json()["feasible"].get<bool>());
  EXPECT_NEAR(ok.json()["device"]["max_minutes"].get<double>(), 18.82, 0.01);
  const auto bad = run_omma("plan --row 1");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("omma: error: the plan does not hold: pixel-clock"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("device-write-rate"), std::string::npos);
  const auto full = run_omma("plan --row 2 --minutes 20");
  EXPECT_EQ(full.exit_code, 1);
  EXPECT_NE(full.err.find("device-capacity"), std::string::npos) << full.err;
  for (const char* args :
       {"plan --device-size 12parsecs", "plan --bits 0", "plan --per-device 50", "plan --fps -1"}) {
    const auto r = run_omma(args);
    EXPECT_EQ(r.exit_code, 1) << args;
    EXPECT_NE(r.err.find("omma: error:"), std::string::npos) << args << r.err;
  }
}

TEST(GigaCoverageCli, FourDistancesAndThePolarBand) {
  const auto r = run_omma(
      "coverage gigaeye-44 --distance 500 --distance 1000 --distance 5000 --distance inf "
      "--polar-max 100 --step 1 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = r.json();
  ASSERT_EQ(j["distances"].size(), 4u);
  const auto& inf = j["distances"][3];
  EXPECT_TRUE(inf["distance_mm"].is_null());
  // Far away: >= 2 cameras from polar ~34 deg to the bottom of the 360 x 100 field, at most 7
  // (thesis Fig. 7.5: "at most 7, at least 2"; near the pole only the zenith camera looks).
  EXPECT_NEAR(inf["band"]["from_deg"].get<double>(), 34, 2);
  EXPECT_EQ(inf["band"]["to_deg"].get<double>(), 100);
  EXPECT_EQ(inf["max_cameras"], 7);
  EXPECT_EQ(inf["min_cameras"], 1);
  // Closer, parallax opens gaps near the pole and narrows the band.
  const auto& near = j["distances"][0];
  EXPECT_LT(near["covered_fraction"].get<double>(), inf["covered_fraction"].get<double>());
  EXPECT_GT(near["band"]["from_deg"].get<double>(), inf["band"]["from_deg"].get<double>());
  const auto bad = run_omma("coverage gigaeye-44 --distance far");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("'far'"), std::string::npos);
  EXPECT_EQ(run_omma("coverage no-such-rig").exit_code, 1);
}

// The panorama from the simulated frames against the simulator's truth.
TEST_F(GigaSim, RenderAgainstTruth) {
  const auto dir = temp_dir("giga-render");
  double psnr[2] = {0, 0};
  int k = 0;
  for (const char* method : {"linear", "hq"}) {
    const auto r = run_omma("render " + frames() + " --size 720x200 --method " + method + " --out " +
                            (dir / (std::string(method) + ".tif")).string() + " --truth " + frames() +
                            "/truth.png" + " --band-rows 64 --no-cache --json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto j = r.json();
    EXPECT_EQ(j["bands"], 4);
    psnr[k++] = j["quality"]["psnr_db"].get<double>();
  }
  // Measured 28-29 dB (vignetting, gains and noise of the simulated sensors; lake.jpg): the
  // panorama is the scene, not just any image.
  EXPECT_GT(psnr[0], 25.0);
  EXPECT_NEAR(psnr[1], psnr[0], 0.5);
  // The 12-bit raw frames through the ISP give a panorama of the same scene.
  const auto raw =
      run_omma("render " + frames() + " --raw --size 720x200 --out " + (dir / "raw.png").string() +
               " --truth " + frames() + "/truth.png --no-cache --json");
  ASSERT_EQ(raw.exit_code, 0) << raw.err;
  EXPECT_GT(raw.json()["quality"]["psnr_db"].get<double>(), 20.0);
  fs::remove_all(dir);
}

TEST_F(GigaSim, RecordCheckRenderAndSurviveSigkill) {
  const auto dir = temp_dir("giga-record");
  const std::string rec = (dir / "rec").string();
  // The simulated frames as stills (frames:DIR), two frame sets.
  const auto r = run_omma("record --rig gigaeye-44-skip5 --source frames:" + frames() +
                          " --fps 4 --frames 2 --out " + rec + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto c = run_omma("recording check " + rec + " --json");
  ASSERT_EQ(c.exit_code, 0) << c.err;
  const auto cj = c.json();
  EXPECT_TRUE(cj["complete"].get<bool>());
  EXPECT_EQ(cj["cameras"], 44);
  EXPECT_EQ(cj["frames"].get<int>() + cj["dropped"].get<int>(), 2 * 44);
  EXPECT_GE(cj["frame_sets"].get<int>(), 2);
  const auto p = run_omma("render " + rec + " --sets 0:2 --size 360x100 --method nn --no-cache --out " +
                          (dir / "p_{set}.tif").string() + " --json");
  ASSERT_EQ(p.exit_code, 0) << p.err;
  EXPECT_TRUE(fs::exists(dir / "p_00000.tif"));
  EXPECT_TRUE(fs::exists(dir / "p_00001.tif"));
  // SIGKILL while recording: everything flushed before stays readable (at most the last flush
  // interval, 0.5 s, is lost). Stills at 10 fps: the frames arrive on time even on a busy machine.
  const std::string killed = (dir / "killed").string();
  const std::string pidfile = (dir / "pid").string();
  ASSERT_EQ(std::system(("sh -c '" OMMA_BINARY " record --rig gigaeye-44-skip5 --source frames:" + frames() +
                         " --fps 10 --duration 60 --out " + killed + " >/dev/null 2>&1 & echo $! > " +
                         pidfile + "'")
                            .c_str()),
            0);
  std::this_thread::sleep_for(std::chrono::seconds(5));
  const auto t_kill = std::chrono::system_clock::now();
  std::ifstream pf(pidfile);
  int pid = 0;
  pf >> pid;
  ASSERT_GT(pid, 0);
  ASSERT_EQ(std::system(("kill -9 " + std::to_string(pid)).c_str()), 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const auto k = run_omma("recording check " + killed + " --json");
  ASSERT_EQ(k.exit_code, 0) << k.err;
  const auto kj = k.json();
  EXPECT_FALSE(kj["complete"].get<bool>());
  EXPECT_GT(kj["frames"].get<int>(), 44);
  // The last frame read back was captured within the last second before the kill.
  const auto manifest = nlohmann::json::parse(std::ifstream(fs::path(killed) / "manifest.json"));
  const double start_s = manifest["start_unix_ns"].get<int64_t>() / 1e9;
  const double kill_s = std::chrono::duration<double>(t_kill.time_since_epoch()).count();
  EXPECT_GT(kj["last_frame_s"].get<double>(), kill_s - start_s - 1.0);
  fs::remove_all(dir);
}

TEST_F(GigaSim, FullDiskAndBadRecordings) {
  const auto dir = temp_dir("giga-full");
  const std::string rec = (dir / "rec").string();
  // A file-size limit (ulimit -f, 1 KiB blocks) stands for a disk that fills up: each camera's
  // stream may grow to 5000 KiB: the recorder stops after about 7 of its 280 kB frames (HDF5 starts
  // writing frames 1.3 MB into the file; the recorder keeps two frames and 1 MiB in reserve).
  const std::string err = (dir / "err").string();
  const int status = std::system(
      ("sh -c 'ulimit -f 5000; " OMMA_BINARY " record --rig gigaeye-44-skip5 --source frames:" + frames() +
       " --fps 20 --frames 12 --out " + rec + " >/dev/null 2>" + err + "'")
          .c_str());
  EXPECT_NE(status, 0);
  const std::string msg = [&] {
    std::ifstream f(err);
    return std::string(std::istreambuf_iterator<char>(f), {});
  }();
  EXPECT_NE(msg.find("omma: error: recording stopped:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("disk full"), std::string::npos) << msg;
  const auto c = run_omma("recording check " + rec + " --json");
  ASSERT_EQ(c.exit_code, 0) << c.err;
  EXPECT_GT(c.json()["frames"].get<int>(), 0);
  EXPECT_LT(c.json()["frames"].get<int>(), 12 * 44);
  // A truncated stream, a missing one, another sensor mode: clear errors, nothing rendered.
  fs::resize_file(fs::path(rec) / "cam_05.h5", 1000);
  auto bad = run_omma("recording check " + rec);
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("camera 5: stream"), std::string::npos) << bad.err;
  bad = run_omma("render " + rec + " --size 360x100 --out " + (dir / "x.tif").string());
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_FALSE(fs::exists(dir / "x.tif"));
  fs::remove(fs::path(rec) / "cam_05.h5");
  bad = run_omma("recording check " + rec);
  EXPECT_NE(bad.err.find("is missing"), std::string::npos) << bad.err;
  bad =
      run_omma("render " + rec + " --rig gigaeye-44-skip2 --size 360x100 --out " + (dir / "x.tif").string());
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_FALSE(fs::exists(dir / "x.tif"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace omma::test
