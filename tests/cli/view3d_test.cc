// 3D from the overlaps, end to end: `omma stitch --depth estimate --ply --depth-pano` on a small simulated
// colon writes a point cloud and a depth panorama that agree with the depth data; `omma view3d` makes a
// page that headless Chromium (playwright-core, tests/cli/view3d_viewer.cjs) opens from file:// with no
// network, reports the PLY's vertex count, draws the cloud (not a blank canvas) and turns with a drag.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {
namespace fs = std::filesystem;

// The vertex count in a PLY's header ("element vertex N"), -1 if none.
long ply_vertices(const fs::path& p) {
  const std::string s = slurp(p);
  const size_t at = s.find("element vertex ");
  return at == std::string::npos ? -1 : std::atol(s.c_str() + at + 15);
}

// A small colon (thesis-24, 128x128 vr180 truth) stitched with the estimated depth, exported: the PLY
// has one point per kept pixel with finite depth (the estimate is finite everywhere), the JSON says so,
// the depth range is the TIFF's, the 16-bit PNG is the TIFF in whole mm and the colour JPEG carries it.
TEST(View3dCli, StitchExportsPointCloudAndDepthPanorama) {
  const fs::path d = temp_dir("view3d-export");
  const RunResult sim = run_omma(
      "simulate --scene colon --truth-size 128x128 --supersample 1 --no-truth --out " + (d / "sim").string());
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const std::string stitch = "stitch --rig " + (d / "sim/rig.json").string() + " --frames " +
                             (d / "sim").string() + " --size 128x128 --depth estimate --out " +
                             (d / "p.jpg").string();
  const RunResult r = run_omma(stitch + " --ply " + (d / "c.ply").string() + " --ply-step 2 --depth-pano " +
                               (d / "depth.png").string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = r.json();
  const cv::Mat tiff = cv::imread((d / "depth.tiff").string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(tiff.type(), CV_32FC1);
  ASSERT_EQ(tiff.size(), cv::Size(128, 128));
  long finite = 0;
  for (int y = 0; y < 128; y += 2)
    for (int x = 0; x < 128; x += 2) finite += std::isfinite(tiff.at<float>(y, x)) ? 1 : 0;
  EXPECT_EQ(finite, 64 * 64);
  EXPECT_EQ(ply_vertices(d / "c.ply"), finite);
  EXPECT_EQ(j.at("ply").at("points").get<long>(), finite);
  double lo = 0, hi = 0;
  cv::minMaxLoc(tiff, &lo, &hi);
  EXPECT_EQ(j.at("depth_range").at("near_mm").get<double>(), lo);
  EXPECT_EQ(j.at("depth_range").at("far_mm").get<double>(), hi);
  EXPECT_TRUE(j.at("depth_pano").at("gdepth_in_panorama").get<bool>());
  // The PNG: whole millimetres of the same depth.
  const cv::Mat png = cv::imread((d / "depth.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(png.type(), CV_16UC1);
  cv::Mat png_mm;
  png.convertTo(png_mm, CV_32F);
  EXPECT_LE(cv::norm(png_mm, tiff, cv::NORM_INF), 0.5);
  // A confidence threshold keeps fewer points; refusals before any work.
  const RunResult conf =
      run_omma(stitch + " --ply " + (d / "c2.ply").string() + " --ply-min-confidence 0.5 --json");
  ASSERT_EQ(conf.exit_code, 0) << conf.err;
  const long kept = conf.json().at("ply").at("points").get<long>();
  EXPECT_EQ(ply_vertices(d / "c2.ply"), kept);
  EXPECT_GT(kept, 0);
  EXPECT_LT(kept, 128 * 128);
  const std::string base = "stitch --rig " + (d / "sim/rig.json").string() + " --frames " +
                           (d / "sim").string() + " --size 64x64 --out " + (d / "x.png").string();
  expect_error(run_omma(base + " --ply " + (d / "x.ply").string()), "finite depth", "--ply with --depth inf");
  expect_error(
      run_omma(base + " --depth sphere:50 --ply " + (d / "x.ply").string() + " --ply-min-confidence 0.5"),
      "estimate only", "--ply-min-confidence with sphere");
  expect_error(run_omma(base + " --depth sphere:50 --ply " + (d / "x.ply").string() + " --ply-step 0"),
               "--ply-step", "--ply-step 0");
  expect_error(run_omma(base + " --depth sphere:50 --ply " + (d / "x.txt").string()), ".ply", "--ply x.txt");
  expect_error(run_omma(base + " --depth sphere:50 --depth-pano " + (d / "x.jpg").string()), ".png",
               "--depth-pano x.jpg");
  expect_error(run_omma(base + " --depth sphere:50 --depth-pano " + (d / "x.png").string()), "must not be",
               "--depth-pano = --out");
  EXPECT_FALSE(fs::exists(d / "x.png"));
  fs::remove_all(d);
}

TEST(View3dCli, PageShowsTheCloudAndTurnsInHeadlessChromium) {
  const std::string web = std::string(OMMA_SOURCE_DIR) + "/web";
  const fs::path d = temp_dir("view3d-page");
  const RunResult sim = run_omma(
      "simulate --scene colon --truth-size 96x96 --supersample 1 --no-truth --out " + (d / "sim").string());
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const RunResult st = run_omma("stitch --rig " + (d / "sim/rig.json").string() + " --frames " +
                                (d / "sim").string() + " --size 96x96 --depth estimate --out " +
                                (d / "p.png").string() + " --ply " + (d / "cloud.ply").string() + " --json");
  ASSERT_EQ(st.exit_code, 0) << st.err;
  const long vertices = ply_vertices(d / "cloud.ply");
  ASSERT_EQ(vertices, 96 * 96);
  const RunResult v =
      run_omma("view3d " + (d / "cloud.ply").string() + " --out " + (d / "view").string() + " --json");
  if (v.exit_code != 0 && has(v.err, "built without the 3D viewer"))
    GTEST_SKIP() << "omma was built without three.js (web/node_modules missing): " << v.err;
  ASSERT_EQ(v.exit_code, 0) << v.err;
  EXPECT_EQ(v.json().at("points").get<long>(), vertices);
  EXPECT_EQ(slurp(d / "view/cloud.ply"), slurp(d / "cloud.ply"));
  // --max-points: every k-th point.
  const RunResult few = run_omma("view3d " + (d / "cloud.ply").string() + " --out " + (d / "few").string() +
                                 " --max-points 1000 --json");
  ASSERT_EQ(few.exit_code, 0) << few.err;
  EXPECT_EQ(few.json().at("stride").get<long>(), 10);   // ceil(9216 / 1000)
  EXPECT_EQ(few.json().at("points").get<long>(), 922);  // ceil(9216 / 10)
  expect_error(run_omma("view3d " + (d / "p.png").string() + " --out " + (d / "bad").string()), "PLY",
               "view3d of a PNG");

  if (std::system("command -v chromium >/dev/null 2>&1 && command -v node >/dev/null 2>&1") != 0 ||
      !fs::exists(web + "/node_modules/playwright-core"))
    GTEST_SKIP() << "chromium, node or web/node_modules (playwright-core) missing";
  const std::string cmd = "timeout 80 node " + std::string(OMMA_SOURCE_DIR) +
                          "/tests/cli/view3d_viewer.cjs " + (d / "view/index.html").string() + " " +
                          d.string() + " " + web + " >" + (d / "viewer.json").string() + " 2>" +
                          (d / "viewer.err").string();
  ASSERT_EQ(std::system(cmd.c_str()), 0) << slurp(d / "viewer.err");
  nlohmann::json j;
  ASSERT_NO_THROW(j = nlohmann::json::parse(slurp(d / "viewer.json"))) << slurp(d / "viewer.err");
  ASSERT_FALSE(j.contains("failure")) << j.dump(1);
  EXPECT_FALSE(j.contains("console")) << j.dump(1);
  EXPECT_TRUE(j.at("requests").empty()) << j.dump(1);  // nothing from the network
  const auto& loaded = j.at("loaded");
  ASSERT_TRUE(loaded.at("ready").get<bool>()) << j.dump(1);
  EXPECT_EQ(loaded.at("points").get<long>(), vertices);
  // The bounds the page reports hold the colon: the tube around the dome axis (the colon's radius
  // about 20 mm, its wall starting at the dome), as the PLY's points do.
  const auto b = loaded.at("bounds");
  ASSERT_EQ(b.size(), 6u);
  EXPECT_LT(b[0].get<double>(), -10);
  EXPECT_GT(b[3].get<double>(), 10);
  EXPECT_GT(b[5].get<double>(), b[2].get<double>() + 20);

  auto shot = [&](const char* name) { return cv::imread((d / (std::string(name) + ".png")).string()); };
  const cv::Mat a = shot("loaded"), again = shot("again"), dragged = shot("dragged"), zoomed = shot("zoomed");
  ASSERT_FALSE(a.empty() || again.empty() || dragged.empty() || zoomed.empty());
  // Pixels that are not the background (#111111) by more than 24 levels in some channel.
  auto drawn = [](const cv::Mat& m) {
    cv::Mat diff;
    cv::absdiff(m, cv::Scalar(17, 17, 17), diff);
    long n = 0;
    for (int y = 0; y < diff.rows; ++y)
      for (int x = 0; x < diff.cols; ++x) {
        const cv::Vec3b p = diff.at<cv::Vec3b>(y, x);
        n += std::max({p[0], p[1], p[2]}) > 24 ? 1 : 0;
      }
    return double(n) / double(m.total());
  };
  auto differ = [](const cv::Mat& x, const cv::Mat& y) {
    return cv::norm(x, y, cv::NORM_L1) / double(x.total());
  };
  std::printf(
      "  view3d: drawn %.3f of the canvas; unchanged %.2f; the drag changes %.1f per pixel, the wheel %.1f\n",
      drawn(a), differ(a, again), differ(a, dragged), differ(dragged, zoomed));
  // Measured (SwiftShader, 4 runs, identical): drawn 0.104, unchanged 0.00, drag 20.7, wheel 15.4 per
  // pixel. A blank canvas draws 0; a view that does not turn changes 0.
  EXPECT_GT(drawn(a), 0.05);
  EXPECT_LT(differ(a, again), 0.5);
  EXPECT_GT(differ(a, dragged), 5.0);
  EXPECT_GT(differ(dragged, zoomed), 5.0);
  EXPECT_GT(j.at("dragged").at("renders").get<int>(), loaded.at("renders").get<int>());
  fs::remove_all(d);
}

}  // namespace
}  // namespace omma::test
