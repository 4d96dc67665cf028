// The bundle adjustment's problem builder (bundle_problem.h) on hand-made tracks.
#include <gtest/gtest.h>

#include "omma/calib/bundle_problem.h"
#include "omma/design/prototype.h"

namespace omma::calib::detail {
namespace {

// Tracks of two observations each on cameras 0 and 1, at the pixel the nominal camera sees the
// direction halfway between their axes.
std::vector<std::vector<TrackObservation>> pair_tracks(const Rig& rig, int count) {
  std::vector<std::vector<TrackObservation>> tracks;
  const Vec3 mid = (rig.cameras[0].frame.t + rig.cameras[1].frame.t).normalized();
  for (int t = 0; t < count; ++t) {
    std::vector<TrackObservation> track;
    for (int cam : {0, 1}) {
      TrackObservation o;
      o.cam = cam;
      o.px = *rig.cameras[cam].model().project(mid) + Vec2(0.5 * t, 0.25 * t);
      track.push_back(o);
    }
    tracks.push_back(track);
  }
  return tracks;
}

int observation_count(const std::vector<std::vector<TrackObservation>>& tracks) {
  int n = 0;
  for (const auto& t : tracks) n += static_cast<int>(t.size());
  return n;
}

TEST(BundleProblem, OneResidualBlockPerObservation) {
  const Rig rig = design::thesis_prototype_rig();
  const auto tracks = pair_tracks(rig, 5);
  CalibrationOptions opt;
  opt.prior_rotation_deg = 0;  // no prior blocks: only the observations
  opt.prior_mean_focal = 0;
  for (SceneModel scene : {SceneModel::kFar, SceneModel::kNear}) {
    BundleBlocks b = init_bundle_blocks(rig, rig, tracks, scene, opt, std::nullopt);
    ASSERT_EQ(b.points.size(), tracks.size());
    std::vector<std::vector<char>> keep(tracks.size(), std::vector<char>(2, 1));
    ceres::Problem::Options popt;
    popt.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(popt);
    BundleManifolds m(b);
    const int added = build_bundle_problem(problem, m, b, tracks, keep, rig, opt, /*intrinsics_free=*/true);
    EXPECT_EQ(added, observation_count(tracks));
    EXPECT_EQ(problem.NumResidualBlocks(), observation_count(tracks)) << to_string(scene);
    // 2 rotations, 2 x (fcc, k) and one point per track.
    EXPECT_EQ(problem.NumParameterBlocks(), 2 + 4 + static_cast<int>(tracks.size()));
  }
}

TEST(BundleProblem, TracksLeftWithOneObservationAndPriorsAreCounted) {
  const Rig rig = design::thesis_prototype_rig();
  const auto tracks = pair_tracks(rig, 4);
  CalibrationOptions opt;  // rotation prior on: one block per camera in the problem
  BundleBlocks b = init_bundle_blocks(rig, rig, tracks, SceneModel::kFar, opt, std::nullopt);
  std::vector<std::vector<char>> keep(tracks.size(), std::vector<char>(2, 1));
  keep[1][0] = 0;  // track 1 keeps one observation: it is left out
  ceres::Problem::Options popt;
  popt.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(popt);
  BundleManifolds m(b);
  const int added = build_bundle_problem(problem, m, b, tracks, keep, rig, opt, /*intrinsics_free=*/false);
  EXPECT_EQ(added, observation_count(tracks) - 2);
  EXPECT_EQ(problem.NumResidualBlocks(), added + 2);  // + the rotation priors of cameras 0 and 1
  // Pass 0 (intrinsics held): the intrinsics blocks are constant.
  EXPECT_TRUE(problem.IsParameterBlockConstant(b.fcc_block(0)));
  EXPECT_TRUE(problem.IsParameterBlockConstant(b.k_block(1)));
  EXPECT_FALSE(problem.IsParameterBlockConstant(b.delta[0].data()));
}

}  // namespace
}  // namespace omma::calib::detail
