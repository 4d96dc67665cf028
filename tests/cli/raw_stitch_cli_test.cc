// `omma stitch --raw`: the simulator's raw Bayer frames developed by the ISP (isp/isp.h)
// give a panorama close to the one stitched from the simulator's own 8-bit frames.
#include <filesystem>

#include <gtest/gtest.h>

#include "omma/core/rig.h"
#include "omma/testing/test_scenes.h"
#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {
namespace fs = std::filesystem;

TEST(RawStitchCli, IspDevelopedFramesMatchTheRgbPath) {
  const fs::path d = temp_dir("rawstitch");
  save_rig(testing::small_rig(64), d / "rig.json");
  const RunResult sim =
      run_omma("simulate --rig " + (d / "rig.json").string() + " --scene photo:" + data_dir() +
               "/louvre.jpg --raw --color-gain 0 --truth-size 128x128 --out " + (d / "f").string());
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const std::string base = "stitch --rig " + (d / "rig.json").string() + " --frames " + (d / "f").string() +
                           " --method linear --projection vr180 --size 128x128 --out ";
  const RunResult rgb = run_omma(base + (d / "rgb.png").string());
  ASSERT_EQ(rgb.exit_code, 0) << rgb.err;
  const RunResult raw = run_omma(base + (d / "raw.png").string() + " --raw --demosaic cc --awb none");
  ASSERT_EQ(raw.exit_code, 0) << raw.err;
  const double p_rgb = eval_psnr(d / "rgb.png", d / "f" / "truth.png");
  const double p_raw = eval_psnr(d / "raw.png", d / "f" / "truth.png");
  // The simulator's 8-bit frames are the ideal demosaic of the same signal: the ISP path may lose
  // a little to demosaicing, but must stay close (a channel swap or a wrong tone curve costs > 5 dB).
  EXPECT_GT(p_rgb, 24.0);
  EXPECT_GT(p_raw, p_rgb - 2.0) << "rgb " << p_rgb << " raw " << p_raw;
  // Without raw frames, --raw fails with a clear message and writes nothing.
  fs::remove(d / "f" / "cam_00_raw.png");
  const RunResult bad = run_omma(base + (d / "bad.png").string() + " --raw");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("cam_00_raw.png"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(d / "bad.png"));
  fs::remove_all(d);
}

}  // namespace
}  // namespace omma::test
