// CLI tests for omma design, coverage, sweep and optics (thesis ch. 3).
#include <fstream>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "omma/core/rig.h"
#include "omma/core/version.h"
#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {
namespace fs = std::filesystem;

TEST(DesignCli, MaxVolumeReproducesThePrototype) {
  const auto dir = temp_dir("design");
  const RunResult r =
      run_omma("design --method max-volume --cam-size 1x1x2 --json --out " + (dir / "rig.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = r.json();
  EXPECT_EQ(j.size(), 5u);  // exactly {method, cameras, layers, r_virtual_mm, omma_version}
  EXPECT_EQ(j["omma_version"], omma::version());
  EXPECT_EQ(j["method"], "max-volume");
  EXPECT_EQ(j["cameras"], 24);
  EXPECT_EQ(j["layers"], nlohmann::json({3, 9, 12}));
  EXPECT_NEAR(j["r_virtual_mm"].get<double>(), 14.0, 0.1);
  const Rig rig = load_rig(dir / "rig.json");
  EXPECT_EQ(rig.cameras.size(), 24u);
  // Table 3.1's 1.85 mm camera length puts 13 cameras in the third layer.
  const auto j2 = run_omma("design --method max-volume --cam-size 1x1x1.85 --json").json();
  EXPECT_EQ(j2["layers"], nlohmann::json({3, 9, 13}));
  fs::remove_all(dir);
}

TEST(DesignCli, MinCamerasAgainstLayeredAtFifteenMillimetres) {
  const auto layered = run_omma("design --method layered --r-virtual 15 --json").json();
  const auto mincam = run_omma("design --method min-cameras --r-virtual 15 --json").json();
  EXPECT_EQ(layered["cameras"], 29);
  EXPECT_GE(mincam["cameras"].get<int>(), 22);
  EXPECT_LE(mincam["cameras"].get<int>(), 25);
  EXPECT_LE(mincam["r_virtual_mm"].get<double>(), 15.0);
  const auto cvt = run_omma("design --method cvt --sphere --r-virtual 18 --json").json();
  EXPECT_GE(cvt["cameras"].get<int>(), 36);
  EXPECT_LE(cvt["cameras"].get<int>(), 48);
}

TEST(DesignCli, BadOptionsFailClearlyAndWriteNothing) {
  const auto dir = temp_dir("design-bad");
  const std::string out = " --out " + (dir / "rig.json").string();
  struct Case {
    std::string args, message;
  };
  for (const Case& c : std::vector<Case>{{"--method voronoi", "voronoi"},
                                         {"--cam-size 1x1", "WxHxL"},
                                         {"--cam-size 1x1x7", "camera length"},
                                         {"--aov 200", "aov"},
                                         {"--method min-cameras --r-virtual 4", "r_virtual"},
                                         {"--r-phys -1", "r-phys"}}) {
    const RunResult r = run_omma("design " + c.args + out + " --json");
    EXPECT_NE(r.exit_code, 0) << c.args;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.args << ": " << r.err;
    EXPECT_TRUE(r.out.empty()) << c.args;
    EXPECT_FALSE(fs::exists(dir / "rig.json")) << c.args;
  }
  fs::remove_all(dir);
}

TEST(CoverageCli, PrototypeStatisticsAndMap) {
  const auto dir = temp_dir("coverage");
  ASSERT_EQ(run_omma("design --out " + (dir / "rig.json").string()).exit_code, 0);
  const RunResult r = run_omma("coverage " + (dir / "rig.json").string() +
                               " --distance 18 --step 0.5 --json --map " + (dir / "map.png").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = r.json();
  for (const char* key :
       {"distance_mm", "covered_fraction", "min_cameras", "max_cameras", "mean_cameras", "r_virtual_mm"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_DOUBLE_EQ(j["distance_mm"].get<double>(), 18.0);
  EXPECT_DOUBLE_EQ(j["covered_fraction"].get<double>(), 1.0);
  EXPECT_GE(j["min_cameras"].get<int>(), 1);
  EXPECT_GE(j["max_cameras"].get<int>(), 3);
  EXPECT_GT(j["mean_cameras"].get<double>(), 1.5);
  EXPECT_NEAR(j["r_virtual_mm"].get<double>(), 14.0, 0.1);
  const cv::Mat map = cv::imread((dir / "map.png").string());
  ASSERT_FALSE(map.empty());
  EXPECT_EQ(map.cols, 1440);
  EXPECT_GT(map.rows, 360);  // 1440 x 360 map plus the legend
  // Closer than R_vir there are gaps (black pixels in the map).
  const auto near =
      run_omma("coverage " + (dir / "rig.json").string() + " --distance 8 --step 0.5 --json").json();
  EXPECT_LT(near["covered_fraction"].get<double>(), 0.9);
  EXPECT_EQ(near["min_cameras"], 0);
  fs::remove_all(dir);
}

TEST(CoverageCli, BadRigFilesAndOptionsFail) {
  const auto dir = temp_dir("coverage-bad");
  std::ofstream(dir / "notjson.json") << "{ this is not json";
  std::ofstream(dir / "badframe.json") << R"({"format": "omma-rig", "version": 1, "dome": {"radius_mm": 5},
            "cameras": [{"id": 0, "t": [0,0,1], "u": [0,1,0], "v": [0,1,0], "position_mm": [0,0,5],
              "intrinsics": {"width": 250, "height": 250, "fu": 200, "fv": 200, "cu": 125,
                             "cv": 125, "k": [0,0,0,0,0], "aov_deg": 64}}]})";
  const std::string map = " --map " + (dir / "map.png").string();
  for (const std::string& args :
       {(dir / "missing.json").string(), (dir / "notjson.json").string(), (dir / "badframe.json").string()}) {
    const RunResult r = run_omma("coverage " + args + map + " --json");
    EXPECT_EQ(r.exit_code, 1) << args;
    EXPECT_NE(r.err.find("omma: error:"), std::string::npos) << r.err;
    EXPECT_TRUE(r.out.empty());
    EXPECT_FALSE(fs::exists(dir / "map.png"));
  }
  ASSERT_EQ(run_omma("design --out " + (dir / "rig.json").string()).exit_code, 0);
  for (const char* opt : {"--step 0", "--distance -3", "--map-width 2"}) {
    const RunResult r = run_omma("coverage " + (dir / "rig.json").string() + " " + opt + map);
    EXPECT_NE(r.exit_code, 0) << opt;
    EXPECT_FALSE(fs::exists(dir / "map.png")) << opt;
  }
  fs::remove_all(dir);
}

TEST(SweepCli, SmallSweepWritesCsvAndPlots) {
  const auto dir = temp_dir("sweep");
  const RunResult r = run_omma("sweep --out-dir " + (dir / "s").string() +
                               " --r-virtual 12 30 --aov-min 60 --aov-max 68 --aov-step 4"
                               " --ratio-min 2.4 --ratio-max 3.6 --ratio-step 0.6 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = r.json();
  EXPECT_EQ(j["rows"], 2 * 3 * 3 + 2 * 3);
  std::ifstream csv(dir / "s" / "sweep.csv");
  std::string line;
  int lines = 0;
  while (std::getline(csv, line)) ++lines;
  EXPECT_EQ(lines, 1 + 2 * 3 * 3 + 2 * 3);
  for (const char* f : {"cameras_vs_aov.svg", "cameras_vs_ratio.svg"}) {
    std::ifstream svg(dir / "s" / f);
    const std::string text((std::istreambuf_iterator<char>(svg)), {});
    EXPECT_NE(text.find("</svg>"), std::string::npos) << f;
    EXPECT_NE(text.find("cameras needed"), std::string::npos) << f;
  }
  const RunResult bad = run_omma("sweep --out-dir " + (dir / "t").string() + " --aov-step 0");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_FALSE(fs::exists(dir / "t" / "sweep.csv"));
  fs::remove_all(dir);
}

TEST(OpticsCli, ThesisNumbers) {
  const RunResult r = run_omma("optics --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = r.json();
  EXPECT_NEAR(j["delta_phi_deg"].get<double>(), 0.26, 0.01);
  EXPECT_NEAR(j["illumination_lm"].get<double>(), 93.2, 0.3);
  EXPECT_NEAR(j["r_ideal_mm"].get<double>(), 3.3, 0.05);
  EXPECT_NEAR(j["size_efficiency"].get<double>(), 0.18, 0.005);
  const auto half = run_omma("optics --distance 40 --json").json();
  EXPECT_NEAR(half["illumination_lm"].get<double>(), j["illumination_lm"].get<double>() / 4, 1e-9);
  const RunResult bad = run_omma("optics --aperture 0 --json");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("aperture"), std::string::npos);
}

}  // namespace
}  // namespace omma::test
