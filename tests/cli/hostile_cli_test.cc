// Hostile input from the command line, third round: lenses that folded the simulator's arithmetic
// into NaN, file-size limits and hang-ups that killed commands mid-write, hardware files taken on
// trust, a depth surface inside the dome, and numbers (NaN, inf, 1e308, -1, 1e23, "3abc") that
// options used to take. Each test reproduces cases that crashed, hung or gave a wrong result with
// exit 0 before the fix.
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {
namespace fs = std::filesystem;

nlohmann::json read_json(const fs::path& p) { return nlohmann::json::parse(slurp(p)); }

fs::path write_json(const fs::path& p, const nlohmann::json& j) {
  std::ofstream(p) << j.dump();
  return p;
}

// Files whose name marks a temporary of an interrupted write (core/io.h, tiff_writer.h, simulate).
std::vector<std::string> temporaries(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    const std::string n = e.path().filename().string();
    if (has(n, ".tmp") || has(n, ".partial")) out.push_back(n);
  }
  return out;
}

// k1 = -0.3 (ordinary barrel distortion) made the simulator's inverse diverge to NaN, and a NaN
// indexed the sRGB table: `omma simulate` died of SIGSEGV. k1 = 2.5 diverged the same way. A lens
// that folds inside its field is now refused by the rig check, one that does not simulates.
TEST(Hostile, StrongLensesSimulateAndFoldingLensesAreRefused) {
  const fs::path dir = louvre_frames_folder("hostile_lens");
  nlohmann::json rig = read_json(dir / "rig.json");
  for (const double k1 : {-0.3, 2.5}) {
    for (auto& c : rig["cameras"]) c["intrinsics"]["k"] = {k1, 0, 0, 0, 0};
    const fs::path file = write_json(dir / "lens.json", rig);
    const RunResult check = run_omma("rig check " + file.string());
    EXPECT_EQ(check.exit_code, 0) << k1 << check.err;
    const fs::path out = dir / ("sim_" + std::to_string(k1));
    const RunResult sim =
        run_omma("simulate --rig " + file.string() + " --scene checker --out " + out.string());
    ASSERT_EQ(sim.exit_code, 0) << "k1 = " << k1 << "\n" << sim.err;
    const cv::Mat frame = cv::imread((out / "cam_00.png").string());
    ASSERT_FALSE(frame.empty());
    EXPECT_GT(cv::mean(frame)[1], 10) << "k1 = " << k1;  // the checker seen, not black
  }
  // The cone (aov 120 deg: 60 deg off the axis) reaches past k1 = -0.3's fold at 46.5 deg.
  for (auto& c : rig["cameras"]) {
    c["intrinsics"]["k"] = {-0.3, 0, 0, 0, 0};
    c["intrinsics"]["aov_deg"] = 120;
  }
  const fs::path folding = write_json(dir / "folding.json", rig);
  expect_error(run_omma("rig check " + folding.string()), "folds back at 46.5 deg", "rig check");
  expect_error(
      run_omma("simulate --rig " + folding.string() + " --scene checker --out " + (dir / "x").string()),
      "folds back", "simulate");
  // Scene numbers that overflowed to inf and NaN inside the simulator.
  const std::string r = (dir / "rig.json").string();
  expect_error(run_omma("simulate --rig " + r + " --scene flat:1e308 --out " + (dir / "f").string()),
               "flat scene", "flat:1e308");
  expect_error(run_omma("simulate --rig " + r + " --scene checker:1e300 --out " + (dir / "c").string()),
               "checker scene", "checker:1e300");
  expect_error(run_omma("run --rig " + r + " --source 'sim:colon@1e308' --duration 1"), "rate", "sim@1e308");
  EXPECT_FALSE(fs::exists(dir / "x"));
  fs::remove_all(dir);
}

// Under `ulimit -f` the kernel's SIGXFSZ killed commands mid-write (exit 153, no message, temporaries
// left). SIGXFSZ is ignored now: the write fails like on a full disk, with an error and no debris.
TEST(Hostile, FileSizeLimitGivesAnErrorAndLeavesNoTemporaries) {
  const fs::path dir = louvre_frames_folder("hostile_fsize");
  const fs::path out = dir / "out";
  fs::create_directories(out);
  const std::string r = (dir / "rig.json").string(), f = dir.string(), o = out.string();
  for (const std::string& args :
       {"stitch --rig " + r + " --frames " + f + " --out " + o + "/s.png --size 1024x1024",
        "render " + f + " --rig " + r + " --out " + o + "/big.tif --size 2048x1024 --no-cache",
        "simulate --rig " + r + " --scene checker --out " + o + "/sim",
        "pto export " + r + " " + o + "/p.pto"}) {
    const RunResult res =
        run_command("sh -c 'ulimit -f 2; exec " + std::string(OMMA_BINARY) + " " + args + "'");
    EXPECT_EQ(res.exit_code, 1) << args << "\n" << res.err;
    EXPECT_TRUE(has(res.err, "omma: error:")) << args << "\n" << res.err;
    EXPECT_EQ(temporaries(out), std::vector<std::string>{}) << args;
  }
  fs::remove_all(dir);
}

