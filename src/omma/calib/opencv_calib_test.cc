// OpenCV calibration files: omma's camera model equals OpenCV's (cv::projectPoints) under the mapping
// of opencv_calib.h, the sample files of opencv-doc read as written, and omma's export reads back.
#include "omma/calib/opencv_calib.h"

#include <unistd.h>

#include <cmath>
#include <fstream>
#include <random>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>

#include "omma/testing/real_data.h"

namespace omma::calib {
namespace {
namespace fs = std::filesystem;

// A camera frame equal to OpenCV's camera axes (u = x, v = y, t = z), so that omma's dome coordinates
// are OpenCV's camera coordinates.
Frame opencv_axes() {
  Frame f;
  f.t = Vec3::UnitZ();
  f.u = Vec3::UnitX();
  f.v = Vec3::UnitY();
  return f;
}

// Largest |omma projection - (cv::projectPoints + 0.5)| over rays through a grid of nx x ny points of
// the image, edges included (found with cv::undistortPoints and kept where they reproject exactly and
// the camera sees them; with `edges` also the right and bottom edges, which lie outside [0, W) x [0, H)),
// in pixels; *count = rays used.
double max_projection_difference(const Intrinsics& in, const cv::Matx33d& K, const std::vector<double>& D,
                                 int* count, int nx = 33, int ny = 25, bool edges = false) {
  std::vector<cv::Point2d> px;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      px.emplace_back(in.width * i / double(nx - 1) - 0.5, in.height * j / double(ny - 1) - 0.5);
  std::vector<cv::Point2d> und, back;
  cv::undistortPoints(px, und, K, D, cv::noArray(), cv::noArray(),
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 500, 1e-15));
  std::vector<cv::Point3d> rays;
  for (const auto& p : und) rays.emplace_back(p.x, p.y, 1.0);
  cv::projectPoints(rays, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, D, back);
  const CameraModel cam{opencv_axes(), in};
  double worst = 0;
  *count = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    if (cv::norm(back[i] - px[i]) > 1e-6) continue;  // outside the invertible part of OpenCV's model
    const Vec3 w(rays[i].x, rays[i].y, rays[i].z);
    if (!edges && !cam.sees(w.normalized())) continue;
    const auto p = cam.project(w);
    if (!p) continue;
    worst = std::max(worst, std::hypot(p->x() - (back[i].x + 0.5), p->y() - (back[i].y + 0.5)));
    ++*count;
  }
  return worst;
}

TEST(OpenCvCalib, DistortionMappingEqualsProjectPoints) {
  // Random cameras with every OpenCV coefficient of the 5-vector non-zero: omma (k1, k2, p2, p1, k3).
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 20; ++trial) {
    const cv::Matx33d K(500 + 100 * u(rng), 0, 320 + 20 * u(rng), 0, 480 + 100 * u(rng), 240 + 20 * u(rng), 0,
                        0, 1);
    const std::vector<double> D = {0.1 * u(rng), 0.05 * u(rng), 0.001 + 0.001 * u(rng),
                                   -0.001 + 0.0005 * u(rng), 0.01 * u(rng)};
    OpenCvCamera oc;
    oc.K = K;
    oc.D = D;
    std::vector<std::string> warnings;
    const Intrinsics in = opencv_intrinsics(oc, 640, 480, "random camera", nullptr, &warnings);
    int n = 0;
    const double diff = max_projection_difference(in, K, D, &n);
    EXPECT_GT(n, 500) << trial;
    EXPECT_LT(diff, 1e-9) << trial;  // measured 1e-13 (rounding only)
    // The mapping is not a guess that happens to pass: swapping p1 and p2 is off by pixels.
    Intrinsics swapped = in;
    std::swap(swapped.k[2], swapped.k[3]);
    EXPECT_GT(max_projection_difference(swapped, K, D, &n), 0.05) << trial;
  }
}

