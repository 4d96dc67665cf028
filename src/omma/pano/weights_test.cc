// Blending weights (thesis eq. 2.6-2.9, 4.8-4.11, 4.17-4.18).
#include "omma/pano/weights.h"

#include <cmath>

#include <gtest/gtest.h>

#include "omma/testing/test_scenes.h"

namespace omma::pano {
namespace {

TEST(PanoWeights, StaticWeightsSumToOneAndReduceToSingleCamera) {
  const Rig rig = testing::small_rig(32);
  for (Projection proj : {Projection::kEquirect, Projection::kVr180}) {
    const PanoGrid grid{proj, 72, proj == Projection::kEquirect ? 18 : 36};
    int single = 0, multi = 0;
    for (Method m : all_methods()) {
      for (int row = 0; row < grid.height; ++row)
        for (int col = 0; col < grid.width; ++col) {
          const auto cs = find_contributors(rig, grid.pixel_direction(col, row));
          const auto taps = static_taps(rig, grid, col, row, m);
          ASSERT_FALSE(cs.empty()) << "the test rig covers the hemisphere";
          double sum = 0;
          for (const auto& t : taps) {
            EXPECT_GT(t.weight, 0);
            sum += t.weight;
          }
          EXPECT_NEAR(sum, 1.0, 1e-12) << to_string(m) << " " << col << "," << row;
          if (cs.size() == 1) {
            ++single;
            ASSERT_EQ(taps.size(), 1u);
            EXPECT_EQ(taps[0].camera, cs[0].camera);
            EXPECT_DOUBLE_EQ(taps[0].weight, 1.0);
          } else {
            ++multi;
          }
          if (m == Method::kNearest) {
            EXPECT_EQ(taps.size(), 1u);  // eq. 2.6: one camera
          }
        }
    }
    EXPECT_GT(single, 0);
    EXPECT_GT(multi, 0);
  }
}

// The mrf posterior of eq. 4.8 on a hand-made neighbourhood.
TEST(PanoWeights, MrfMatchesHandComputation) {
  Rig rig = testing::small_rig(32);
  auto c = [](int cam, double r) { return Contributor{cam, Vec2(16, 16), r}; };
  const std::vector<Contributor> centre = {c(0, 1.0), c(1, 2.0)};
  const std::vector<Contributor> left = {c(0, 1.0), c(1, 1.0)};
  const std::vector<Contributor> right = {c(0, 2.0), c(1, 1.0)};
  const std::vector<Contributor> up = {c(0, 0.5), c(1, 4.0)};
  const std::array<const std::vector<Contributor>*, 4> nb{&left, &right, &up, nullptr};
  // p_0 = 1/1 * 1/1 * 1/2 * 1/0.5 = 1, p_1 = 1/2 * 1/1 * 1/1 * 1/4 = 0.125 -> 1/1.125, 0.125/1.125
  const auto w = method_weights(rig, Method::kMrf, centre, nb);
  ASSERT_EQ(w.size(), 2u);
  EXPECT_NEAR(w[0], 1 / 1.125, 1e-12);
  EXPECT_NEAR(w[1], 0.125 / 1.125, 1e-12);
  // Linear (eq. 2.8) on the same centre: 1 : 1/2.
  const auto lin = method_weights(rig, Method::kLinear, centre, nb);
  EXPECT_NEAR(lin[0], 2.0 / 3, 1e-12);
  // mrf-spherical (eq. 4.10): a = r_max (pi/2 - acos(r / r_max)) replaces r in every node.
  auto a = [](double r, double rmax) { return rmax * (kPi / 2 - std::acos(r / rmax)); };
  const double p0 = 1 / a(1, 2) * (1 / a(1, 1)) * (1 / a(2, 2)) * (1 / a(0.5, 4));
  const double p1 = 1 / a(2, 2) * (1 / a(1, 1)) * (1 / a(1, 2)) * (1 / a(4, 4));
  const auto ws = method_weights(rig, Method::kMrfSpherical, centre, nb);
  EXPECT_NEAR(ws[0], p0 / (p0 + p1), 1e-12);
  EXPECT_NEAR(ws[0], 0.926111, 1e-5);  // 1 / (1 + 0.50131/6.28319)
  // A camera that does not see a neighbour gets probability 0 there (eq. 4.8).
  const std::vector<Contributor> only0 = {c(0, 3.0)};
  const std::array<const std::vector<Contributor>*, 4> nb2{&left, &only0, nullptr, nullptr};
  const auto w2 = method_weights(rig, Method::kMrf, centre, nb2);
  EXPECT_DOUBLE_EQ(w2[0], 1.0);
  EXPECT_DOUBLE_EQ(w2[1], 0.0);
}

TEST(PanoWeights, GaussianFavoursTheCameraCentre) {
  Rig rig = testing::small_rig(32);
  // Same |r|, camera 0 samples its centre, camera 1 its cone edge (d = f tan(aov/2) = 16 px):
  // eq. 2.9 with sigma = 0.5 * 16 px gives exp(-2) relative weight.
  const std::vector<Contributor> cs = {{0, Vec2(16, 16), 1.0}, {1, Vec2(32, 16), 1.0}};
  const auto w = method_weights(rig, Method::kGaussian, cs, {nullptr, nullptr, nullptr, nullptr});
  EXPECT_NEAR(w[1] / w[0], std::exp(-2.0), 1e-9);
}

TEST(PanoWeights, SadEvidenceMatchesHandComputation) {
  // eq. 4.17: SAD = {0.4, 0.4, 0.8}; eq. 4.18 with eps = 0: {0.5/0.4, 0.3/0.4, 0.2/0.8} normalised.
  const std::vector<Tap> taps = {{0, Vec2::Zero(), 0.5}, {1, Vec2::Zero(), 0.3}, {2, Vec2::Zero(), 0.2}};
  const auto w = sad_weights(taps, {0.5, 0.5, 0.9}, 0.0);
  EXPECT_NEAR(w[0], 1.25 / 2.25, 1e-12);
  EXPECT_NEAR(w[1], 0.75 / 2.25, 1e-12);
  EXPECT_NEAR(w[2], 0.25 / 2.25, 1e-12);
  // Two cameras: equal SADs, the prior is unchanged (thesis §4.3.2).
  const auto w2 = sad_weights({{0, Vec2::Zero(), 0.7}, {1, Vec2::Zero(), 0.3}}, {0.1, 0.8});
  EXPECT_NEAR(w2[0], 0.7, 1e-12);
  EXPECT_DOUBLE_EQ(sad_weights({{3, Vec2::Zero(), 1.0}}, {0.4})[0], 1.0);
}

TEST(PanoWeights, NeighboursWrapOnEquirectOnly) {
  const PanoGrid eq{Projection::kEquirect, 10, 5};
  auto n = grid_neighbours(eq, 0, 0);
  EXPECT_EQ(n[0][0], 9);   // left wraps
  EXPECT_EQ(n[2][0], -1);  // nothing above the top row
  const PanoGrid vr{Projection::kVr180, 10, 10};
  n = grid_neighbours(vr, 0, 5);
  EXPECT_EQ(n[0][0], -1);
  EXPECT_EQ(n[1][0], 1);
}

}  // namespace
}  // namespace omma::pano