// SIGHUP (the terminal or the ssh session gone) killed `omma run` and left only .v.partial.mp4:
// it now stops the run like SIGTERM, and the video is finished and playable.
TEST(Hostile, HangUpFinishesTheVideo) {
  const fs::path dir = louvre_frames_folder("hostile_hup");
  const fs::path video = dir / "v.mp4";
  const std::string cmd = std::string(OMMA_BINARY) + " run --rig " + (dir / "rig.json").string() +
                          " --source frames:" + dir.string() + " --sink " + video.string() +
                          " --size 256x256 --fps 20 --duration 60 --json > " + (dir / "run.json").string() +
                          " 2>/dev/null & pid=$!; sleep 4; kill -HUP $pid; wait $pid";
  const auto t0 = std::chrono::steady_clock::now();
  const RunResult r = run_command(cmd, 120);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_LT(seconds, 30);  // stopped by the hang-up, not by --duration 60
  ASSERT_TRUE(fs::exists(video));
  EXPECT_EQ(temporaries(dir), std::vector<std::string>{});
  const RunResult probe = run_command(
      "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
      "stream=nb_read_frames -of csv=p=0 " +
      video.string());
  ASSERT_EQ(probe.exit_code, 0) << probe.err;
  EXPECT_GT(std::atoi(probe.out.c_str()), 10) << probe.out;
  fs::remove_all(dir);
}

// `omma hw import` read integers modulo 2^32, took any grid width and ignored the vignetting memory:
// an export and import dropped the rig's photometric model without a word.
TEST(Hostile, HardwareFilesAreCheckedAndKeepThePhotometricModel) {
  const fs::path dir = louvre_frames_folder("hostile_hw");
  nlohmann::json rig = read_json(dir / "rig.json");
  int i = 0;
  for (auto& c : rig["cameras"])
    c["photometric"] = {{"vignetting", {-0.25, 0.04, -0.01}},
                        {"vignetting_center_px", {0, 0}},
                        {"gains_bgr", {1.1, 1.0, 0.9 + 0.01 * i++}}};
  const fs::path rp = write_json(dir / "photometric.json", rig);
  const fs::path chip = dir / "chip";
  ASSERT_EQ(run_omma("hw export " + rp.string() + " " + chip.string()).exit_code, 0);
  const RunResult im =
      run_omma("hw import " + chip.string() + " " + (dir / "back.json").string() + " --json");
  ASSERT_EQ(im.exit_code, 0) << im.err;
  EXPECT_EQ(im.json()["photometric_cameras"].get<int>(), int(rig["cameras"].size()));
  EXPECT_LT(im.json()["vignetting_fit_error"].get<double>(), 1e-3);
  const nlohmann::json back = read_json(dir / "back.json");
  for (size_t c = 0; c < rig["cameras"].size(); ++c)
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(back["cameras"][c]["photometric"]["gains_bgr"][k].get<double>(),
                  rig["cameras"][c]["photometric"]["gains_bgr"][k].get<double>(), 1e-3);
  EXPECT_NEAR(back["cameras"][0]["photometric"]["vignetting"][0].get<double>(), -0.25, 0.01);

  const nlohmann::json config = read_json(chip / "config.json");
  auto import_with = [&](const nlohmann::json& c) {
    write_json(chip / "config.json", c);
    const RunResult r = run_omma("hw import " + chip.string() + " " + (dir / "x.json").string());
    write_json(chip / "config.json", config);
    return r;
  };
  nlohmann::json wrap = config;
  wrap["hw"]["angle_bits"] = 4294967316ULL;  // 2^32 + 20: ran as 20
  expect_error(import_with(wrap), "angle_bits must be an integer", "angle_bits 2^32+20");
  for (const nlohmann::json& w : {nlohmann::json(-64), nlohmann::json(0), nlohmann::json(4294967360ULL),
                                  nlohmann::json(1080.5), nlohmann::json("1080")}) {
    nlohmann::json g = config;
    g["grid"]["width"] = w;
    expect_error(import_with(g), "grid width", "grid width " + w.dump());
  }
  // An empty vignetting memory, or one of a rig with another camera count: refused, not unit gains.
  const std::string pix_val = slurp(chip / "pix_val.hex");
  std::ofstream(chip / "pix_val.hex") << "";
  expect_error(run_omma("hw import " + chip.string() + " " + (dir / "x.json").string()), "vignetting entry",
               "empty pix_val.hex");
  std::ofstream(chip / "pix_val.hex") << pix_val.substr(0, pix_val.find('\n', pix_val.size() / 2) + 1);
  expect_error(run_omma("hw import " + chip.string() + " " + (dir / "x.json").string()), "missing",
               "half a pix_val.hex");
  EXPECT_FALSE(fs::exists(dir / "x.json"));
  fs::remove_all(dir);
}