TEST(OpenCvCalib, ReadsTheCalibrationSampleFile) {
  const fs::path dir = testing::opencv_samples_dir();
  if (dir.empty() || !fs::exists(dir / "left_intrinsics.yml"))
    GTEST_SKIP() << "opencv-doc samples not installed";
  const fs::path file = dir / "left_intrinsics.yml";
  const OpenCvCalibration c = read_opencv_calibration(file);
  EXPECT_EQ(c.layout, "calibration");
  ASSERT_EQ(c.cameras.size(), 1u);
  // The numbers as OpenCV reads them.
  cv::FileStorage f(file.string(), cv::FileStorage::READ);
  cv::Mat K, D;
  f["camera_matrix"] >> K;
  f["distortion_coefficients"] >> D;
  EXPECT_EQ(int(f["image_width"]), 640);
  std::vector<std::string> warnings;
  const Intrinsics in = opencv_intrinsics(c.cameras[0], 0, 0, "left", nullptr, &warnings);
  EXPECT_TRUE(warnings.empty()) << warnings[0];
  EXPECT_EQ(in.width, 640);
  EXPECT_EQ(in.height, 480);
  EXPECT_EQ(in.fu, K.at<double>(0, 0));
  EXPECT_EQ(in.fv, K.at<double>(1, 1));
  EXPECT_EQ(in.cu, K.at<double>(0, 2) + 0.5);
  EXPECT_EQ(in.cv, K.at<double>(1, 2) + 0.5);
  EXPECT_EQ(in.k[0], D.at<double>(0));
  EXPECT_EQ(in.k[1], D.at<double>(1));
  EXPECT_EQ(in.k[2], D.at<double>(3));  // p2
  EXPECT_EQ(in.k[3], D.at<double>(2));  // p1
  EXPECT_EQ(in.k[4], D.at<double>(4));  // k3
  EXPECT_EQ(in.field, Intrinsics::Field::kImage);
  int n = 0;
  const std::vector<double> d(D.begin<double>(), D.end<double>());
  const double diff = max_projection_difference(in, cv::Matx33d(K.ptr<double>()), d, &n);
  std::printf("left_intrinsics.yml: %d rays over the image, max |omma - projectPoints| = %.3g px\n", n, diff);
  EXPECT_EQ(n, 32 * 24);  // every grid point inside [0, W) x [0, H): the lens model maps the whole image
  EXPECT_LT(diff, 1e-6);
}

TEST(OpenCvCalib, ReadsTheStereoSampleFile) {
  const fs::path dir = testing::opencv_samples_dir();
  if (dir.empty() || !fs::exists(dir / "intrinsics.yml")) GTEST_SKIP() << "opencv-doc samples not installed";
  const fs::path file = dir / "intrinsics.yml";
  const OpenCvCalibration c = read_opencv_calibration(file);
  EXPECT_EQ(c.layout, "stereo");
  ASSERT_EQ(c.cameras.size(), 2u);
  EXPECT_FALSE(c.cameras[1].R.has_value());  // intrinsics only
  // No size in the file: it must come from the user.
  try {
    opencv_intrinsics(c.cameras[0], 0, 0, "camera 1");
    ADD_FAILURE() << "a camera without a size was accepted";
  } catch (const OpenCvCalibError& e) {
    EXPECT_NE(std::string(e.what()).find("image size"), std::string::npos) << e.what();
  }
  cv::FileStorage f(file.string(), cv::FileStorage::READ);
  for (int i = 0; i < 2; ++i) {
    cv::Mat K, D;
    f[fmt::format("M{}", i + 1)] >> K;
    f[fmt::format("D{}", i + 1)] >> D;
    std::vector<std::string> warnings;
    const Intrinsics in =
        opencv_intrinsics(c.cameras[i], 640, 480, fmt::format("camera {}", i + 1), nullptr, &warnings);
    EXPECT_EQ(in.fu, K.at<double>(0, 0));
    EXPECT_EQ(in.cu, K.at<double>(0, 2) + 0.5);
    EXPECT_EQ(in.cv, K.at<double>(1, 2) + 0.5);
    EXPECT_EQ(in.k[0], D.at<double>(0));
    EXPECT_EQ(in.k[1], D.at<double>(1));
    // Both calibrations fold back before the image corners (k2 < 0 dominates there): the camera sees
    // the widest cone its lens model describes, and says so.
    for (const auto& w : warnings) std::printf("%s\n", w.c_str());
    EXPECT_EQ(in.field, Intrinsics::Field::kCone);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_TRUE(in.lens_problem().empty());
    EXPECT_GT(rad2deg(in.aov), 50.0);  // measured 66.4 and 70.4 deg
    int n = 0;
    const std::vector<double> d(D.begin<double>(), D.end<double>());
    const double diff = max_projection_difference(in, cv::Matx33d(K.ptr<double>()), d, &n);
    std::printf("intrinsics.yml camera %d: cone %.2f deg, %d rays, max |omma - projectPoints| = %.3g px\n",
                i + 1, rad2deg(in.aov), n, diff);
    EXPECT_GE(n, 300);
    EXPECT_LT(diff, 1e-6);
  }
}

