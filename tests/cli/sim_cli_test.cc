// CLI tests of `omma simulate`.
#include <cmath>
#include <fstream>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "omma/core/frames.h"
#include "omma/core/rig.h"
#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {

// A small 3-camera rig written to `path`.
void write_small_rig(const std::filesystem::path& path) {
  Rig rig;
  rig.name = "cli-3";
  for (int i = 0; i < 3; ++i) {
    RigCamera c;
    c.id = i;
    const Vec3 t = i == 0 ? Vec3::UnitZ() : direction_from_spherical(deg2rad(50), i * kPi);
    c.frame = frame_looking_at(t, -Vec3::UnitZ());
    c.position_mm = 5 * t;
    c.in.width = 64;
    c.in.height = 48;
    c.in.fu = c.in.fv = 60;
    c.in.cu = 32;
    c.in.cv = 24;
    rig.cameras.push_back(c);
  }
  save_rig(rig, path);
}

TEST(SimCli, PhotoSceneWritesTheFramesFolder) {
  const auto dir = temp_dir("simcli");
  write_small_rig(dir / "rig.json");
  const auto out = dir / "frames";
  const RunResult r = run_omma("simulate --rig " + (dir / "rig.json").string() +
                               " --scene photo:" + data_dir() + "/lake.jpg --out " + out.string() +
                               " --truth-size 200x100 --projection equirect --raw --seed 3 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = r.json();
  EXPECT_EQ(j["cameras"], 3);
  EXPECT_EQ(j["truth"]["width"], 200);
  EXPECT_GT(j["ms"].get<double>(), 0.0);
  const Rig rig = load_rig(out / "rig.json");
  const auto frames = load_frames(out, rig);
  const auto raws = load_raw_frames(out, rig);
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_EQ(frames[0].cols, 64);
  EXPECT_EQ(frames[0].rows, 48);
  double maxv = 0;
  cv::minMaxLoc(raws[1], nullptr, &maxv);
  EXPECT_LE(maxv, 1023.0);  // 10-bit values in 16-bit PNGs
  EXPECT_GT(maxv, 100.0);
  const cv::Mat truth = cv::imread((out / "truth.png").string());
  EXPECT_EQ(truth.cols, 200);
  EXPECT_EQ(truth.rows, 100);
  // Without --perturb the true rig is the nominal one.
  const Rig true_rig = load_rig(out / "rig_true.json");
  EXPECT_NEAR((true_rig.cameras[2].frame.t - rig.cameras[2].frame.t).norm(), 0.0, 1e-9);
  std::filesystem::remove_all(dir);
}

TEST(SimCli, PerturbWritesTheTrueRig) {
  const auto dir = temp_dir("simcli_perturb");
  write_small_rig(dir / "rig.json");
  const auto out = dir / "frames";
  const RunResult r =
      run_omma("simulate --rig " + (dir / "rig.json").string() + " --scene checker:60 --out " + out.string() +
               " --truth-size 64x64 --perturb orient=2,focal=0.05 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Rig nominal = load_rig(out / "rig.json"), truth = load_rig(out / "rig_true.json");
  for (size_t i = 0; i < nominal.cameras.size(); ++i) {
    const Mat3 rel =
        truth.cameras[i].frame.dome_to_camera() * nominal.cameras[i].frame.dome_to_camera().transpose();
    EXPECT_NEAR(rad2deg(std::acos(std::clamp((rel.trace() - 1) / 2, -1.0, 1.0))), 2.0,
                1e-3);  // file precision
    EXPECT_NEAR(std::abs(truth.cameras[i].in.fu / nominal.cameras[i].in.fu - 1), 0.05, 1e-6);
  }
  std::filesystem::remove_all(dir);
}

TEST(SimCli, BadInputGivesClearErrorsAndNoOutput) {
  const auto dir = temp_dir("simcli_bad");
  write_small_rig(dir / "rig.json");
  const std::string rig = " --rig " + (dir / "rig.json").string();
  const auto out = dir / "frames";
  const std::string o = " --out " + out.string();
  struct Case {
    std::string args, message;
  } cases[] = {
      {rig + " --scene sky" + o, "unknown scene"},
      {rig + " --scene photo:/no/such/photo.jpg" + o, "does not exist"},
      {rig + " --scene colon --truth-size 100" + o, "WxH"},
      {rig + " --scene colon --truth-size 0x10" + o, "out of range"},
      {rig + " --scene colon --projection fisheye" + o, "unknown projection"},
      {rig + " --scene colon --perturb tilt=3" + o, "perturb"},
      {rig + " --scene colon --perturb orient=abc" + o, "not a number"},
      {" --rig " + (dir / "none.json").string() + " --scene colon" + o, "does not exist"},
      {rig + " --scene colon --supersample 0" + o, "supersample"},
  };
  for (const auto& c : cases) {
    const RunResult r = run_omma("simulate" + c.args);
    EXPECT_EQ(r.exit_code, 1) << c.args;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_FALSE(std::filesystem::exists(out)) << c.args;
  }
  // An empty rig.
  std::ofstream(dir / "empty.json")
      << R"({"format": "omma-rig", "version": 1, "dome": {"radius_mm": 5}, "cameras": []})";
  const RunResult e = run_omma("simulate --rig " + (dir / "empty.json").string() + " --scene colon" + o);
  EXPECT_EQ(e.exit_code, 1);
  EXPECT_NE(e.err.find("camera"), std::string::npos) << e.err;
  EXPECT_FALSE(std::filesystem::exists(out));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace omma::test
