// CLI tests for `omma hw simulate|sweep|throughput|memory|export|import` (the bit-accurate
// hardware model, src/omma/hw).
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "omma/design/prototype.h"
#include "omma/testing/test_scenes.h"
#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {
namespace fs = std::filesystem;

// DIR with rig.json (the 24-camera prototype) and cam_XX.png of louvre.jpg.
fs::path make_scene(const std::string& tag) {
  const fs::path dir = temp_dir(tag);
  const Rig rig = design::thesis_prototype_rig();
  const cv::Mat tex = testing::photo_texture(data_dir() + "/louvre.jpg", 1440);
  testing::write_frames_folder(dir, rig, testing::render_frames(rig, tex));
  return dir;
}

TEST(HwCli, SimulateMatchesTheFloatStitchAndCountsCycles) {
  const fs::path d = make_scene("hw_sim");
  const RunResult r = run_omma("hw simulate --frames " + d.string() + " --method mrf --size 540x540 --out " +
                               (d / "hw.png").string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = r.json();
  EXPECT_GE(j.at("psnr_vs_float_db").get<double>(), 45.0);
  EXPECT_GE(j.at("cycles_per_pixel").get<double>(), 3.0);
  EXPECT_LE(j.at("cycles_per_pixel").get<double>(), 4.0);
  uint64_t pixels = 0;
  for (const auto& v : j.at("contributors_histogram")) pixels += v.get<uint64_t>();
  EXPECT_EQ(pixels, 540u * 540u);
  EXPECT_GT(j.at("fps_at_clock").get<double>(), 100.0);  // 540^2 pixels at 120 MHz
  EXPECT_TRUE(fs::exists(d / "hw.png"));
  fs::remove_all(d);
}

TEST(HwCli, ThroughputAndMemoryReproduceTheThesis) {
  RunResult r = run_omma("hw throughput --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.json().at("th_sys"), 4);
  EXPECT_NEAR(r.json().at("fps_at_clock").get<double>(), 25.72, 0.005);
  r = run_omma("hw throughput --cameras 20 --search-per-camera --size 1024x1024 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NEAR(r.json().at("fmin_mhz").get<double>(), 524.288, 1e-6);
  r = run_omma("hw memory --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NEAR(r.json().at("total_kbytes").get<double>(), 3415.552, 1e-6);
  EXPECT_NEAR(r.json().at("total_area_mm2").get<double>(), 25.620, 1e-9);
  EXPECT_EQ(r.json().at("pins_initial"), 151);
  EXPECT_EQ(r.json().at("pins_with_io"), 125);
  EXPECT_TRUE(r.json().at("fpga").at("fits").get<bool>());
  r = run_omma("hw memory --cameras 40 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(r.json().at("fpga").at("fits").get<bool>());
}

TEST(HwCli, ExportImportRoundTrip) {
  const fs::path d = temp_dir("hw_export");
  const fs::path rig = d / "rig.json", out = d / "chip", back = d / "back.json";
  RunResult r =
      run_omma("design --method max-volume --aov 64 --r-phys 5 --cam-size 1x1x2 --out " + rig.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_omma("hw export " + rig.string() + " " + out.string() + " --method mrf --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.json().at("words").at("pix_pos"), 24 * 15);
  r = run_omma("hw import " + out.string() + " " + back.string() + " --compare " + rig.string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = r.json();
  for (const char* f : {"axis_deg", "position_mm", "focal_px", "centre_px", "k", "aov_deg"})
    EXPECT_LE(j.at("difference").at(f).get<double>(), j.at("quantisation_bound").at(f).get<double>()) << f;
  // A corrupt word stream: clear error naming the field, exit 1, no rig written.
  std::ofstream(out / "cam_search.hex", std::ios::app) << "01E00000\n";
  r = run_omma("hw import " + out.string() + " " + (d / "bad.json").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("omma: error:"), std::string::npos);
  EXPECT_NE(r.err.find("array select"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(d / "bad.json"));
  fs::remove_all(d);
}

TEST(HwCli, BadWidthsAreRejected) {
  const fs::path d = temp_dir("hw_bad");
  const fs::path rig = d / "rig.json";
  ASSERT_EQ(run_omma("design --method max-volume --aov 64 --r-phys 5 --cam-size 1x1x2 --out " + rig.string())
                .exit_code,
            0);
  RunResult r = run_omma("hw export " + rig.string() + " " + (d / "x").string() + " --set angle_bits=40");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("angle_bits"), std::string::npos) << r.err;
  r = run_omma("hw export " + rig.string() + " " + (d / "x").string() + " --set camera_bits=4");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("camera_bits"), std::string::npos) << r.err;
  r = run_omma("hw export " + rig.string() + " " + (d / "x").string() + " --set frame_addr_bits=12");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("frame_addr_bits"), std::string::npos) << r.err;
  r = run_omma("hw export " + rig.string() + " " + (d / "x").string() +
               " --set sincos_addr_bits=14 --set angle_bits=14");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("angle_bits"), std::string::npos) << r.err;
  r = run_omma("hw simulate --frames " + d.string() + " --method gaussian");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("nn, linear and mrf"), std::string::npos) << r.err;
  fs::remove_all(d);
}

}  // namespace
}  // namespace omma::test
