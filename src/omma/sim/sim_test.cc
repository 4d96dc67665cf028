// Tests of the dome simulator: scenes, camera rendering, truth, sensor effects, perturbation.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "omma/core/frames.h"
#include "omma/sim/perturb.h"
#include "omma/sim/render.h"
#include "omma/sim/scene.h"
#include "omma/sim/simulate.h"
#include "omma/sim/usaf.h"

namespace omma::sim {
namespace {

RigCamera test_camera(int id, const Vec3& t, int size = 160, double aov_deg = 60, double k1 = 0) {
  RigCamera c;
  c.id = id;
  c.frame = frame_looking_at(t.normalized(), -Vec3::UnitZ());
  c.position_mm = 5 * t.normalized();
  c.in.width = c.in.height = size;
  c.in.aov = deg2rad(aov_deg);
  c.in.fu = c.in.fv = Intrinsics::focal_for_aov(size, c.in.aov);
  c.in.cu = c.in.cv = size / 2.0;
  c.in.k[0] = k1;
  return c;
}

Rig test_rig() {
  Rig r;
  r.name = "test-5";
  r.cameras.push_back(test_camera(0, Vec3(0, 0, 1), 96));
  for (int i = 0; i < 4; ++i)
    r.cameras.push_back(test_camera(i + 1, direction_from_spherical(deg2rad(50), i * kPi / 2), 96));
  return r;
}

// The louvre photo, reduced (8-bit sRGB) to keep the tests fast.
const cv::Mat& photo() {
  static const cv::Mat m = [] {
    cv::Mat full = cv::imread(std::string(OMMA_DATA_DIR) + "/louvre.jpg");
    cv::Mat small;
    if (!full.empty()) cv::resize(full, small, cv::Size(1024, 512), 0, 0, cv::INTER_AREA);
    return small;
  }();
  return m;
}

// Photo sampled (cv::remap, bilinear, sRGB values) at the directions `dir(col, row)`.
template <typename F>
cv::Mat remap_photo(const cv::Mat& img, int w, int h, F dir) {
  cv::Mat mx(h, w, CV_32F), my(h, w, CV_32F);
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) {
      const Spherical s = spherical_from_direction(dir(c, r));
      mx.at<float>(r, c) = static_cast<float>(equirect_x(s.phi, img.cols) - 0.5);  // (G1)
      my.at<float>(r, c) = static_cast<float>(s.theta / kPi * img.rows - 0.5);
    }
  cv::Mat out;
  cv::remap(img, out, mx, my, cv::INTER_LINEAR, cv::BORDER_WRAP);
  return out;
}

TEST(SimPhoto, IdealCameraMatchesPhotoResampled) {
  ASSERT_FALSE(photo().empty()) << "missing " << OMMA_DATA_DIR << "/louvre.jpg";
  const auto scene = make_photo_scene(photo());
  // An oblique camera with barrel distortion exercises unproject (eq. 5.21-5.26 inverted).
  const RigCamera cam = test_camera(3, direction_from_spherical(deg2rad(60), deg2rad(100)), 128, 60, -0.08);
  const CameraFrame f = render_camera(*scene, cam, {}, CameraEffects::ideal(1));
  const CameraModel m = cam.model();
  const cv::Mat ref =
      remap_photo(photo(), 128, 128, [&](int c, int r) { return m.unproject(Vec2(c + 0.5, r + 0.5)); });
  const double psnr = cv::PSNR(f.image, ref);
  EXPECT_GT(psnr, 35.0);
  // With 3x3 supersampling (optical blur) the image is close but not identical.
  const CameraFrame blurred = render_camera(*scene, cam, {}, CameraEffects::ideal(3));
  const double psnr_blur = cv::PSNR(blurred.image, ref);
  std::printf("  ideal camera vs remapped photo: %.2f dB (1 ray), %.2f dB (3x3 rays)\n", psnr, psnr_blur);
  EXPECT_GT(psnr_blur, 25.0);
  EXPECT_LT(psnr_blur, psnr);
}

TEST(SimPhoto, TruthEqualsPhotoResampledOnTheGrid) {
  const auto scene = make_photo_scene(photo());
  for (Projection p : {Projection::kEquirect, Projection::kVr180}) {
    const PanoGrid grid{p, 256, p == Projection::kEquirect ? 64 : 256};
    const cv::Mat truth = render_truth(*scene, grid, {}, 1);
    ASSERT_EQ(truth.type(), CV_8UC3);
    ASSERT_EQ(truth.cols, grid.width);
    const cv::Mat ref = remap_photo(photo(), grid.width, grid.height,
                                    [&](int c, int r) { return grid.pixel_direction(c, r); });
    std::printf("  truth %s vs remapped photo: %.2f dB\n", to_string(p).c_str(), cv::PSNR(truth, ref));
    EXPECT_GT(cv::PSNR(truth, ref), 38.0) << to_string(p);
  }
}

TEST(SimPhoto, EquirectTruthIsTheTopHalfOfThePhoto) {
  // Photo top row = dome axis, centre row = horizon, read as an equirect-full panorama (conventions.h
  // (G1), as every 360-degree viewer shows it): the 360x90 grid at the photo's own resolution
  // reproduces the top half pixel for pixel (up to the sRGB round trip), and not its mirror image.
  const auto scene = make_photo_scene(photo());
  const PanoGrid grid{Projection::kEquirect, photo().cols, photo().rows / 2};
  const cv::Mat truth = render_truth(*scene, grid, {}, 1);
  const cv::Mat top = photo().rowRange(0, photo().rows / 2);
  cv::Mat mirrored;
  cv::flip(top, mirrored, 1);
  EXPECT_GT(cv::PSNR(truth, top), 45.0);
  EXPECT_LT(cv::PSNR(truth, mirrored), 25.0);
}

TEST(SimColon, BrightnessFallsWithDistance) {
  const auto scene = make_colon_scene();
  // Mean luminance of the truth in bands of polar angle: looking down the tube (small theta) the
  // wall is far and dark; looking sideways it is near and bright (inverse-square lighting).
  const PanoGrid grid{Projection::kEquirect, 180, 90};  // 1 deg rows
  const cv::Mat lin = render_truth_linear(*scene, grid, {}, 1);
  std::vector<double> band;
  for (int b = 0; b < 6; ++b) {
    cv::Mat gray;
    cv::cvtColor(lin.rowRange(b * 15, b * 15 + 15), gray, cv::COLOR_BGR2GRAY);
    band.push_back(cv::mean(gray)[0]);
  }
  for (int b = 0; b + 1 < 4; ++b) EXPECT_LT(band[b], band[b + 1]) << "band " << b;
  EXPECT_LT(band[0], 0.1 * band[5]);
  // Inverse-square law: the same wall point seen along the same ray from further back (light at
  // the ray origin, same incidence) gets darker as 1/d^2: sqrt(L0 / Lk) = 1 + 3k / d0 for origins
  // moved back by 3k mm. d0 from k = 1 must predict k = 2..4.
  std::vector<double> lum;
  for (int k = 0; k <= 4; ++k) {
    const Vec3 o(-3.0 * k, 0, 2);
    lum.push_back(cv::norm(scene->radiance(o, Vec3::UnitX(), o)));
  }
  const double d0 = 3.0 / (std::sqrt(lum[0] / lum[1]) - 1);
  EXPECT_GT(d0, 12);  // the wall is 12-30 mm from the axis
  EXPECT_LT(d0, 30);
  std::printf("  colon bands:");
  for (double b : band) std::printf(" %.4f", b);
  std::printf("; wall distance from the falloff d0 = %.1f mm\n", d0);
  for (int k = 2; k <= 4; ++k) EXPECT_NEAR(std::sqrt(lum[0] / lum[k]), 1 + 3.0 * k / d0, 0.01) << k;
}

TEST(SimColon, HasVisiblePolypsAndIsDeterministic) {
  const auto a = make_colon_scene();
  const auto b = make_colon_scene();
  const RigCamera cam = test_camera(0, direction_from_spherical(deg2rad(55), deg2rad(40)), 64);
  const cv::Mat ia = render_radiance(*a, cam, {}, 1), ib = render_radiance(*b, cam, {}, 1);
  EXPECT_EQ(cv::norm(ia, ib, cv::NORM_INF), 0.0);
  // Reddish: R > G, B on average.
  const cv::Scalar m = cv::mean(ia);
  EXPECT_GT(m[2], 1.5 * m[1]);
  EXPECT_GT(m[2], 1.5 * m[0]);
}

TEST(SimPerturb, TrueRigDiffersByTheRequestedAmounts) {
  const Rig nominal = test_rig();
  const PerturbSpec spec = parse_perturb("orient=1.5,focal=0.03,center=4,k1=-0.05,pos=0.2");
  const Rig truth = perturb_rig(nominal, spec, 42);
  ASSERT_EQ(truth.cameras.size(), nominal.cameras.size());
  for (size_t i = 0; i < nominal.cameras.size(); ++i) {
    const RigCamera &a = nominal.cameras[i], &b = truth.cameras[i];
    const Mat3 rel = b.frame.dome_to_camera() * a.frame.dome_to_camera().transpose();
    const double angle = rad2deg(std::acos(std::clamp((rel.trace() - 1) / 2, -1.0, 1.0)));
    EXPECT_NEAR(angle, 1.5, 1e-6) << "camera " << i;
    EXPECT_NEAR(std::abs(b.in.fu / a.in.fu - 1), 0.03, 1e-9);
    EXPECT_NEAR(b.in.fv / a.in.fv, b.in.fu / a.in.fu, 1e-12);
    EXPECT_NEAR(std::hypot(b.in.cu - a.in.cu, b.in.cv - a.in.cv), 4.0, 1e-9);
    EXPECT_NEAR(b.in.k[0] - a.in.k[0], -0.05, 1e-12);
    EXPECT_NEAR((b.position_mm - a.position_mm).norm(), 0.2, 1e-9);
  }
  // Reproducible from the seed, different for another seed.
  const Rig again = perturb_rig(nominal, spec, 42), other = perturb_rig(nominal, spec, 43);
  EXPECT_EQ((again.cameras[1].frame.t - truth.cameras[1].frame.t).norm(), 0.0);
  EXPECT_GT((other.cameras[1].frame.t - truth.cameras[1].frame.t).norm(), 1e-6);
}

TEST(SimPerturb, BadSpecsAreRejected) {
  EXPECT_FALSE(parse_perturb("").any());
  for (const char* bad : {"orient", "orient=x", "tilt=1", "focal=-0.1", "orient=90", "k1=5", "focal=0.1,"})
    EXPECT_THROW(parse_perturb(bad), std::invalid_argument) << bad;
  try {
    parse_perturb("tilt=1");
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("tilt"), std::string::npos);
  }
}

