// The projection surface and depth from the overlaps (surface.h, plane_sweep.h): D = infinity reproduces the
// thesis's stitcher exactly; on the simulated colon the true depth removes most of the parallax
// error and the estimated depth closes most of the gap to it.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "omma/design/prototype.h"
#include "omma/pano/depth_eval.h"
#include "omma/pano/maps.h"
#include "omma/pano/plane_sweep.h"
#include "omma/pano/quality.h"
#include "omma/pano/stitch.h"
#include "omma/pano/surface.h"
#include "omma/sim/simulate.h"
#include "omma/testing/test_scenes.h"

namespace omma::pano {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(PanoSurface, InfinityIsTheThesisModelExactly) {
  const Rig rig = testing::small_rig(64);
  const PanoGrid grid{Projection::kVr180, 96, 96};
  const auto frames =
      testing::render_frames(rig, testing::smooth_texture(),
                             testing::NearSphere{15.0 * direction_from_spherical(deg2rad(45), deg2rad(30)),
                                                 3.0, cv::Vec3f(1, 1, 1)});
  const cv::Mat inf_depth(grid.height, grid.width, CV_32FC1, cv::Scalar(kInf));
  for (Method m : all_methods()) {
    StitchOptions a;
    a.method = m;
    a.grid = grid;
    a.progress = false;
    StitchOptions b = a;
    b.depth = inf_depth;
    const cv::Mat pa = stitch(rig, frames, a), pb = stitch(rig, frames, b);
    EXPECT_EQ(cv::norm(pa, pb, cv::NORM_INF), 0.0) << to_string(m);
  }
  EXPECT_EQ(
      cv::norm(boundary_map(rig, frames, grid), boundary_map(rig, frames, grid, {}, inf_depth), cv::NORM_INF),
      0.0);
  EXPECT_EQ(inter_camera_psnr(rig, frames, grid), inter_camera_psnr(rig, frames, grid, {}, inf_depth));
  // A very distant sphere is infinity to within float rounding of the rays.
  StitchOptions far;
  far.grid = grid;
  far.progress = false;
  StitchOptions ref = far;
  far.depth = sphere_depth(rig, grid, 1e7);
  EXPECT_GT(psnr_db(stitch(rig, frames, far), stitch(rig, frames, ref)), 80.0);
}

TEST(PanoSurface, SphereGeometry) {
  const Rig rig = testing::small_rig(64);
  const PanoGrid grid{Projection::kVr180, 32, 32};
  // From the centre every direction meets the sphere at R; from an offset q, |q + D w| = R.
  const cv::Mat d0 = sphere_depth(rig, grid, 20);
  EXPECT_NEAR(cv::mean(d0)[0], 20.0, 1e-4);
  const Vec3 q(1, 2, 0.5);
  const cv::Mat dq = sphere_depth(rig, grid, 20, q);
  for (int r = 0; r < grid.height; r += 7)
    for (int c = 0; c < grid.width; c += 5)
      EXPECT_NEAR((q + dq.at<float>(r, c) * grid.pixel_direction(c, r)).norm(), 20.0, 1e-4);
  // Bad input: a sphere inside the dome, non-positive depths, a depth map of the wrong size.
  EXPECT_THROW(sphere_depth(rig, grid, 4.0), std::invalid_argument);
  EXPECT_THROW(sphere_depth(rig, grid, -1), std::invalid_argument);
  cv::Mat bad = d0.clone();
  bad.at<float>(3, 4) = 0;
  EXPECT_THROW(check_depth(bad, grid), std::invalid_argument);
  bad.at<float>(3, 4) = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(check_depth(bad, grid), std::invalid_argument);
  EXPECT_THROW(check_depth(cv::Mat(10, 10, CV_32FC1, cv::Scalar(5)), grid), std::invalid_argument);
  PlaneSweepOptions so;
  so.near_mm = 4;  // inside the dome
  EXPECT_THROW(DepthSweep(rig, grid, so), std::invalid_argument);
  so.near_mm = 50;
  so.far_mm = 20;
  EXPECT_THROW(DepthSweep(rig, grid, so), std::invalid_argument);
}

// ---------------------------------------------------------------------------------- colon
struct Colon {
  Rig rig;
  PanoGrid grid;
  std::vector<cv::Mat> frames;
  cv::Mat truth, depth;
};

Colon simulate_colon(const PanoGrid& grid, uint64_t seed) {
  Colon s;
  s.rig = design::thesis_prototype_rig();
  s.grid = grid;
  const sim::ColonCase cc = sim::colon_case(seed);
  sim::SimulateOptions so = cc.options;
  so.effects.supersample = 1;
  so.truth_grid = grid;
  so.truth_supersample = 1;
  so.progress = false;
  const auto r = sim::simulate(s.rig, *sim::make_colon_scene(cc.scene), so);
  for (const auto& f : r.frames) s.frames.push_back(f.image);
  s.truth = r.truth;
  s.depth = r.truth_depth;
  return s;
}

struct ColonFigures {
  EvalSummary inf, sphere, truth, estimate;
  DepthError depth;
  BoundaryScore thesis, with_depth, from_depth;
  DepthEstimate est;
};

// mrf on the colon of `seed` (sim::colon_case), the fixed sphere at 22 mm (the best of 15, 18, 22,
// 27 and 35 mm on every case of docs/results/depth_table.sh), the true and the estimated depth.
ColonFigures colon_figures(const PanoGrid& grid, uint64_t seed) {
  const Colon c = simulate_colon(grid, seed);
  const cv::Mat seam = seam_mask(coverage_map(c.rig, c.grid), false);
  ColonFigures f;
  StitchOptions opt;
  opt.method = Method::kMrf;
  opt.grid = c.grid;
  opt.progress = false;
  f.inf = evaluate(stitch(c.rig, c.frames, opt), c.truth, seam);
  opt.depth = sphere_depth(c.rig, c.grid, 22);
  f.sphere = evaluate(stitch(c.rig, c.frames, opt), c.truth, seam);
  opt.depth = clamp_depth(c.depth, 300);
  f.truth = evaluate(stitch(c.rig, c.frames, opt), c.truth, seam);
  f.est = estimate_depth(c.rig, c.frames, c.grid);
  opt.depth = f.est.depth;
  f.estimate = evaluate(stitch(c.rig, c.frames, opt), c.truth, seam);
  f.depth = depth_error(f.est.depth, c.depth, 300);
  // Boundary maps (eq. 4.12-4.16, each at its best threshold th_ob) against the true occlusion boundaries.
  const cv::Mat occl = depth_discontinuities(c.depth);
  const int tol = std::max(1, grid.width / 270);
  f.thesis = best_boundary_score(boundary_map(c.rig, c.frames, c.grid), occl, tol);
  f.with_depth = best_boundary_score(boundary_map(c.rig, c.frames, c.grid, {}, f.est.depth), occl, tol);
  f.from_depth = best_boundary_score(depth_jump_map(f.est.depth), occl, tol);
  if (std::getenv("DUMP")) {
    cv::imwrite(fmt::format("/tmp/d_est{}.png", seed), depth_colormap(f.est.depth, 10, 60));
    cv::imwrite(fmt::format("/tmp/d_true{}.png", seed), depth_colormap(c.depth, 10, 60));
    cv::imwrite(fmt::format("/tmp/d_occl{}.png", seed), occl);
    cv::Mat b8;
    boundary_map(c.rig, c.frames, c.grid, {}, f.est.depth).convertTo(b8, CV_8U, 255 * 4);
    cv::imwrite(fmt::format("/tmp/d_lob{}.png", seed), b8);
    std::printf("boundary pixels: truth %ld, thesis %ld, with depth %ld, from depth %ld\n", f.thesis.truth,
                f.thesis.predicted, f.with_depth.predicted, f.from_depth.predicted);
  }
  std::printf(
      "colon seed %d %s %dx%d, mrf PSNR (seam): inf %.2f (%.2f), sphere:22 %.2f (%.2f), truth %.2f (%.2f), "
      "estimate %.2f (%.2f); gap closed %.0f %% (seam %.0f %%); depth median rel %.3f, within 10 %% %.2f; "
      "boundary P/R/F1 thesis %.2f/%.2f/%.2f, L_ob with depth %.2f/%.2f/%.2f, from depth %.2f/%.2f/%.2f\n",
      int(seed), to_string(grid.projection).c_str(), grid.width, grid.height, f.inf.psnr_db,
      f.inf.seam_psnr_db, f.sphere.psnr_db, f.sphere.seam_psnr_db, f.truth.psnr_db, f.truth.seam_psnr_db,
      f.estimate.psnr_db, f.estimate.seam_psnr_db,
      100 * (f.estimate.psnr_db - f.sphere.psnr_db) / (f.truth.psnr_db - f.sphere.psnr_db),
      100 * (f.estimate.seam_psnr_db - f.sphere.seam_psnr_db) /
          (f.truth.seam_psnr_db - f.sphere.seam_psnr_db),
      f.depth.median_rel, f.depth.within_10, f.thesis.precision, f.thesis.recall, f.thesis.f1,
      f.with_depth.precision, f.with_depth.recall, f.with_depth.f1, f.from_depth.precision,
      f.from_depth.recall, f.from_depth.f1);
  return f;
}

// One seed and projection in CI (OMMA_DEPTH_SEEDS=1,2,3 runs more; docs/results/depth_table.sh has the
// full-size table). Thresholds: see the measured values in the comments.
TEST(PanoDepth, ColonTruthAndEstimate) {
  std::vector<int> seeds{1};
  if (const char* e = std::getenv("OMMA_DEPTH_SEEDS")) {
    seeds.clear();
    for (const char* p = e; *p; ++p)
      if (*p >= '0' && *p <= '9') seeds.push_back(*p - '0');
  }
  std::vector<Projection> projections{Projection::kVr180};
  if (std::getenv("OMMA_DEPTH_EQUIRECT")) projections.push_back(Projection::kEquirect);
  for (Projection p : projections)
    for (int seed : seeds) {
      const PanoGrid grid = p == Projection::kVr180 ? PanoGrid{p, 270, 270} : PanoGrid{p, 480, 128};
      const ColonFigures f = colon_figures(grid, seed);
      // Measured on seeds 1, 2, 3 (vr180 270x270): truth - inf = 6.3 / 6.7 / 5.8 dB, truth - sphere:22 =
      // 2.0 / 2.5 / 1.7 dB; the estimate closes 88 / 77 / 82 % of the gap between the best sphere and the
      // truth (seam band the same; equirect 480x128: 93 / 83 / 88 %). Before the band-pass of the matched
      // gray levels (plane_sweep.h "Cost") seed 2 closed 28 %: the vignetting ramp at the image edges
      // matched. Median relative depth error 2.1 / 1.8 / 1.7 %. Boundaries (best F1 over th_ob): the depth's
      // own jumps F1 0.16 / 0.29 / 0.25 against 0.13 / 0.21 / 0.11 for the thesis's L_ob at infinity
      // (equirect 0.30 / 0.44 / 0.52 against 0.21 / 0.22 / 0.23, where L_ob is best marking everything:
      // recall 1.0, so recall alone would not compare them).
      EXPECT_GT(f.truth.psnr_db, f.inf.psnr_db + 4.0);
      EXPECT_GT(f.truth.psnr_db, f.sphere.psnr_db + 1.0);
      const double closed = (f.estimate.psnr_db - f.sphere.psnr_db) / (f.truth.psnr_db - f.sphere.psnr_db);
      const double closed_seam =
          (f.estimate.seam_psnr_db - f.sphere.seam_psnr_db) / (f.truth.seam_psnr_db - f.sphere.seam_psnr_db);
      EXPECT_GT(f.estimate.psnr_db, f.sphere.psnr_db + 0.8);
      EXPECT_GT(closed, 0.7);  // target: the estimate closes 70 % of the gap to the true depth
      EXPECT_GT(closed_seam, 0.7);
      EXPECT_LT(f.depth.median_rel, 0.04);
      EXPECT_GT(f.from_depth.f1, f.thesis.f1);
    }
}

// Far field: the estimate must not cost anything where there is no parallax (within 0.2 dB of inf).
TEST(PanoDepth, FarFieldNotWorseThanInfinity) {
  const Rig rig = design::thesis_prototype_rig();
  const PanoGrid grid{Projection::kVr180, 270, 270};
  sim::SimulateOptions so;
  so.effects.supersample = 1;
  so.truth_grid = grid;
  so.truth_supersample = 1;
  so.progress = false;
  const auto r = sim::simulate(rig, *sim::make_photo_scene(std::string(OMMA_DATA_DIR) + "/louvre.jpg"), so);
  std::vector<cv::Mat> frames;
  for (const auto& f : r.frames) frames.push_back(f.image);
  StitchOptions opt;
  opt.method = Method::kMrf;
  opt.grid = grid;
  opt.progress = false;
  const double inf = psnr_db(stitch(rig, frames, opt), r.truth);
  const DepthEstimate est = estimate_depth(rig, frames, grid);
  opt.depth = est.depth;
  const double with = psnr_db(stitch(rig, frames, opt), r.truth);
  cv::Mat inv;
  cv::divide(1.0, est.depth, inv);
  std::printf("louvre vr180 270x270 mrf: inf %.2f dB, estimate %.2f dB (median depth %.0f mm)\n", inf, with,
              1 / cv::mean(inv)[0]);
  EXPECT_GT(with,
            inf - 0.2);  // measured 25.93 and 25.93 dB (540x540 louvre and lake: docs/results/depth_table.md)
}

// The aggregation alone (plane_sweep.h "Aggregation"), on hand-made cost volumes.
TEST(PanoDepthSgm, WithoutPenaltiesEveryPathIsTheCostItself) {
  const int W = 6, H = 4, K = 5;
  std::vector<float> C(size_t(W) * H * K);
  for (size_t t = 0; t < C.size(); ++t) C[t] = float((t * 7919) % 13) / 13;
  const cv::Mat guide(H, W, CV_32FC1, cv::Scalar(0.5));
  for (int paths : {4, 8}) {
    const std::vector<float> S = detail::aggregate_sgm(C, W, H, K, guide, 0, 0, 0.03, paths);
    ASSERT_EQ(S.size(), C.size());
    for (size_t t = 0; t < C.size(); ++t) ASSERT_NEAR(S[t], paths * C[t], 1e-5) << t;
  }
}

TEST(PanoDepthSgm, SmoothnessOverrulesAnIsolatedMinimum) {
  // Every pixel prefers candidate 1; the centre alone prefers 3 (cost 0 there, 0.5 at 1).
  const int W = 5, H = 5, K = 4;
  std::vector<float> C(size_t(W) * H * K, 1.f);
  for (int u = 0; u < W * H; ++u) C[size_t(u) * K + 1] = 0;
  const int centre = 2 * W + 2;
  C[size_t(centre) * K + 1] = 0.5f;
  C[size_t(centre) * K + 3] = 0;
  const cv::Mat guide(H, W, CV_32FC1, cv::Scalar(0.5));
  const std::vector<float> S = detail::aggregate_sgm(C, W, H, K, guide, 0.2, 2.0, 0.03, 8);
  const float* s = &S[size_t(centre) * K];
  EXPECT_EQ(std::min_element(s, s + K) - s, 1);
  // A corner pixel keeps its own minimum.
  const float* s0 = &S[0];
  EXPECT_EQ(std::min_element(s0, s0 + K) - s0, 1);
  // Sizes are checked.
  EXPECT_THROW(detail::aggregate_sgm(C, W, H + 1, K, guide, 0.2, 2.0, 0.03, 8), std::invalid_argument);
  EXPECT_THROW(detail::aggregate_sgm(C, W, H, K, guide, 0.2, 2.0, 0.03, 6), std::invalid_argument);
}

}  // namespace
}  // namespace omma::pano
