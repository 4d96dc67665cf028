// Coverage analysis (§2.4.2, §3.4): closed form vs the plain reference, statistics, count maps.
#include "omma/design/coverage.h"

#include <random>

#include <gtest/gtest.h>

#include "omma/design/dome.h"
#include "omma/design/prototype.h"

namespace omma::design {
namespace {

TEST(Coverage, ReachAngleAndDistanceAreInverse) {
  // eq. 3.1-3.2 at the thesis's numbers: AOV 64 deg, R_phy 5 mm.
  const double aov = deg2rad(64);
  EXPECT_NEAR(rad2deg(reach_angle(aov, 5, 15)), 21.83, 0.01);
  EXPECT_NEAR(rad2deg(reach_angle(aov, 5, 18)), 23.54, 0.01);
  for (double r : {6.0, 9.0, 18.0, 50.0})
    EXPECT_NEAR(distance_for_reach(aov, 5, reach_angle(aov, 5, r)), r, 1e-9);
  EXPECT_TRUE(std::isinf(distance_for_reach(aov, 5, deg2rad(32))));
}

TEST(Coverage, ClosedFormMatchesThePointTest) {
  // For radial cameras covered_from(w) is where the point test switches from unseen to seen.
  const Rig rig = thesis_prototype_rig();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < 300; ++i) {
    const Vec3 w = direction_from_spherical(std::acos(u(rng)), 2 * kPi * u(rng));
    const double r = covered_from(rig, w);
    ASSERT_TRUE(std::isfinite(r));
    EXPECT_GE(cameras_seeing(rig, w, r * (1 + 1e-6) + 1e-9), 1);
    EXPECT_GE(cameras_seeing(rig, w, r * 3), 1);
    if (r > 5.01) {
      EXPECT_EQ(cameras_seeing(rig, w, r * (1 - 1e-6)), 0) << r;
    }
  }
}

TEST(Coverage, VirtualRadiusAgreesWithBisectionReference) {
  const Rig rig = thesis_prototype_rig();
  const double step = deg2rad(2.0);
  EXPECT_NEAR(virtual_radius(rig, step), virtual_radius_bisection(rig, step, 1e-4, 100), 2e-4);
}

TEST(Coverage, NonRadialCamerasAgreeWithBisectionReference) {
  // Tilted cameras whose pinholes are off their axes (a calibrated rig): general intervals.
  Rig rig = thesis_prototype_rig();
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0, 1);
  for (RigCamera& c : rig.cameras) {
    const Vec3 axis = Vec3(n(rng), n(rng), n(rng)).normalized();
    const Mat3 rot = Eigen::AngleAxisd(deg2rad(3), axis).toRotationMatrix();
    c.frame.t = rot * c.frame.t;
    c.frame.u = rot * c.frame.u;
    c.frame.v = rot * c.frame.v;
    c.position_mm += 0.3 * Vec3(n(rng), n(rng), n(rng));
  }
  const double step = deg2rad(2.0);
  const double fast = virtual_radius(rig, step);
  EXPECT_TRUE(std::isfinite(fast));
  EXPECT_NEAR(fast, virtual_radius_bisection(rig, step, 1e-4, 100), 2e-3);
}

TEST(Coverage, StatisticsOfThePrototype) {
  const Rig rig = thesis_prototype_rig();
  const double step = deg2rad(0.5);
  const CoverageSummary at_rvir = analyze_coverage(rig, virtual_radius(rig, step), step);
  EXPECT_DOUBLE_EQ(at_rvir.covered_fraction, 1.0);
  EXPECT_GE(at_rvir.min_cameras, 1);
  EXPECT_NEAR(at_rvir.r_virtual_mm, 14.0, 0.1);
  const CoverageSummary near = analyze_coverage(rig, 8.0, step);
  EXPECT_LT(near.covered_fraction, 0.9);
  EXPECT_GT(near.covered_fraction, 0.5);
  EXPECT_EQ(near.min_cameras, 0);
  // Far away every camera sees a cap of radius ~32 deg: the mean count is at most 24 such caps
  // over the hemisphere's area (less, as the lowest layer's caps reach below the rim).
  const CoverageSummary far = analyze_coverage(rig, 1e5, step);
  EXPECT_DOUBLE_EQ(far.covered_fraction, 1.0);
  const double all_caps = 24 * (1 - std::cos(deg2rad(32)));
  EXPECT_LT(far.mean_cameras, all_caps);
  EXPECT_GT(far.mean_cameras, 0.8 * all_caps);
  EXPECT_GT(far.mean_cameras, at_rvir.mean_cameras);
}

TEST(Coverage, CountMapMatchesThePointTest) {
  const Rig rig = thesis_prototype_rig();
  for (Projection proj : {Projection::kEquirect, Projection::kVr180}) {
    PanoGrid grid{proj, 72, proj == Projection::kEquirect ? 18 : 72};
    const cv::Mat counts = coverage_count_map(rig, grid, 12.0);
    ASSERT_EQ(counts.type(), CV_32SC1);
    ASSERT_EQ(counts.rows, grid.height);
    ASSERT_EQ(counts.cols, grid.width);
    for (int r = 0; r < grid.height; ++r)
      for (int c = 0; c < grid.width; ++c)
        EXPECT_EQ(counts.at<int>(r, c), cameras_seeing(rig, grid.pixel_direction(c, r), 12.0));
  }
}

TEST(Coverage, RenderedMapHasLegendAndColours) {
  cv::Mat counts(40, 160, CV_32SC1, cv::Scalar(0));
  counts(cv::Rect(40, 0, 40, 40)).setTo(1);
  counts(cv::Rect(80, 0, 80, 40)).setTo(3);
  const cv::Mat img = render_coverage_map(counts, "test");
  ASSERT_EQ(img.type(), CV_8UC3);
  EXPECT_GT(img.rows, counts.rows);                          // legend strip below
  EXPECT_EQ(img.at<cv::Vec3b>(10, 10), cv::Vec3b(0, 0, 0));  // a gap is black
  EXPECT_EQ(img.at<cv::Vec3b>(10, 50), coverage_color(1, 3));
  EXPECT_EQ(img.at<cv::Vec3b>(10, 100), coverage_color(3, 3));
  EXPECT_NE(coverage_color(1, 3), coverage_color(3, 3));
  EXPECT_THROW(render_coverage_map(cv::Mat(), "x"), std::invalid_argument);
}

TEST(Coverage, CapModelHelpers) {
  const Sampling s = make_sampling(deg2rad(1.0), false);
  EXPECT_EQ(s.rows, 91);
  EXPECT_EQ(s.cols, 360);
  double total = 0;
  for (int j = 0; j < s.rows; ++j) total += s.weight(j) * s.cols;
  EXPECT_NEAR(total, 2 * kPi, 1e-9);
  // One camera at the pole: covering radius = 90 deg (the rim), uncovered from just beyond reach.
  const std::vector<Vec3> pole = {Vec3::UnitZ()};
  EXPECT_NEAR(rad2deg(covering_radius(pole, s)), 90, 1e-9);
  EXPECT_NEAR(rad2deg(first_uncovered_theta(pole, s, deg2rad(30.5))), 31, 1e-9);
  EXPECT_TRUE(covers(pole, s, deg2rad(90)));
  EXPECT_FALSE(covers(pole, s, deg2rad(89)));
  EXPECT_THROW(make_sampling(0, false), std::invalid_argument);
}

}  // namespace
}  // namespace omma::design
