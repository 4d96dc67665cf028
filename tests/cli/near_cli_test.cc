// CLI tests of near scenes at Giga-Eye's scale: omma render --depth (band by band, one process and
// under mpirun) and omma refocus on the simulated room (sim/room.h).
#include <filesystem>

#include <gtest/gtest.h>

#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {

namespace fs = std::filesystem;

// The room seen by Giga-Eye at a test size (skip5: 432 x 324 per camera, one ray per pixel), with a
// 900 x 250 equirect-100 truth and its depth.
class NearSim : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(temp_dir("near-sim"));
    const auto s =
        run_omma("simulate --rig gigaeye-44-skip5 --scene room --out " + frames() +
                 " --projection equirect-100 --truth-size 900x250 --supersample 1 --truth-supersample 1 "
                 "--json");
    ASSERT_EQ(s.exit_code, 0) << s.err;
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
  }
  static std::string frames() { return (*dir_ / "f").string(); }
  static std::string out(const std::string& name) { return (*dir_ / name).string(); }
  // omma render FRAMES --depth SPEC at 900x250 against the truth: its --json summary.
  static nlohmann::json render(const std::string& depth, const std::string& name,
                               const std::string& extra = "") {
    const auto r =
        run_omma("render " + frames() + " --size 900x250 --no-cache --band-rows 64 --depth " + depth +
                 " --out " + out(name) + " --truth " + frames() + "/truth.png --json " + extra);
    EXPECT_EQ(r.exit_code, 0) << depth << ": " << r.err;
    return r.exit_code == 0 ? r.json() : nlohmann::json();
  }
  static fs::path* dir_;
};
fs::path* NearSim::dir_ = nullptr;

TEST_F(NearSim, RenderDepthBeatsEverySphere) {
  // Measured (PanoRenderDepth.* in render/, the same scene): infinity 20.2, best sphere (2 m) 21.9,
  // true depth 25.1, estimate 25.4 dB.
  const double inf = render("inf", "inf.png")["quality"]["psnr_db"];
  double best = 0;
  for (const char* r : {"sphere:1000", "sphere:2000", "sphere:4000"})
    best = std::max(best, render(r, "sphere.png")["quality"]["psnr_db"].get<double>());
  const auto truth = render("truth:" + frames() + "/truth_depth.tiff", "truth.png");
  const auto est = render("estimate", "estimate.png");
  EXPECT_GT(best, inf + 1);
  EXPECT_GT(truth["quality"]["psnr_db"].get<double>(), best + 2);
  EXPECT_GT(est["quality"]["psnr_db"].get<double>(), best + 2);
  EXPECT_EQ(est["depth"]["estimates"], 1);
  EXPECT_GT(est["depth"]["estimate_seconds_per_panorama"].get<double>(), 0);
}

TEST_F(NearSim, RenderDepthUnderMpirunIsTheSamePanorama) {
  const auto v = run_omma("--version");
  if (!has(v.out, "MPI (mpirun omma render): yes") || run_command("sh -c 'command -v mpirun'").exit_code != 0)
    GTEST_SKIP() << "omma was built without MPI or mpirun is missing";
  const auto one =
      run_omma("render " + frames() + " --size 900x250 --no-cache --band-rows 32 --depth estimate --out " +
               out("one.tif"));
  ASSERT_EQ(one.exit_code, 0) << one.err;
  const auto two = run_command(
      "mpirun --allow-run-as-root --oversubscribe -np 2 " + std::string(OMMA_BINARY) + " render " + frames() +
          " --size 900x250 --no-cache --band-rows 32 --depth estimate --split tiles --out " + out("two.tif"),
      300);
  ASSERT_EQ(two.exit_code, 0) << two.err;
  // Every rank estimates the same depth from the same frames: bit-identical bands.
  EXPECT_EQ(slurp(out("one.tif")), slurp(out("two.tif")));
}

TEST_F(NearSim, RenderDepthBadInput) {
  const std::string base = "render " + frames() + " --size 900x250 --no-cache --out " + out("bad.png");
  expect_error(run_omma(base + " --depth sphere:abc"), "sphere:R", "a radius that is no number");
  expect_error(run_omma(base + " --depth plane:3"), "--depth must be", "an unknown surface");
  expect_error(run_omma(base + " --depth estimate --method hq"), "hq", "depth with the offline blend");
  expect_error(run_omma(base + " --depth-pitch 1"), "--depth-pitch", "a pitch without an estimate");
  expect_error(run_omma(base + " --depth truth:" + out("missing.tiff")), "missing.tiff",
               "a missing depth file");
}

TEST_F(NearSim, RefocusStackAndBadInput) {
  const auto r = run_omma("refocus --rig gigaeye-44-skip5 --frames " + frames() +
                          " --focus 850 2590 --projection equirect-100 --size 900x250 --out " +
                          out("rf.png") + " --stack " + out("stack.png") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = r.json();
  ASSERT_EQ(j["outputs"].size(), 2u);
  EXPECT_TRUE(fs::exists(out("rf_00850mm.png")));
  EXPECT_TRUE(fs::exists(out("rf_02590mm.png")));
  // Giga-Eye's overlaps on spheres 0.85 and 2.59 m away: 2.04 and 2.78 cameras per direction on
  // average (measured; 1.43 m: 2.46), fewer the nearer the sphere.
  ASSERT_EQ(j["outputs"].size(), 2u);
  EXPECT_GT(j["outputs"][0]["mean_cameras"].get<double>(), 1.6);
  EXPECT_GT(j["outputs"][1]["mean_cameras"].get<double>(), j["outputs"][0]["mean_cameras"].get<double>());
  const std::string base =
      "refocus --rig gigaeye-44-skip5 --frames " + frames() + " --size 900x250 --out " + out("x.png");
  expect_error(run_omma(base + " --focus -5"), "--focus", "a negative focus");
  expect_error(run_omma(base + " --aperture wide"), "--aperture", "an aperture that is no number");
  expect_error(run_omma(base + " --combine max"), "max", "an unknown combination");
  expect_error(run_omma(base + " --focus-depth truth:" + out("missing.tiff")), "missing.tiff",
               "a missing depth file");
}

}  // namespace
}  // namespace omma::test
