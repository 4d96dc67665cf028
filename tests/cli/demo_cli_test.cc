// omma demo, end to end at a small panorama size: every method is measured against the
// simulator's ground truth and the report is written.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {

TEST(DemoCli, SmallDemoMeasuresEveryMethod) {
  const auto dir = temp_dir("demo");
  const RunResult r = run_omma("demo --size 270x270 --json --out " + (dir / "d").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = r.json();
  EXPECT_EQ(j["cameras"], 24);
  ASSERT_EQ(j["methods"].size(), 6u);
  for (const auto& [name, m] : j["methods"].items()) {
    // Measured at 270x270 on the colon scene with the default sensor effects (vignetting, gains,
    // noise): 26-29 dB. A broken projection or weight drops far below 20 dB.
    EXPECT_GT(m["psnr_db"].get<double>(), 24.0) << name;
    EXPECT_LT(m["psnr_db"].get<double>(), 40.0) << name;
    EXPECT_GT(m["ssim"].get<double>(), 0.6) << name;
  }
  // Linear blending averages noise away: never worse than nearest neighbour by more than 0.2 dB.
  EXPECT_GT(j["methods"]["linear"]["psnr_db"].get<double>(),
            j["methods"]["nn"]["psnr_db"].get<double>() - 0.2);
  const double inter = j["inter_camera_psnr_db"].get<double>();
  EXPECT_GT(inter, 18.0);
  EXPECT_LT(inter, 40.0);
  // The real-time engine renders the same mrf panorama (its speed is the benchmark's business).
  EXPECT_GE(j["engine"]["psnr_vs_reference_db"].get<double>(), 50.0);
  EXPECT_GT(j["engine"]["fps"].get<double>(), 0.0);
  std::ifstream html(dir / "d" / "report.html");
  std::stringstream ss;
  ss << html.rdbuf();
  EXPECT_NE(ss.str().find("mrf-spherical"), std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(dir / "d" / "frames" / "cam_23.png"));
  std::filesystem::remove_all(dir);
}

TEST(DemoCli, GigaEyeNearSceneAtATestSize) {
  // omma demo --rig gigaeye-44 --scene room: the near section (depth, refocusing, 3D) with skip5
  // frames and a 1800 x 480 panorama (previews 360 x 96). Measured (two runs): infinity 23.4-23.5 dB,
  // best sphere (2 m) 26.3-26.4, estimate 29.7-29.8, true depth 27.2-27.5 (the estimate is above the
  // true depth: no visibility test per camera, docs/results/near_scene.md); 34,560 points; 10-22 s.
  const auto dir = temp_dir("demo-room");
  const RunResult r =
      run_omma("demo --rig gigaeye-44 --scene room --size 1800x480 --giga-mode skip5 --json --out " +
               (dir / "d").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = r.json();
  const auto& rows = j["near"]["rows"];
  ASSERT_EQ(rows.size(), 6u);
  double best_sphere = 0;
  for (size_t i = 1; i + 2 < rows.size(); ++i)
    best_sphere = std::max(best_sphere, rows[i]["psnr_db"].get<double>());
  const double inf = rows[0]["psnr_db"], estimate = rows[4]["psnr_db"], truth = rows[5]["psnr_db"];
  EXPECT_EQ(rows[4]["surface"], "estimated depth");
  EXPECT_GT(best_sphere, inf);
  EXPECT_GT(estimate, best_sphere + 2);
  EXPECT_GT(truth, best_sphere + 0.4);
  EXPECT_GE(j["near"]["closes"].get<double>(), 0.7);
  EXPECT_EQ(j["near"]["cloud_points"], 360 * 96);  // every preview pixel has a finite depth (a room)
  EXPECT_TRUE(std::filesystem::exists(dir / "d" / "near_3d" / "index.html"));
  EXPECT_TRUE(std::filesystem::exists(dir / "d" / "near_refocus_stack.jpg"));
  // Behind the grid, averaging the cameras beats the nearest camera alone.
  const auto& grid = j["refocus"]["grid"];
  ASSERT_EQ(grid.size(), 3u);
  EXPECT_GT(grid[1]["psnr_db"].get<double>(), grid[0]["psnr_db"].get<double>());
  std::filesystem::remove_all(dir);
}

TEST(DemoCli, BadSceneFailsCleanly) {
  const auto dir = temp_dir("demobad");
  const RunResult r = run_omma("demo --scene nowhere --out " + (dir / "d").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("error"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir / "d" / "report.html"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace omma::test
