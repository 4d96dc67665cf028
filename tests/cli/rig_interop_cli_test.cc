// CLI tests for `omma rig new | export | import`: a rig from what a user knows (sizes, fields of view,
// OpenCV calibration files), and rigs moving between omma, COLMAP, OpenCV and Hugin.
#include <cmath>
#include <fstream>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "omma/core/rig.h"
#include "omma/design/prototype.h"
#include "omma/testing/real_data.h"
#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {
namespace fs = std::filesystem;

double angle_deg(const Vec3& a, const Vec3& b) { return rad2deg(angle_between(a, b)); }

TEST(RigInterop, StereoRigFromOpenCvSampleThenCheck) {
  const fs::path samples = testing::opencv_samples_dir();
  if (samples.empty() || !fs::exists(samples / "intrinsics.yml"))
    GTEST_SKIP() << "opencv-doc samples not installed";
  const fs::path dir = temp_dir("rig-stereo");
  const std::string file = (samples / "intrinsics.yml").string();
  const RunResult r = run_omma("rig new --stereo " + file + " --size 640x480 --baseline 60 --out " +
                               (dir / "r.json").string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = r.json();
  EXPECT_EQ(j["cameras"], 2);
  EXPECT_EQ(j["name"], "r");
  // Both calibrations fold back before their image corners: said, and each camera gets a valid cone.
  EXPECT_GE(j["warnings"].size(), 2u) << r.out;
  const RunResult check = run_omma("rig check " + (dir / "r.json").string() + " --json");
  ASSERT_EQ(check.exit_code, 0) << check.err;
  EXPECT_EQ(check.json()["valid"], true);
  EXPECT_EQ(check.json()["cameras"], 2);
  const Rig rig = load_rig(dir / "r.json");
  const RigCamera &a = rig.cameras[0], &b = rig.cameras[1];
  EXPECT_NEAR((b.position_mm - a.position_mm).norm(), 60, 1e-9);
  EXPECT_NEAR((b.position_mm - a.position_mm).dot(a.frame.u), 60, 1e-9);  // camera 2 to camera 1's right
  EXPECT_LT((a.position_mm + b.position_mm).norm(), 1e-9);                // centred on the dome
  EXPECT_LT(angle_deg(a.frame.t, Vec3::UnitX()), 1e-9);                   // looking along +x,
  EXPECT_LT(angle_deg(a.frame.v, -Vec3::UnitZ()), 1e-9);                  // image upright
  EXPECT_DOUBLE_EQ(a.in.fu, 5.3480326845051309e+02);
  EXPECT_DOUBLE_EQ(a.in.cu, 3.3568643204394891e+02 + 0.5);
  EXPECT_DOUBLE_EQ(b.in.cv, 2.4205324573376600e+02 + 0.5);
  EXPECT_DOUBLE_EQ(a.in.k[0], 2.9589439552724328e-01);
  EXPECT_DOUBLE_EQ(b.in.k[1], -1.1214173641213163e-01);
  // The same file as an import, and omma's stereo export read back (R, T in mm).
  ASSERT_EQ(
      run_omma("rig export " + (dir / "r.json").string() + " --opencv " + (dir / "r.yml").string()).exit_code,
      0);
  const RunResult back = run_omma("rig import " + (dir / "r.yml").string() + " --out " +
                                  (dir / "back.json").string() + " --json");
  ASSERT_EQ(back.exit_code, 0) << back.err;
  EXPECT_EQ(back.json()["opencv_layout"], "stereo");
  const Rig rb = load_rig(dir / "back.json");
  for (int i = 0; i < 2; ++i) {
    EXPECT_LT((rb.cameras[i].position_mm - rig.cameras[i].position_mm).norm(), 1e-9);
    EXPECT_LT(angle_deg(rb.cameras[i].frame.t, rig.cameras[i].frame.t), 1e-9);
    EXPECT_EQ(rb.cameras[i].in.k, rig.cameras[i].in.k);
  }
  fs::remove_all(dir);
}

TEST(RigInterop, NewFromSpecsAndImages) {
  const fs::path dir = temp_dir("rig-new");
  cv::imwrite((dir / "a.png").string(), cv::Mat(300, 400, CV_8UC3, cv::Scalar(9, 9, 9)));
  const RunResult r = run_omma(
      "rig new --camera size=640x480,fov=60 --camera "
      "focal=535,530,center=200,150.5,ypr=-90,0,180,pos=0,60,0,id=7 "
      "--images " +
      (dir / "a.png").string() + " " + (dir / "a.png").string() + " --name pair --out " +
      (dir / "pair.json").string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.json()["name"], "pair");
  const Rig rig = load_rig(dir / "pair.json");
  ASSERT_EQ(rig.cameras.size(), 2u);
  const RigCamera &a = rig.cameras[0], &b = rig.cameras[1];
  EXPECT_EQ(a.in.width, 640);                               // size= wins over --images
  EXPECT_NEAR(a.in.fu, 320 / std::tan(deg2rad(30)), 1e-9);  // fov is horizontal
  EXPECT_EQ(a.in.cu, 320);
  EXPECT_EQ(a.in.field, Intrinsics::Field::kImage);
  EXPECT_NEAR(rad2deg(a.in.aov), 2 * rad2deg(std::atan(400 / a.in.fu)), 1e-9);  // to the image corners
  EXPECT_EQ(b.id, 7);
  EXPECT_EQ(b.in.width, 400);  // from the image
  EXPECT_EQ(b.in.fv, 530);
  EXPECT_EQ(b.in.cv, 150.5);
  EXPECT_LT(angle_deg(b.frame.t, Vec3::UnitY()), 1e-9);  // yaw -90 deg: eq. 3.13's yaw turns +x to -y
  EXPECT_LT(angle_deg(b.frame.v, -Vec3::UnitZ()), 1e-9);
  EXPECT_LT((b.position_mm - Vec3(0, 60, 0)).norm(), 1e-12);
  EXPECT_NEAR(rig.dome.radius_mm, 60, 1e-12);
  fs::remove_all(dir);
}

TEST(RigInterop, BadSpecsExitOneNamingTheField) {
  const fs::path dir = temp_dir("rig-bad");
  const std::string out = " --out " + (dir / "x.json").string();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"--camera size=640x480,fov=200", "fov"},
      {"--camera size=640x480,fov=abc", "fov"},
      {"--camera size=640,fov=60", "size"},
      {"--camera fov=60", "size"},
      {"--camera size=640x480", "fov"},
      {"--camera size=640x480,fov=60,focal=500", "fov"},
      {"--camera size=640x480,fov=60,zoom=2", "zoom"},
      {"--camera size=640x480,focal=-3", "focal"},
      {"--camera size=640x480,fov=60,ypr=1,2", "ypr"},
      {"--camera size=640x480,fov=60,pos=1,2,x", "pos"},
      {"--camera size=640x480,fov=60,dist=0.1", "dist"},
      {"--camera opencv=" + (dir / "missing.yml").string(), "missing.yml"},
      {"--camera size=640x480,fov=60 --stereo x.yml", "not both"},
      {"", "--camera"},
      {"--camera size=640x480,fov=60 --images a.png b.png", "--images"},
  };
  for (const auto& [args, part] : cases) expect_error(run_omma("rig new " + args + out), part, args);
  const fs::path samples = testing::opencv_samples_dir();
  if (!samples.empty() && fs::exists(samples / "intrinsics.yml")) {
    const std::string st = " --stereo " + (samples / "intrinsics.yml").string();
    expect_error(run_omma("rig new" + st + " --baseline 60" + out), "image size", "stereo without a size");
    expect_error(run_omma("rig new" + st + " --size 640x480" + out), "--baseline",
                 "stereo without R, T or baseline");
    expect_error(run_omma("rig new" + st + " --size 640x480 --baseline -2" + out), "--baseline",
                 "negative baseline");
    expect_error(run_omma("rig new --camera opencv=" + (samples / "intrinsics.yml").string() + ":3" + out),
                 "2 camera", "camera 3 of a stereo file");
  }
  EXPECT_FALSE(fs::exists(dir / "x.json"));
  expect_error(run_omma("rig export thesis-24"), "nothing to export", "export without a target");
  expect_error(run_omma("rig import " + (dir / "nothing.txt").string() + out), "not a COLMAP",
               "unknown format");
  expect_error(run_omma("rig import " + dir.string() + out), "no COLMAP text model", "empty folder");
  fs::remove_all(dir);
}