Rig two_camera_rig() {
  Rig rig;
  rig.name = "pair";
  for (int i = 0; i < 2; ++i) {
    RigCamera c;
    c.id = 3 + 4 * i;
    c.frame = frame_from_ypr({deg2rad(10 + 25 * i), deg2rad(-5 + 3 * i), deg2rad(170 + 7 * i)});
    c.position_mm = Vec3(1.5 - 60 * i, 2 + 0.5 * i, -3 + i);
    c.in.width = 640 + 160 * i;
    c.in.height = 480;
    c.in.fu = 530 + i;
    c.in.fv = 531 - i;
    c.in.cu = 321.25;
    c.in.cv = 239.75 + i;
    c.in.k = {-0.12, 0.03, 0.0007, -0.0004, 0.002 * i};
    std::vector<std::string> w;
    EXPECT_EQ(choose_field(c.in, "test"), "");
    rig.cameras.push_back(c);
  }
  rig.dome = dome_around(rig, "test");
  return rig;
}

TEST(OpenCvCalib, ExportReadsBackInOpenCvAndInOmma) {
  const fs::path dir = fs::temp_directory_path() / fmt::format("omma-opencv-calib-{}", ::getpid());
  fs::create_directories(dir);
  const Rig rig = two_camera_rig();
  for (const char* ext : {".yml", ".xml"}) {
    const fs::path file = dir / (std::string("pair") + ext);
    write_opencv_calibration(rig, file);
    // OpenCV reads the stereo layout and its numbers (pixel centres shifted by 0.5).
    cv::FileStorage f(file.string(), cv::FileStorage::READ);
    ASSERT_TRUE(f.isOpened());
    cv::Mat M1, D2, R, T;
    f["M1"] >> M1;
    f["D2"] >> D2;
    f["R"] >> R;
    f["T"] >> T;
    EXPECT_EQ(M1.at<double>(0, 0), rig.cameras[0].in.fu);
    EXPECT_EQ(M1.at<double>(0, 2), rig.cameras[0].in.cu - 0.5);
    EXPECT_EQ(M1.at<double>(1, 2), rig.cameras[0].in.cv - 0.5);
    ASSERT_EQ(D2.total(), 5u);
    EXPECT_EQ(D2.at<double>(2), rig.cameras[1].in.k[3]);  // p1 = omma k4
    EXPECT_EQ(D2.at<double>(4), rig.cameras[1].in.k[4]);
    // R, T as cv::stereoCalibrate defines them: x2 = R x1 + T for any point, in each camera's axes (mm).
    const Vec3 X(100, -40, 250);
    auto in_camera = [&](const RigCamera& c) {
      const Vec3 d = X - c.position_mm;
      return cv::Vec3d(d.dot(c.frame.u), d.dot(c.frame.v), d.dot(c.frame.t));
    };
    const cv::Vec3d x1 = in_camera(rig.cameras[0]), x2 = in_camera(rig.cameras[1]);
    const cv::Mat pred = R * cv::Mat(x1) + T;
    EXPECT_LT(cv::norm(pred - cv::Mat(x2)), 1e-9) << ext;
    // omma reads it back: the same rig.
    const OpenCvRigSummary back = rig_from_opencv(read_opencv_calibration(file), {});
    ASSERT_EQ(back.rig.cameras.size(), 2u);
    EXPECT_EQ(back.max_fit_px, 0);
    for (int i = 0; i < 2; ++i) {
      const RigCamera &a = rig.cameras[i], &b = back.rig.cameras[i];
      EXPECT_EQ(a.id, b.id);
      EXPECT_LT((a.frame.t - b.frame.t).norm(), 1e-12);
      EXPECT_LT((a.frame.u - b.frame.u).norm(), 1e-12);
      EXPECT_LT((a.position_mm - b.position_mm).norm(), 1e-9);
      EXPECT_EQ(a.in.width, b.in.width);
      EXPECT_NEAR(a.in.cu, b.in.cu, 1e-12);
      EXPECT_NEAR(a.in.fv, b.in.fv, 1e-12);
      for (int j = 0; j < 5; ++j) EXPECT_EQ(a.in.k[j], b.in.k[j]);
      EXPECT_NEAR(a.in.aov, b.in.aov, 1e-12);
    }
  }
  // One camera: the calibration sample's layout.
  Rig one = rig;
  one.cameras.resize(1);
  const fs::path file = dir / "one.yml";
  write_opencv_calibration(one, file);
  cv::FileStorage f(file.string(), cv::FileStorage::READ);
  cv::Mat K;
  f["camera_matrix"] >> K;
  EXPECT_EQ(K.at<double>(1, 1), one.cameras[0].in.fv);
  EXPECT_EQ(int(f["image_width"]), 640);
  EXPECT_EQ(read_opencv_calibration(file).layout, "calibration");
  fs::remove_all(dir);
}

