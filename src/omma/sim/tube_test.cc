// The calibration tube and the flat-field target (scene.h), several shots of a static scene
// (simulate.h), and the simulator's true photometric model (render.h).
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "omma/core/frames.h"
#include "omma/core/io.h"
#include "omma/sim/render.h"
#include "omma/sim/scene.h"
#include "omma/sim/simulate.h"

namespace omma::sim {
namespace {

RigCamera side_camera(int id, const Vec3& t, int size = 128) {
  RigCamera c;
  c.id = id;
  c.frame = frame_looking_at(t.normalized(),
                             std::abs(t.normalized().z()) > 0.9 ? Vec3::UnitX() : Vec3(-Vec3::UnitZ()));
  c.position_mm = 5 * t.normalized();
  c.in.width = c.in.height = size;
  c.in.aov = deg2rad(64);
  c.in.fu = c.in.fv = Intrinsics::focal_for_aov(size, c.in.aov);
  c.in.cu = c.in.cv = size / 2.0;
  return c;
}

double band_std(const cv::Mat& gray, double s_fine, double s_coarse) {
  cv::Mat a = gray, b;
  if (s_fine > 0) cv::GaussianBlur(gray, a, cv::Size(), s_fine);
  cv::GaussianBlur(gray, b, cv::Size(), s_coarse);
  cv::Scalar mean, sd;
  cv::meanStdDev(a - b, mean, sd);
  return sd[0];
}

TEST(SimTube, GeometryAndClosedEnds) {
  const auto tube = make_tube_scene();
  EXPECT_EQ(tube->spec(), "tube:35");
  const Vec3 o = Vec3::Zero();
  // Every direction hits something textured: wall, far end, back end.
  for (const Vec3& d : {Vec3(0, 0, 1), Vec3(1, 0, 0), Vec3(0, 0, -1), Vec3(0.3, 0.2, 0.9).normalized()}) {
    const cv::Vec3f v = tube->radiance(o, d, o);
    EXPECT_GT(v[0] + v[1] + v[2], 0.05) << d.transpose();
    EXPECT_LE(std::max({v[0], v[1], v[2]}), 0.85f);
  }
  EXPECT_THROW(make_scene("tube:5"), SceneError);  // smaller than the dome
  EXPECT_EQ(make_scene("tube:40")->spec(), "tube:40");
  const auto flat = make_scene("flat:0.5");
  EXPECT_FLOAT_EQ(flat->radiance(o, Vec3(0, 1, 0), o)[1], 0.5f);
  EXPECT_THROW(make_scene("flat:-1"), SceneError);
}

TEST(SimTube, HighContrastTextureAtEveryScale) {
  // A camera looking at the wall and one at the far end: contrast over most of the range, and
  // texture in every band from one pixel to a quarter of the image.
  const auto tube = make_tube_scene();
  for (const Vec3& t : {Vec3(1, 0, 0.3), Vec3(0, 0, 1)}) {
    const RigCamera cam = side_camera(0, t);
    cv::Mat rad = render_radiance(*tube, cam, {}, 2), gray;
    cv::cvtColor(encode_srgb8(rad), gray, cv::COLOR_BGR2GRAY);
    gray.convertTo(gray, CV_32F, 1.0 / 255);
    cv::Mat sorted = gray.reshape(1, 1).clone();
    cv::sort(sorted, sorted, cv::SORT_ASCENDING);
    const float p5 = sorted.at<float>(int(sorted.total() * 0.05)),
                p95 = sorted.at<float>(int(sorted.total() * 0.95));
    EXPECT_GT(p95 - p5, 0.5) << t.transpose();
    EXPECT_GT(band_std(gray, 0, 1), 0.02) << "finest band, " << t.transpose();
    EXPECT_GT(band_std(gray, 1, 3), 0.04) << t.transpose();
    EXPECT_GT(band_std(gray, 3, 9), 0.04) << t.transpose();
    EXPECT_GT(band_std(gray, 9, 27), 0.02) << t.transpose();
  }
}

TEST(SimShots, SameGainsFreshNoiseOneFolderPerShot) {
  Rig rig;
  rig.name = "two";
  rig.cameras = {side_camera(0, Vec3(1, 0, 0.5), 64), side_camera(1, Vec3(0, 1, 0.5), 64)};
  SimulateOptions o;
  o.truth = false;
  o.progress = false;
  o.shots = 3;
  o.effects.read_noise_dn = 4;
  const auto tube = make_tube_scene();
  const SimulateSummary r = simulate(rig, *tube, o);
  ASSERT_EQ(r.more_shots.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    const CameraFrame& a = r.frames[i];
    const CameraFrame& b = r.more_shots[1][i];
    EXPECT_EQ(a.gains, b.gains);
    cv::Mat d = a.signal - b.signal;
    cv::Scalar mean, sd;
    cv::meanStdDev(d.reshape(1), mean, sd);
    EXPECT_GT(sd[0], 1e-3);              // independent noise ...
    EXPECT_LT(std::abs(mean[0]), 1e-3);  // ... of the same signal
  }
  // Shot 0 is the single-shot simulation (same seed, same noise).
  o.shots = 1;
  const SimulateSummary one = simulate(rig, *tube, o);
  EXPECT_EQ(cv::norm(one.frames[1].image, r.frames[1].image, cv::NORM_INF), 0);

  o.shots = 3;
  const auto dir = std::filesystem::temp_directory_path() / ("omma_shots_test_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  write_shots_folder(dir, r, o, *tube);
  const auto folders = expand_shot_folders({dir});
  ASSERT_EQ(folders.size(), 3u);
  EXPECT_EQ(folders[2].filename(), "shot_02");
  const auto sets = load_frame_sets({dir}, rig);
  EXPECT_EQ(cv::norm(sets[1][0], r.more_shots[0][0].image, cv::NORM_INF), 0);
  EXPECT_THROW(expand_shot_folders({dir / "nope"}), IoError);
  std::filesystem::remove_all(dir);
}

TEST(SimPhotometric, TruePolynomialFitsTheCos4Falloff) {
  // The prototype's camera (250 px, 64 deg) with the default 50 % vignetting, with and without
  // the test perturbations' lens distortion: the centred cubic in r^2 (Hugin's model) matches the
  // cos^4 falloff within 0.21 % everywhere with the minimax fit (a plain least-squares fit leaves
  // 1.1 % in the corners).
  CameraEffects e;
  for (double k1 : {0.0, 0.05}) {
    RigCamera c = side_camera(3, Vec3(1, 0, 0), 250);
    c.in.k[0] = k1;
    double err = 1;
    const Photometric p = true_photometric(c, e, &err);
    std::printf("k1 %.2f: largest relative error of the fitted polynomial %.5f\n", k1, err);
    EXPECT_LT(err, 3e-3) << "k1 " << k1;
    EXPECT_NEAR(vignetting_falloff(p, 250, 250, 0.5, 0.5) / true_falloff(c, e, Vec2(0.5, 0.5)), 1, 3e-3);
    const cv::Vec3d g = camera_gains(e, 3);
    EXPECT_EQ(p.gains[2], g[2]);
  }
}

}  // namespace
}  // namespace omma::sim