TEST(SimSensor, RawBayerMosaicIsRggb) {
  RigCamera cam = test_camera(0, Vec3(0, 0, 1), 8);
  cv::Mat radiance(8, 8, CV_32FC3, cv::Scalar(0.2, 0.5, 0.8));  // B, G, R
  CameraEffects e = CameraEffects::ideal(1);
  e.bits = 10;
  const CameraFrame f = apply_sensor(radiance, cam, e, true);
  ASSERT_EQ(f.raw.type(), CV_16UC1);
  EXPECT_EQ(f.raw.at<uint16_t>(0, 0), std::lround(0.8 * 1023));  // R
  EXPECT_EQ(f.raw.at<uint16_t>(0, 1), std::lround(0.5 * 1023));  // G
  EXPECT_EQ(f.raw.at<uint16_t>(1, 0), std::lround(0.5 * 1023));  // G
  EXPECT_EQ(f.raw.at<uint16_t>(1, 1), std::lround(0.2 * 1023));  // B
  EXPECT_EQ(f.raw.at<uint16_t>(6, 7), std::lround(0.5 * 1023));
  EXPECT_EQ(f.raw.at<uint16_t>(7, 7), std::lround(0.2 * 1023));
  // The 8-bit frame is the sRGB encoding of the same quantised signal.
  EXPECT_EQ(f.image.at<cv::Vec3b>(0, 0)[2],
            std::lround(255 * linear_to_srgb(std::lround(0.8 * 1023) / 1023.0f)));
}