// A depth file putting the surface inside the dome rendered an all-black panorama with exit 0 (and
// "inter-camera PSNR inf dB"), while --depth sphere:R inside the dome was refused.
TEST(Hostile, DepthFileInsideTheDomeIsRefused) {
  const fs::path dir = louvre_frames_folder("hostile_depth");
  cv::Mat depth(128, 128, CV_32FC1, cv::Scalar(2.0f));  // 2 mm: the cameras sit 5 mm out
  ASSERT_TRUE(cv::imwrite((dir / "depth.tif").string(), depth));
  const RunResult r = run_omma("stitch --rig " + (dir / "rig.json").string() + " --frames " + dir.string() +
                               " --size 128x128 --out " + (dir / "p.png").string() +
                               " --depth truth:" + (dir / "depth.tif").string());
  expect_error(r, "inside the dome", "depth file at 2 mm");
  EXPECT_FALSE(fs::exists(dir / "p.png"));
  fs::remove_all(dir);
}

// Numbers options used to take: NaN through every range check, inf into JSON as null, values that
// overflowed (fps 1e-300 lifted the rate limit, coverage at 1e155 mm), wrapped (seed -1 and 1e23
// as 2^64 - 1, STEPS 2^31 as -2^31) or were read by prefix (--sets 1:3abc as 1..2). Each is refused
// at once (before the simulator's start-up, before a render) with the option named.
TEST(Hostile, NumbersAreFiniteInRangeAndWhole) {
  const fs::path dir = louvre_frames_folder("hostile_numbers");
  const std::string r = (dir / "rig.json").string(), f = dir.string(), o = (dir / "o.png").string();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"stitch --rig " + r + " --frames " + f + " --out " + o + " --threshold nan", "--threshold"},
      {"simulate --rig " + r + " --scene checker --out " + f + "/s --seed -1", "--seed"},
      {"simulate --rig " + r + " --scene checker --out " + f + "/s --seed 1e23", "--seed"},
      {"simulate --rig " + r + " --scene checker --out " + f + "/s --exposure inf", "--exposure"},
      {"hw memory --fps inf", "--fps"},
      {"optics --channel-diameter 1e308", "channel diameter"},
      {"coverage " + r + " --distance 1e155", "--distance"},
      {"link encode " + f + "/cam_00.png " + f + "/l.bin --flip-rate nan", "--flip-rate"},
      {"run --rig " + r + " --source sim:colon --fps 1e-300 --duration 1", "fps"},
      {"run --rig " + r + " --source sim:colon --duration nan", "--duration"},
      {"run --rig " + r + " --source sim:colon --source-fps nan", "--source-fps"},
      {"stitch --rig " + r + " --frames " + f + " --out " + o + " --depth estimate:6,1e308", "far distance"},
      {"stitch --rig " + r + " --frames " + f + " --out " + o + " --depth estimate:6,20,2147483648",
       "got 2147483648"},
      {"render " + f + " --rig " + r + " --out " + f + "/p.png --sets 1:3abc", "--sets"},
      {"render " + f + " --rig " + r + " --out " + f + "/p.jpg --size 65520x64", "at most 65500"},
  };
  for (const auto& [args, part] : cases) {
    const auto t0 = std::chrono::steady_clock::now();
    expect_error(run_omma(args, 60), part, args);
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 10) << args;
  }
  // Decimal, not octal: --seed 010 is ten.
  const RunResult ten =
      run_omma("simulate --rig " + r + " --scene checker --out " + f + "/s10 --seed 010 --json");
  ASSERT_EQ(ten.exit_code, 0) << ten.err;
  EXPECT_EQ(ten.json()["seed"].get<uint64_t>(), 10u);
  fs::remove_all(dir);
}

// A tile render killed mid-write (SIGKILL) left big.tif.tmpPID behind for good, even after a
// successful rerun. The rerun now removes temporaries of processes that have ended, and only those.
TEST(Hostile, KilledRenderTemporaryIsRemovedByTheNextRender) {
  const fs::path dir = louvre_frames_folder("hostile_tiles");
  const fs::path dead = dir / "big.tif.tmp999999999",
                 alive = dir / ("big.tif.tmp" + std::to_string(::getpid()));
  std::ofstream(dead) << "left by a killed render";
  std::ofstream(alive) << "being written by a live process";
  const RunResult r =
      run_omma("render " + dir.string() + " --rig " + (dir / "rig.json").string() + " --out " +
               (dir / "big.tif").string() + " --split tiles --size 512x256 --no-cache");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir / "big.tif"));
  EXPECT_FALSE(fs::exists(dead));
  EXPECT_TRUE(fs::exists(alive));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace omma::test
