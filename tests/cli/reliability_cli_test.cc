// Bad input from the command line: each test reproduces a case of bad input that used to crash,
// hang, exit with CLI11's codes or give a wrong result with exit 0.
#include <filesystem>
#include <fstream>
#include <regex>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "omma/core/limits.h"
#include "omma/core/rig.h"
#include "omma/design/prototype.h"
#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {
namespace fs = std::filesystem;

nlohmann::json prototype_json() { return rig_to_json(design::thesis_prototype_rig()); }

fs::path write_json(const fs::path& dir, const std::string& name, const nlohmann::json& j) {
  std::ofstream(dir / name) << j.dump();
  return dir / name;
}

// CLI11's parse errors used to exit 105/106/109/114 without "omma: error:"; `--threads -1`
// printed the range 0 .. DBL_MAX in 309 digits.
TEST(Reliability, CommandLineErrorsExitOneWithOneClearLine) {
  const RunResult threads = run_omma("run --rig x.json --source sim:colon --threads -1");
  expect_error(threads, "--threads", "--threads -1");
  EXPECT_FALSE(std::regex_search(threads.err, std::regex("[0-9]{20}"))) << threads.err;
  expect_error(run_omma("optics --no-such-option"), "no-such-option", "unknown option");
  expect_error(run_omma("rig check"), "RIG", "missing positional");
  expect_error(run_omma("stitch --rig"), "--rig", "option without its value");
  const RunResult v = run_omma("--version");
  EXPECT_EQ(v.exit_code, 0);
  std::ifstream version_file(std::string(OMMA_SOURCE_DIR) + "/VERSION");
  std::string version;
  std::getline(version_file, version);
  // The first line is the version; the build configuration follows (Manners.VersionShowsBuild...).
  EXPECT_EQ(v.out.substr(0, v.out.find('\n') + 1), "omma " + version + "\n");
}

// Numbers that wrap or underflow, wrong types, unknown versions and huge
// camera counts in rig files are refused by `omma rig check` and by every command that loads a rig.
TEST(Reliability, RigFilesWithOutOfRangeNumbersAreRefused) {
  const fs::path dir = temp_dir("rel-rig");
  struct Case {
    const char* name;
    void (*edit)(nlohmann::json&);
    const char* part;
  };
  const Case cases[] = {
      {"tiny-focal", [](nlohmann::json& j) { j["cameras"][3]["intrinsics"]["fu"] = 1e-320; }, "focal length"},
      {"wide", [](nlohmann::json& j) { j["cameras"][0]["intrinsics"]["width"] = 4294967546ull; },
       "out of range"},
      {"name", [](nlohmann::json& j) { j["name"] = 17; }, "'name' must be a string"},
      {"version", [](nlohmann::json& j) { j["version"] = 99; }, "version 99"},
  };
  for (const Case& c : cases) {
    nlohmann::json j = prototype_json();
    c.edit(j);
    const fs::path rig = write_json(dir, std::string(c.name) + ".json", j);
    expect_error(run_omma("rig check " + rig.string()), c.part, c.name);
  }
  // The crash of the adversarial run: the simulator on a camera with fu = 1e-320 (was exit 139).
  expect_error(run_omma("simulate --rig " + (dir / "tiny-focal.json").string() + " --scene checker --out " +
                        (dir / "sim").string()),
               "focal length", "simulate, tiny focal");
  EXPECT_FALSE(fs::exists(dir / "sim"));
  // More cameras than the map format and the renderer hold (10^5 took 7.4 s and passed).
  nlohmann::json many = prototype_json();
  const nlohmann::json cam = many["cameras"][0];
  many["cameras"] = nlohmann::json::array();
  for (int i = 0; i < kMaxCameras + 1; ++i) {
    many["cameras"].push_back(cam);
    many["cameras"].back()["id"] = i;
  }
  expect_error(run_omma("rig check " + write_json(dir, "many.json", many).string()), "limit is 4096",
               "cameras");
  fs::remove_all(dir);
}