TEST(RigInterop, ExportImportColmapPtoOpenCv) {
  const fs::path dir = temp_dir("rig-interop");
  const std::string d = dir.string();
  const RunResult ex = run_omma("rig export thesis-24 --colmap " + d + "/colmap --pto " + d +
                                "/rig.pto --opencv " + d + "/rig.yml --json");
  ASSERT_EQ(ex.exit_code, 0) << ex.err;
  EXPECT_EQ(ex.json()["colmap_models"]["PINHOLE"], 24);
  for (const char* f :
       {"colmap/cameras.txt", "colmap/images.txt", "colmap/points3D.txt", "rig.pto", "rig.yml"})
    EXPECT_TRUE(fs::exists(dir / f)) << f;
  const Rig truth = design::load_rig_or_builtin("thesis-24");
  for (const std::string in : {"colmap", "rig.pto", "rig.yml"}) {
    const RunResult im = run_omma("rig import " + d + "/" + in + " --out " + d + "/back.json --json");
    ASSERT_EQ(im.exit_code, 0) << in << ": " << im.err;
    const Rig rig = load_rig(dir / "back.json");
    ASSERT_EQ(rig.cameras.size(), 24u) << in;
    double worst = 0;
    for (size_t i = 0; i < 24; ++i) {
      EXPECT_EQ(rig.cameras[i].id, truth.cameras[i].id);
      worst = std::max({worst, angle_deg(rig.cameras[i].frame.t, truth.cameras[i].frame.t),
                        angle_deg(rig.cameras[i].frame.u, truth.cameras[i].frame.u)});
    }
    EXPECT_LT(worst, 1e-6) << in;
  }
  // COLMAP's own sparse layout (sparse/0) and a foreign name scheme, at 1000 mm per unit.
  fs::create_directories(dir / "proj" / "sparse" / "0");
  std::ofstream(dir / "proj" / "sparse" / "0" / "cameras.txt") << "1 PINHOLE 640 480 500 500 320 240\n";
  std::ofstream(dir / "proj" / "sparse" / "0" / "images.txt")
      << "1 1 0 0 0 0 0 0 1 left.jpg\n\n2 1 0 0 0 -0.06 0 0 1 right.jpg\n\n";
  const RunResult sfm = run_omma("rig import " + d + "/proj --scale 1000 --out " + d + "/sfm.json --json");
  ASSERT_EQ(sfm.exit_code, 0) << sfm.err;
  const auto j = sfm.json();
  EXPECT_EQ(j["ids_from_names"], false);
  EXPECT_EQ(j["images"][1]["name"], "right.jpg");
  EXPECT_EQ(j["images"][1]["id"], 1);
  EXPECT_EQ(j["name"], "proj");
  const Rig sfm_rig = load_rig(dir / "sfm.json");
  EXPECT_NEAR((sfm_rig.cameras[1].position_mm - sfm_rig.cameras[0].position_mm).norm(), 60, 1e-9);
  expect_error(run_omma("rig import " + d + "/proj --scale 0 --out " + d + "/x.json"), "--scale",
               "zero scale");
  expect_error(run_omma("rig import " + d + "/rig.pto --size 640x480 --out " + d + "/x.json"), "--size",
               "size for a PTO");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace omma::test