TEST(OpenCvCalib, RationalModelIsFittedWithItsResidual) {
  Intrinsics in;
  in.width = 640, in.height = 480, in.fu = in.fv = 535, in.cu = 320.5, in.cv = 240.5;
  const std::vector<double> exact8 = {-0.2, 0.05, 0.001, -0.0005, 0.01, 0, 0, 0};
  LensConversion c = omma_k_from_opencv(exact8, in, "exact");
  EXPECT_TRUE(c.exact);
  EXPECT_EQ(c.k[4], 0.01);
  std::vector<double> d = exact8;
  d[5] = 0.2;  // k4: a rational radial factor
  c = omma_k_from_opencv(d, in, "camera 0");
  EXPECT_FALSE(c.exact);
  EXPECT_NE(c.note.find("camera 0"), std::string::npos);
  // The reported residual is the one cv::projectPoints measures.
  Intrinsics fitted = in;
  fitted.k = c.k;
  int n = 0;
  const double diff = max_projection_difference(fitted, opencv_camera_matrix(in), d, &n, 41, 31, true);
  std::printf("rational k4 = 0.2 fitted: reported %.4f px max, measured %.4f px over %d rays\n", c.max_px,
              diff, n);
  EXPECT_EQ(n, 41 * 31);
  EXPECT_NEAR(diff, c.max_px, 1e-6);  // the fit's own grid, measured by projectPoints
  EXPECT_LT(c.max_px, 1.0);
  EXPECT_GT(c.max_px, 1e-3);  // a fit, not exact
}

TEST(OpenCvCalib, UnsupportedModelsAndFilesAreRefused) {
  Intrinsics in;
  in.width = 640, in.height = 480, in.fu = in.fv = 535, in.cu = 320.5, in.cv = 240.5;
  auto refused = [&](const std::vector<double>& d, const std::string& part) {
    try {
      omma_k_from_opencv(d, in, "camera 5");
      ADD_FAILURE() << "accepted " << d.size() << " coefficients";
    } catch (const OpenCvCalibError& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("camera 5"), std::string::npos) << e.what();
    }
  };
  std::vector<double> d12(12, 0.0);
  d12[8] = 0.001;
  refused(d12, "thin prism");
  std::vector<double> d14(14, 0.0);
  d14[12] = 0.01;
  refused(d14, "tilted");
  refused({0.1, 0.2, 0.3}, "3 distortion coefficients");
  d14[12] = 0;
  EXPECT_TRUE(omma_k_from_opencv(d14, in, "zeros").exact);  // all extra terms zero: exact
  const fs::path dir = fs::temp_directory_path() / fmt::format("omma-opencv-bad-{}", ::getpid());
  fs::create_directories(dir);
  std::ofstream(dir / "skew.yml")
      << "%YAML:1.0\ncamera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n"
         "   data: [ 500., 2., 320., 0., 500., 240., 0., 0., 1. ]\n";
  std::ofstream(dir / "none.yml") << "%YAML:1.0\nfoo: 1\n";
  std::ofstream(dir / "broken.yml") << "%YAML:1.0\ncamera_matrix: [ 1, 2\n";
  for (const auto& [name, part] :
       std::vector<std::pair<std::string, std::string>>{{"skew.yml", "skew"},
                                                        {"none.yml", "no camera matrix"},
                                                        {"broken.yml", "broken.yml"},
                                                        {"missing.yml", "does not exist"}}) {
    try {
      read_opencv_calibration(dir / name);
      ADD_FAILURE() << name << " was accepted";
    } catch (const OpenCvCalibError& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace omma::calib