// Endless or special files used to be read into memory without limit (4.1 GB in 25 s).
TEST(Reliability, DevicesAndFoldersAreRefusedBeforeReading) {
  const fs::path dir = temp_dir("rel-dev");
  expect_error(run_omma("rig check /dev/zero", 20), "not a regular file", "rig /dev/zero");
  expect_error(run_omma("pto import /dev/zero " + (dir / "r.json").string(), 20), "not a regular file",
               "pto");
  expect_error(run_omma("link decode /dev/zero " + (dir / "f").string(), 20), "not a regular file", "link");
  EXPECT_FALSE(fs::exists(dir / "r.json"));
  fs::remove_all(dir);
}

// `omma run --size 65536x65536` used to run for minutes; every size option has the same bounds
// (core/limits.h), as `omma stitch` had.
TEST(Reliability, HugePanoramaSizesAreRefused) {
  const fs::path dir = temp_dir("rel-size");
  const fs::path rig = write_json(dir, "rig.json", prototype_json());
  expect_error(
      run_omma("run --rig " + rig.string() + " --source sim:colon --frames 1 --no-cache --size 65536x65536",
               30),
      "out of range", "run --size");
  expect_error(run_omma("stitch --rig " + rig.string() + " --frames " + dir.string() + " --out " +
                        (dir / "o").string() + " --size 65536x65536"),
               "out of range", "stitch");
  expect_error(run_omma("simulate --scene checker --truth-size 65536x65536 --out " + (dir / "s").string()),
               "out of range", "simulate");
  fs::remove_all(dir);
}

// A PTO value that is not a number, through the command (pto_test.cc checks the parser).
TEST(Reliability, MalformedPtoIsRefused) {
  const fs::path dir = temp_dir("rel-pto");
  std::ofstream(dir / "p.pto") << "i w250 h250 f0 v60 y1e999 p0 r0 n\"cam_00.png\"\n";
  expect_error(run_omma("pto import " + (dir / "p.pto").string() + " " + (dir / "r.json").string()),
               "not a finite number", "pto ynan");
  EXPECT_FALSE(fs::exists(dir / "r.json"));
  fs::remove_all(dir);
}

// ff ff ff ff at byte 36 of a cached map used to crash `omma run` (exit 139 or 134); other
// damage rendered a different panorama with exit 0. Now: a warning, the map compiled again and
// the same panorama as before.
TEST(Reliability, DamagedMapCacheIsRecompiledWithAWarning) {
  const fs::path dir = temp_dir("rel-cache");
  const fs::path rig = write_json(dir, "rig.json", prototype_json());
  auto run = [&](const std::string& out) {
    return run_omma("run --rig " + rig.string() + " --source pano:" + data_dir() +
                    "/lake.jpg@0 --frames 1 --size 216x216 --method mrf --fps 0 --cache " +
                    (dir / "cache").string() + " --sink png:" + (dir / out).string());
  };
  const RunResult first = run("first");
  ASSERT_EQ(first.exit_code, 0) << first.err;
  fs::path map;
  for (const auto& e : fs::directory_iterator(dir / "cache")) map = e.path();
  ASSERT_TRUE(fs::is_regular_file(map));
  auto first_png = [&](const std::string& out) {
    for (const auto& e : fs::directory_iterator(dir / out)) return cv::imread(e.path().string());
    return cv::Mat();
  };
  const cv::Mat want = first_png("first");
  ASSERT_FALSE(want.empty());
  for (const auto& [at, name] : {std::pair<long, std::string>{36, "a"}, {5000, "b"}}) {
    {
      std::fstream f(map, std::ios::in | std::ios::out | std::ios::binary);
      f.seekp(at);
      f.write("\xff\xff\xff\xff", 4);
    }
    const RunResult again = run(name);
    ASSERT_EQ(again.exit_code, 0) << again.err;
    EXPECT_TRUE(has(again.err, "not used")) << again.err;
    const cv::Mat got = first_png(name);
    ASSERT_EQ(got.size(), want.size());
    EXPECT_EQ(cv::norm(got, want, cv::NORM_INF), 0) << "byte " << at;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace omma::test
