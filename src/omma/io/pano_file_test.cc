// Panoramas written to files band by band (pano_file.h): the offline blend into a BigTIFF.
#include "omma/io/pano_file.h"

#include <filesystem>

#include <gtest/gtest.h>

#include "omma/design/prototype.h"
#include "omma/io/tiff_writer.h"
#include "omma/render/render.h"
#include "omma/testing/synthetic.h"

namespace omma::io {
namespace {

namespace fs = std::filesystem;

TEST(PanoFile, OfflineBlendMatchesTheEngineAndBigTiffHoldsIt) {
  const Rig rig = *design::builtin_rig("gigaeye-44-skip5");
  const auto frames = testing::random_frames(rig, 5);
  render::PanoRenderOptions o;
  o.grid = PanoGrid{Projection::kEquirect100, 360, 100};
  o.method = pano::Method::kLinear;
  o.cache_dir.clear();
  o.progress = false;
  o.band_rows = 40;
  render::PanoRenderer engine(rig, o);
  engine.set_frames(frames);
  const cv::Mat fast = engine.render_image();
  o.offline = true;
  render::PanoRenderer hq(rig, o);
  hq.set_frames(frames);
  const fs::path dir = fs::temp_directory_path() / "omma_pano_render_test";
  fs::create_directories(dir);
  render_to_file(hq, dir / "hq.tif");
  const cv::Mat back = read_tiff_rows(dir / "hq.tif");
  ASSERT_EQ(back.size(), fast.size());
  // 8-bit fixed-point taps (1/128) against the double-precision blend: within 1-2 levels.
  EXPECT_GT(render::psnr_u8(back, fast), 45.0);
  EXPECT_EQ(tiff_size(dir / "hq.tif"), cv::Size(360, 100));
  EXPECT_EQ(cv::norm(read_tiff_rows(dir / "hq.tif", 37, 20), back.rowRange(37, 57), cv::NORM_INF), 0);
  EXPECT_GT(hq.memory().store_bytes, size_t(44) * 432 * 324 * 6);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace omma::io