TEST(SimSensor, NoiseStatisticsAsConfigured) {
  RigCamera cam = test_camera(5, Vec3(0, 0, 1), 200);
  const double level = 0.25;
  cv::Mat radiance(200, 200, CV_32FC3, cv::Scalar::all(level));
  CameraEffects e = CameraEffects::ideal(1);
  e.full_scale_electrons = 4000;
  e.read_noise_dn = 2.0;
  e.bits = 10;
  const CameraFrame f = apply_sensor(radiance, cam, e);
  cv::Scalar mean, sd;
  cv::meanStdDev(f.signal.reshape(1), mean, sd);
  const double expected = std::sqrt(level / 4000 + std::pow(2.0 / 1023, 2) + 1.0 / (12 * 1023.0 * 1023.0));
  EXPECT_NEAR(mean[0], level, 0.001);
  std::printf("  noise sd %.5f expected %.5f, mean %.5f\n", sd[0], expected, mean[0]);
  EXPECT_NEAR(sd[0], expected, 0.05 * expected);
  // Deterministic per seed; another seed gives other noise.
  EXPECT_EQ(cv::norm(f.signal, apply_sensor(radiance, cam, e).signal, cv::NORM_INF), 0.0);
  CameraEffects e2 = e;
  e2.seed = 2;
  EXPECT_GT(cv::norm(f.signal, apply_sensor(radiance, cam, e2).signal, cv::NORM_INF), 0.0);
}

