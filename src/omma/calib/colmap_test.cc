// COLMAP text models: omma's export round-trips exactly, COLMAP itself reads it (model_converter to
// binary and back) with the same numbers, and the camera COLMAP holds projects like omma's.
#include "omma/calib/colmap.h"

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <regex>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>

#include "omma/calib/opencv_calib.h"
#include "omma/calib/pto.h"
#include "omma/core/io.h"
#include "omma/design/prototype.h"

namespace omma::calib {
namespace {
namespace fs = std::filesystem;

// thesis-24 with distortion on some cameras: FULL_OPENCV (k5), OPENCV (k1..k4), PINHOLE (none).
Rig distorted_thesis_rig() {
  Rig rig = design::load_rig_or_builtin("thesis-24");
  for (size_t i = 0; i < rig.cameras.size(); i += 3) {
    Intrinsics& in = rig.cameras[i].in;
    in.k = {-0.08 + 0.002 * i, 0.01, 0.0004 * (i % 2 ? 1 : -1), -0.0003, i % 2 ? 0.0 : 0.003};
    in.fv = in.fu * 1.01;
    in.cu += 0.75;
  }
  rig.cameras[4].position_mm += Vec3(0.1, -0.2, 0.05);
  rig.validate();
  return rig;
}

fs::path temp_dir(const std::string& tag) {
  const fs::path d = fs::temp_directory_path() / fmt::format("omma-colmap-{}-{}", tag, ::getpid());
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::string strip_omma(const std::string& text) {
  return std::regex_replace(text, std::regex("# omma-rig [^\n]*\n"), "");
}

double angle_deg(const Vec3& a, const Vec3& b) { return rad2deg(angle_between(a, b)); }

TEST(Colmap, RoundTripIsExact) {
  const Rig rig = distorted_thesis_rig();
  const ColmapText t = colmap_text(rig);
  EXPECT_NE(t.cameras.find(" FULL_OPENCV "), std::string::npos);
  EXPECT_NE(t.cameras.find(" OPENCV "), std::string::npos);
  EXPECT_NE(t.cameras.find(" PINHOLE "), std::string::npos);
  const ColmapImportSummary s = import_colmap_text(t.cameras, t.images, {}, "folder");
  EXPECT_TRUE(s.omma_metadata);
  EXPECT_TRUE(s.ids_from_names);
  EXPECT_EQ(s.max_fit_px, 0);
  EXPECT_EQ(s.rig.name, rig.name);
  EXPECT_EQ(s.rig.dome.radius_mm, rig.dome.radius_mm);
  EXPECT_EQ(s.rig.dome.sphere, rig.dome.sphere);
  ASSERT_EQ(s.rig.cameras.size(), rig.cameras.size());
  double worst = 0;
  for (size_t i = 0; i < rig.cameras.size(); ++i) {
    const RigCamera &a = rig.cameras[i], &b = s.rig.cameras[i];
    EXPECT_EQ(a.id, b.id);
    worst = std::max({worst, (a.frame.t - b.frame.t).norm(), (a.frame.u - b.frame.u).norm(),
                      (a.frame.v - b.frame.v).norm(), (a.position_mm - b.position_mm).norm()});
    EXPECT_EQ(a.in.width, b.in.width);
    EXPECT_EQ(a.in.height, b.in.height);
    for (const auto& [x, y] :
         {std::pair{a.in.fu, b.in.fu}, {a.in.fv, b.in.fv}, {a.in.cu, b.in.cu}, {a.in.cv, b.in.cv}})
      EXPECT_EQ(x, y);
    for (int j = 0; j < 5; ++j) EXPECT_EQ(a.in.k[j], b.in.k[j]) << i << " k" << j + 1;
    EXPECT_EQ(a.in.field, b.in.field);
    EXPECT_EQ(a.in.aov, b.in.aov);
  }
  std::printf("rig -> COLMAP text -> rig: largest frame / position difference %.3g\n", worst);
  EXPECT_LT(worst, 1e-9);  // measured 4e-16
}

TEST(Colmap, WithoutOmmaCommentsCamerasSeeTheirImagesAroundTheCentroid) {
  const Rig rig = distorted_thesis_rig();
  const ColmapText t = colmap_text(rig);
  ColmapImportOptions opt;
  opt.scale_mm = 2;  // 2 mm per COLMAP unit
  const ColmapImportSummary s = import_colmap_text(strip_omma(t.cameras), t.images, opt, "my_dome");
  EXPECT_FALSE(s.omma_metadata);
  EXPECT_EQ(s.rig.name, "my_dome");
  Vec3 centroid = Vec3::Zero();
  for (const auto& c : rig.cameras) centroid += c.position_mm;
  centroid /= rig.cameras.size();
  double radius = 0;
  for (size_t i = 0; i < rig.cameras.size(); ++i) {
    const RigCamera &a = rig.cameras[i], &b = s.rig.cameras[i];
    EXPECT_LT((a.frame.t - b.frame.t).norm(), 1e-12);
    EXPECT_LT((2 * (a.position_mm - centroid) - b.position_mm).norm(), 1e-9);
    radius = std::max(radius, 2 * (a.position_mm - centroid).norm());
    EXPECT_EQ(b.in.field, Intrinsics::Field::kImage);
    EXPECT_NEAR(b.in.aov, b.in.bounding_aov(), 1e-12);
  }
  EXPECT_NEAR(s.rig.dome.radius_mm, radius, 1e-9);
  EXPECT_TRUE(s.rig.dome.sphere);  // the 75 deg layer's images reach below the horizon
}

// COLMAP's own reader and writer: text -> binary -> text keeps every number our export wrote.
TEST(Colmap, ColmapReadsOurExport) {
  if (std::system("command -v colmap >/dev/null 2>&1") != 0) GTEST_SKIP() << "colmap not installed";
  const Rig rig = distorted_thesis_rig();
  const fs::path dir = temp_dir("peer");
  export_colmap(rig, dir / "txt");
  fs::create_directories(dir / "bin");
  fs::create_directories(dir / "back");
  const std::string env = "QT_QPA_PLATFORM=offscreen ";
  const std::string to_bin = env + "colmap model_converter --input_path " + (dir / "txt").string() +
                             " --output_path " + (dir / "bin").string() + " --output_type BIN > " +
                             (dir / "log").string() + " 2>&1";
  const std::string to_txt = env + "colmap model_converter --input_path " + (dir / "bin").string() +
                             " --output_path " + (dir / "back").string() + " --output_type TXT >> " +
                             (dir / "log").string() + " 2>&1";
  ASSERT_EQ(std::system(to_bin.c_str()), 0) << read_text_file(dir / "log");
  ASSERT_TRUE(fs::exists(dir / "bin" / "cameras.bin"));
  ASSERT_EQ(std::system(to_txt.c_str()), 0) << read_text_file(dir / "log");
  const std::string cams = read_text_file(dir / "back" / "cameras.txt");
  EXPECT_EQ(cams.find("omma-rig"), std::string::npos);  // COLMAP drops our comment
  ColmapImportOptions keep;
  keep.keep_origin = true;
  const ColmapImportSummary s = import_colmap(dir / "back", keep);
  ASSERT_EQ(s.rig.cameras.size(), rig.cameras.size());
  EXPECT_TRUE(s.ids_from_names);
  double frame_err = 0, pos_err = 0, intr_err = 0, proj_err = 0;
  int projected = 0;
  for (size_t i = 0; i < rig.cameras.size(); ++i) {
    const RigCamera &a = rig.cameras[i], &b = s.rig.cameras[i];
    EXPECT_EQ(a.id, b.id);
    frame_err = std::max({frame_err, (a.frame.t - b.frame.t).norm(), (a.frame.u - b.frame.u).norm()});
    pos_err = std::max(pos_err, (a.position_mm - b.position_mm).norm());
    for (const auto& [x, y] :
         {std::pair{a.in.fu, b.in.fu}, {a.in.fv, b.in.fv}, {a.in.cu, b.in.cu}, {a.in.cv, b.in.cv}})
      intr_err = std::max(intr_err, std::abs(x - y));
    for (int j = 0; j < 5; ++j) intr_err = std::max(intr_err, std::abs(a.in.k[j] - b.in.k[j]));
  }
  // The camera as COLMAP wrote it (its model's parameters, pose R, T), projected by OpenCV (the same
  // formula as COLMAP's OPENCV / FULL_OPENCV) vs omma's projection of the original rig.
  std::ifstream cin_(dir / "back" / "cameras.txt"), iin(dir / "back" / "images.txt");
  std::map<int, std::vector<double>> params;
  std::map<int, std::string> model;
  std::string line;
  while (std::getline(cin_, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    int id, w, h;
    std::string m;
    ls >> id >> m >> w >> h;
    model[id] = m;
    double v;
    while (ls >> v) params[id].push_back(v);
  }
  while (std::getline(iin, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    int image_id, camera_id;
    double qw, qx, qy, qz, tx, ty, tz;
    std::string name;
    ls >> image_id >> qw >> qx >> qy >> qz >> tx >> ty >> tz >> camera_id >> name;
    std::getline(iin, line);  // points
    const RigCamera& a = rig.cameras[image_id - 1];
    ASSERT_EQ(name, fmt::format("cam_{:02d}.png", a.id));
    const std::vector<double>& p = params[camera_id];
    const cv::Matx33d K(p[0], 0, p[2] - 0.5, 0, p[1], p[3] - 0.5, 0, 0,
                        1);  // COLMAP (0.5) -> OpenCV (0) centres
    std::vector<double> D = {0, 0, 0, 0, 0};
    if (model[camera_id] != "PINHOLE")
      D = {p[4], p[5], p[6], p[7], model[camera_id] == "FULL_OPENCV" ? p[8] : 0.0};
    const Mat3 R = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
    cv::Matx33d Rcv;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) Rcv(r, c) = R(r, c);
    cv::Vec3d rvec;
    cv::Rodrigues(Rcv, rvec);
    // World points 20 mm .. 2 m away in directions inside the camera's image.
    std::vector<cv::Point3d> X;
    std::vector<Vec2> ours;
    const CameraModel cam = a.model();
    for (int j = 0; j <= 8; ++j)
      for (int k = 0; k <= 8; ++k) {
        const Vec2 px(a.in.width * (0.02 + 0.96 * k / 8.0), a.in.height * (0.02 + 0.96 * j / 8.0));
        const Vec3 w = cam.unproject(px);
        const Vec3 P = a.position_mm + (20 + 25 * (j + k)) * w;
        const auto q = cam.project(P - a.position_mm);
        if (!q) continue;
        X.emplace_back(P.x(), P.y(), P.z());
        ours.push_back(*q);
      }
    std::vector<cv::Point2d> theirs;
    cv::projectPoints(X, rvec, cv::Vec3d(tx, ty, tz), K, D, theirs);
    for (size_t j = 0; j < X.size(); ++j) {
      proj_err = std::max(proj_err,
                          std::hypot(ours[j].x() - (theirs[j].x + 0.5), ours[j].y() - (theirs[j].y + 0.5)));
      ++projected;
    }
  }
  std::printf(
      "COLMAP model_converter TXT -> BIN -> TXT: frame %.3g, position %.3g mm, intrinsics %.3g; %d points "
      "projected, max |omma - COLMAP's camera (projectPoints)| = %.3g px\n",
      frame_err, pos_err, intr_err, projected, proj_err);
  EXPECT_LT(frame_err, 1e-9);  // measured 3e-16 (COLMAP writes 17 digits)
  EXPECT_LT(pos_err, 1e-9);
  EXPECT_LT(intr_err, 1e-9);
  EXPECT_EQ(projected, int(rig.cameras.size()) * 81);
  EXPECT_LT(proj_err, 1e-6);  // measured 1e-10 px
  fs::remove_all(dir);
}

TEST(Colmap, PtoToRigToColmapKeepsDirections) {
  Rig rig = design::load_rig_or_builtin("thesis-24");
  for (auto& c : rig.cameras) c.in.k[0] = -0.05;  // k1: PTO's exact case
  const PtoExportSummary pto = export_pto(rig);
  const PtoImportSummary from_pto = import_pto(pto.text);
  const ColmapText t = colmap_text(from_pto.rig);
  for (const bool comment : {true, false}) {
    const ColmapImportSummary s =
        import_colmap_text(comment ? t.cameras : strip_omma(t.cameras), t.images, {}, "pto");
    ASSERT_EQ(s.rig.cameras.size(), rig.cameras.size());
    double worst = 0;
    for (size_t i = 0; i < rig.cameras.size(); ++i) {
      const RigCamera &a = from_pto.rig.cameras[i], &b = s.rig.cameras[i];
      EXPECT_EQ(a.id, b.id);
      worst = std::max({worst, angle_deg(a.frame.t, b.frame.t), angle_deg(a.frame.u, b.frame.u),
                        angle_deg(a.frame.v, b.frame.v)});
      // And against the rig the PTO was made from (the PTO's %.17g text, its exact k1 mapping).
      worst = std::max(worst, angle_deg(rig.cameras[i].frame.t, b.frame.t));
      EXPECT_NEAR(a.in.k[0], b.in.k[0], 1e-12);
    }
    std::printf("rig -> PTO -> rig -> COLMAP -> rig (%s comment): largest direction change %.3g deg\n",
                comment ? "with" : "without", worst);
    EXPECT_LT(worst, 1e-6);
  }
}

TEST(Colmap, ModelsConvertExactlyOrAreFittedOrRefused) {
  auto camera = [](const std::string& model, std::vector<double> p) {
    ColmapCamera c;
    c.id = 7;
    c.model = model;
    c.width = 640;
    c.height = 480;
    c.params = std::move(p);
    return c;
  };
  Intrinsics in = intrinsics_from_colmap(camera("SIMPLE_PINHOLE", {500, 320, 240}), "c");
  EXPECT_EQ(in.fu, 500);
  EXPECT_EQ(in.fv, 500);
  EXPECT_EQ(in.cu, 320);  // no shift: COLMAP's centres are at +0.5 like omma's
  in = intrinsics_from_colmap(camera("SIMPLE_RADIAL", {500, 320, 240, -0.1}), "c");
  EXPECT_EQ(in.k[0], -0.1);
  in = intrinsics_from_colmap(camera("RADIAL", {500, 320, 240, -0.1, 0.02}), "c");
  EXPECT_EQ(in.k[1], 0.02);
  in = intrinsics_from_colmap(camera("OPENCV", {500, 510, 320, 240, -0.1, 0.02, 0.001, -0.002}), "c");
  EXPECT_EQ(in.fv, 510);
  EXPECT_EQ(in.k[2], -0.002);  // p2
  EXPECT_EQ(in.k[3], 0.001);   // p1
  // FULL_OPENCV with k4 != 0: fitted, residual reported.
  double fit = 0;
  std::vector<std::string> notes;
  in = intrinsics_from_colmap(camera("FULL_OPENCV", {500, 500, 320, 240, -0.1, 0.02, 0, 0, 0, 0.2, 0, 0}),
                              "image 3", &fit, &notes);
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("image 3"), std::string::npos);
  std::printf("FULL_OPENCV k4 = 0.2: %s\n", notes[0].c_str());
  EXPECT_GT(fit, 1e-3);
  EXPECT_LT(fit, 1.0);
  for (const char* m : {"OPENCV_FISHEYE", "FOV", "RADIAL_FISHEYE", "THIN_PRISM_FISHEYE"}) {
    try {
      intrinsics_from_colmap(camera(m, {500, 500, 320, 240, 0.1, 0, 0, 0}), "image 9 'x.jpg' (camera 7)");
      ADD_FAILURE() << m << " accepted";
    } catch (const ColmapError& e) {
      EXPECT_NE(std::string(e.what()).find(m), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("camera 7"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(intrinsics_from_colmap(camera("PINHOLE", {500, 320, 240}), "c"),
               ColmapError);  // 3 of 4 params
}

TEST(Colmap, ForeignModelsImagesAndFolders) {
  const fs::path dir = temp_dir("foreign");
  // A model as COLMAP writes one: shared camera, photo names, sparse/0 folder, arbitrary scale.
  fs::create_directories(dir / "proj" / "sparse" / "0");
  std::ofstream(dir / "proj" / "sparse" / "0" / "cameras.txt")
      << "# Camera list\n1 SIMPLE_RADIAL 640 480 520 320 240 -0.05\n";
  std::ofstream(dir / "proj" / "sparse" / "0" / "images.txt")
      << "# Image list\n"
      << "5 1 0 0 0 0 0 0 1 IMG_0005.JPG\n100 200 -1 300 400 -1\n"
      << "2 0.9238795325112867 0 0.3826834323650898 0 -0.1 0 0 1 IMG_0002.JPG\n\n";
  std::ofstream(dir / "proj" / "sparse" / "0" / "points3D.txt") << "";
  ColmapImportOptions opt;
  opt.scale_mm = 10;
  const ColmapImportSummary s = import_colmap(dir / "proj", opt);
  EXPECT_EQ(s.rig.name, "proj");
  EXPECT_FALSE(s.ids_from_names);
  ASSERT_EQ(s.images.size(), 2u);
  EXPECT_EQ(s.images[0], (std::pair<std::string, int>("IMG_0002.JPG", 0)));  // IMAGE_ID order
  EXPECT_EQ(s.images[1], (std::pair<std::string, int>("IMG_0005.JPG", 1)));
  // Image 2 is turned 45 deg about the camera's y (down) axis: it looks along +x+z of COLMAP's world.
  EXPECT_LT(angle_deg(s.rig.cameras[0].frame.t, Vec3(-1, 0, 1)), 1e-9);
  const double baseline = (s.rig.cameras[0].position_mm - s.rig.cameras[1].position_mm).norm();
  EXPECT_NEAR(baseline, 1.0, 1e-12);  // 0.1 COLMAP units x 10 mm
  EXPECT_NEAR(s.rig.dome.radius_mm, 0.5, 1e-12);
  // A binary model names the conversion; a folder without a model says so.
  fs::create_directories(dir / "bin" / "0");
  std::ofstream(dir / "bin" / "0" / "cameras.bin") << "x";
  for (const auto& [p, part] :
       std::vector<std::pair<fs::path, std::string>>{{dir / "bin", "model_converter"},
                                                     {dir / "empty", "does not exist"},
                                                     {dir, "no COLMAP text model"}}) {
    try {
      import_colmap(p);
      ADD_FAILURE() << p;
    } catch (const ColmapError& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
  }
  // Malformed lines name the file and line.
  try {
    import_colmap_text("1 PINHOLE 640 480 500 500 320\n", "", {}, "x");
    ADD_FAILURE();
  } catch (const ColmapError& e) {
    EXPECT_NE(std::string(e.what()).find("images.txt"), std::string::npos) << e.what();
  }
  try {
    import_colmap_text("1 PINHOLE 640 480 500 500 320 abc\n", "1 1 0 0 0 0 0 0 1 a.png\n\n", {}, "x");
    ADD_FAILURE();
  } catch (const ColmapError& e) {
    EXPECT_NE(std::string(e.what()).find("cameras.txt line 1"), std::string::npos) << e.what();
  }
  try {
    import_colmap_text("1 PINHOLE 640 480 500 500 320 240\n", "1 1 0 0 0 0 0 0 2 a.png\n\n", {}, "x");
    ADD_FAILURE();
  } catch (const ColmapError& e) {
    EXPECT_NE(std::string(e.what()).find("camera 2"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace omma::calib