TEST(SimSensor, VignettingAndGains) {
  RigCamera cam = test_camera(2, Vec3(0, 0, 1), 100, 80);
  cv::Mat radiance(100, 100, CV_32FC3, cv::Scalar::all(0.5));
  CameraEffects e = CameraEffects::ideal(1);
  e.vignetting = 1.0;
  const CameraFrame f = apply_sensor(radiance, cam, e);
  const double a = angle_between(cam.model().unproject(Vec2(0.5, 0.5)), cam.frame.t);
  EXPECT_NEAR(f.signal.at<cv::Vec3f>(0, 0)[1], 0.5 * std::pow(std::cos(a), 4), 1e-5);
  EXPECT_NEAR(f.signal.at<cv::Vec3f>(50, 50)[1], 0.5, 1e-3);
  e = CameraEffects::ideal(1);
  e.color_gain = 0.1;
  double spread = 0;
  for (int id = 0; id < 20; ++id) {
    const cv::Vec3d g = camera_gains(e, id);
    for (int k = 0; k < 3; ++k) {
      EXPECT_GE(g[k], 0.9);
      EXPECT_LE(g[k], 1.1);
      spread = std::max(spread, std::abs(g[k] - 1));
    }
  }
  EXPECT_GT(spread, 0.05);
  cam.id = 7;
  const CameraFrame fg = apply_sensor(radiance, cam, e);
  EXPECT_NEAR(fg.signal.at<cv::Vec3f>(10, 10)[0], 0.5 * camera_gains(e, 7)[0], 1e-5);
}

TEST(SimScene, SpecsAndClearErrors) {
  EXPECT_EQ(make_scene("checker:50")->spec(), "checker:50");
  EXPECT_EQ(make_scene("usaf")->spec(), "usaf:25");
  EXPECT_EQ(make_scene("colon")->spec(), "colon");
  auto message = [](const std::string& spec) {
    try {
      make_scene(spec);
    } catch (const SceneError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("sky").find("unknown scene"), std::string::npos);
  EXPECT_NE(message("photo:/no/such.jpg").find("does not exist"), std::string::npos);
  EXPECT_NE(message("photo:").find("needs a path"), std::string::npos);
  EXPECT_NE(message("checker:abc").find("not a number"), std::string::npos);
  EXPECT_NE(message("checker:-3").find("positive"), std::string::npos);
  // Numbers that overflowed to inf and NaN in the simulator: refused with the bound.
  EXPECT_NE(message("checker:1e300").find("up to 1000000"), std::string::npos) << message("checker:1e300");
  EXPECT_NE(message("usaf:1e308").find("up to 1000000"), std::string::npos);
  EXPECT_NE(message("flat:1e308").find("(0, 1000]"), std::string::npos) << message("flat:1e308");
  EXPECT_NE(message("flat:nan").find("(0, 1000]"), std::string::npos);
  const auto dir = std::filesystem::temp_directory_path() / "omma_sim_badphoto";
  std::filesystem::create_directories(dir);
  { std::ofstream(dir / "x.jpg") << "not an image"; }
  EXPECT_NE(message("photo:" + (dir / "x.jpg").string()).find("cannot read"), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(SimUsaf, ChartGeometry) {
  EXPECT_NEAR(usaf_lp_per_mm(1, 2), 2.2449, 1e-3);  // thesis §5.5.2: group 1 element 2
  EXPECT_NEAR(usaf_lp_per_mm(0, 1), 1.0, 1e-12);
  const auto& chart = usaf_chart();
  ASSERT_EQ(chart.size(), 30u);
  for (const auto& e : chart) {
    const double b = e.bar_mm;
    EXPECT_NEAR(b, 0.5 / e.lp_per_mm, 1e-12);
    // Vertical bars: black at bar centres (x offsets -2b, 0, 2b), white in the gaps (-b, b).
    for (double dx : {-2.0, 0.0, 2.0})
      EXPECT_EQ(usaf_paint(e.vertical_bars_mm + Vec2(dx * b, 0.3 * b)), UsafPaint::kBlack);
    for (double dx : {-1.0, 1.0})
      EXPECT_EQ(usaf_paint(e.vertical_bars_mm + Vec2(dx * b, 0.3 * b)), UsafPaint::kWhite);
    for (double dy : {-2.0, 0.0, 2.0})
      EXPECT_EQ(usaf_paint(e.horizontal_bars_mm + Vec2(0.3 * b, dy * b)), UsafPaint::kBlack);
    for (double dy : {-1.0, 1.0})
      EXPECT_EQ(usaf_paint(e.horizontal_bars_mm + Vec2(0.3 * b, dy * b)), UsafPaint::kWhite);
  }
  // Seen from the dome centre, group 1 element 2 bars subtend about 0.5 deg at 25 mm (thesis).
  const double bar = 0.5 / usaf_lp_per_mm(1, 2);
  EXPECT_NEAR(rad2deg(std::atan(bar / 25.0)), 0.51, 0.01);
}

TEST(SimSimulate, FramesFolderIsComplete) {
  const Rig rig = test_rig();
  const auto scene = make_checker_scene(80);
  SimulateOptions o;
  o.truth_grid = PanoGrid{Projection::kVr180, 128, 128};
  o.raw = true;
  o.progress = false;
  const SimulateSummary r = simulate(rig, *scene, o);
  ASSERT_EQ(r.frames.size(), rig.cameras.size());
  const auto dir = std::filesystem::temp_directory_path() / "omma_sim_folder_test";
  std::filesystem::remove_all(dir);
  write_frames_folder(dir, r, o, *scene);
  const Rig loaded = load_rig(dir / "rig.json");
  const auto frames = load_frames(dir, loaded);
  const auto raws = load_raw_frames(dir, loaded);
  ASSERT_EQ(frames.size(), rig.cameras.size());
  EXPECT_EQ(cv::norm(frames[2], r.frames[2].image, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(raws[1], r.frames[1].raw, cv::NORM_INF), 0.0);
  const cv::Mat truth = cv::imread((dir / "truth.png").string());
  EXPECT_EQ(truth.cols, 128);
  EXPECT_EQ(cv::norm(truth, r.truth, cv::NORM_INF), 0.0);
  EXPECT_TRUE(std::filesystem::exists(dir / "rig_true.json"));
  EXPECT_TRUE(std::filesystem::exists(dir / "sim.json"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace omma::sim

namespace omma::sim {
namespace {

TEST(SimUsaf, TruthResolutionFollowsThePanoramaPixelSize) {
  const auto scene = make_usaf_scene(25);
  auto limit_bar_deg = [&](int size) {
    const PanoGrid grid{Projection::kVr180, size, size};
    const UsafMeasurement m = measure_usaf(render_truth(*scene, grid, {}, 2), grid, 25, 0.1);
    EXPECT_NE(m.limit(), nullptr) << size;
    EXPECT_NE(m.strict_limit(), nullptr) << size;
    return m.limit() ? m.limit()->bar_deg : 99.0;
  };
  const double px360 = 180.0 / 360, px900 = 180.0 / 900;
  const double coarse = limit_bar_deg(360), fine = limit_bar_deg(900);
  std::printf("  truth USAF limit: %.3f deg/bar at 360 px (%.3f deg/px), %.3f at 900 px (%.3f deg/px)\n",
              coarse, px360, fine, px900);
  EXPECT_LT(fine, coarse);
  // A bar needs at least about one pixel, and about two pixels suffice (box-filtered truth).
  EXPECT_GE(coarse, 0.9 * px360);
  EXPECT_LE(coarse, 2.5 * px360);
  EXPECT_GE(fine, 0.9 * px900);
  EXPECT_LE(fine, 2.5 * px900);
}

TEST(SimRender, AutoTruthSupersampling) {
  EXPECT_EQ(auto_truth_supersample({Projection::kVr180, 1080, 1080}), 2);
  EXPECT_EQ(auto_truth_supersample({Projection::kVr180, 540, 540}), 4);
  EXPECT_EQ(auto_truth_supersample({Projection::kVr180, 4000, 4000}), 1);
  EXPECT_EQ(auto_truth_supersample({Projection::kEquirect, 1920, 480}), 3);
  EXPECT_EQ(auto_truth_supersample({Projection::kEquirect, 64, 16}), 4);
}

TEST(SimRender, RenderRigEqualsCameraByCamera) {
  const Rig rig = test_rig();
  const auto scene = make_checker_scene(40);
  DomePose pose;
  pose.translation_mm = Vec3(1, 2, 3);
  CameraEffects e;
  e.supersample = 2;
  e.seed = 9;
  const auto frames = render_rig(*scene, rig, pose, e, true);
  ASSERT_EQ(frames.size(), rig.cameras.size());
  for (size_t i = 0; i < frames.size(); ++i) {
    const CameraFrame one = render_camera(*scene, rig.cameras[i], pose, e, true);
    EXPECT_EQ(cv::norm(frames[i].image, one.image, cv::NORM_INF), 0.0) << i;
    EXPECT_EQ(cv::norm(frames[i].raw, one.raw, cv::NORM_INF), 0.0) << i;
  }
}

TEST(SimRender, MovingTheDomeRotatesWhatTheCamerasSee) {
  // Rotating the dome by R equals rendering a camera whose frame is turned by R (far-field scene).
  const auto scene = make_photo_scene(photo());
  const RigCamera cam = test_camera(1, direction_from_spherical(deg2rad(40), deg2rad(10)), 64);
  DomePose pose;
  pose.rotation = Eigen::AngleAxisd(deg2rad(30), Vec3(1, 2, 3).normalized()).toRotationMatrix();
  pose.translation_mm = Vec3(3, -2, 40);
  RigCamera turned = cam;
  turned.frame.t = pose.rotation * cam.frame.t;
  turned.frame.u = pose.rotation * cam.frame.u;
  turned.frame.v = pose.rotation * cam.frame.v;
  const cv::Mat a = render_radiance(*scene, cam, pose, 1), b = render_radiance(*scene, turned, {}, 1);
  EXPECT_LT(cv::norm(a, b, cv::NORM_INF), 1e-5);
}

}  // namespace
}  // namespace omma::sim

#include "omma/design/prototype.h"
#include "omma/testing/expect.h"

namespace omma::sim {
namespace {

TEST(SimPrototype, EveryCameraOfTheThesisDomeSeesThePhotoWhereItShould) {
  const Rig rig = design::thesis_prototype_rig();
  ASSERT_EQ(rig.cameras.size(), 24u);
  const auto scene = make_photo_scene(photo());
  double worst = 1e9;
  for (const auto& cam : rig.cameras) {
    const CameraFrame f = render_camera(*scene, cam, {}, CameraEffects::ideal(1));
    const CameraModel m = cam.model();
    const cv::Mat ref = remap_photo(photo(), cam.in.width, cam.in.height,
                                    [&](int c, int r) { return m.unproject(Vec2(c + 0.5, r + 0.5)); });
    worst = std::min(worst, cv::PSNR(f.image, ref));
  }
  std::printf("  prototype: worst camera vs remapped photo %.2f dB\n", worst);
  EXPECT_GT(worst, 35.0);
}

using testing::refusal;

TEST(SimOptions, RefuseBadValues) {
  SimulateOptions o;
  EXPECT_TRUE(o.IsValid());
  o.shots = 0;
  EXPECT_FALSE(o.IsValid());
  const Rig rig = design::thesis_prototype_rig();
  const auto scene = make_colon_scene();
  EXPECT_EQ(refusal([&] { simulate(rig, *scene, o); }), "shots must be 1..1000, got 0");
  o = {};
  o.truth_supersample = -1;
  EXPECT_FALSE(o.IsValid());
}

}  // namespace
}  // namespace omma::sim
