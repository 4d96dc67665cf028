// Band-by-band panoramas (pano_render.h) on the Giga-Eye rig at a simulation size.
#include "omma/engine/pano_render.h"

#include <filesystem>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "omma/design/prototype.h"
#include "omma/engine/synthetic.h"
#include "omma/engine/tiff_writer.h"

namespace omma::engine {
namespace {

namespace fs = std::filesystem;

// engine::random_frames (synthetic.h): random-texture frames, cameras disagree entirely, the
// hardest case for a blend, so any difference in taps shows.

TEST(PanoRender, BandsGiveTheSamePanoramaAsOneMap) {
  const Rig rig = *design::builtin_rig("gigaeye-44-skip5");  // 432 x 324 per camera
  const auto frames = random_frames(rig, 3);
  for (pano::Method m : {pano::Method::kNearest, pano::Method::kMrf, pano::Method::kSad}) {
    PanoRenderOptions o;
    o.grid = PanoGrid{Projection::kEquirect100, 720, 200};
    o.method = m;
    o.cache_dir.clear();
    o.progress = false;
    o.band_rows = 200;  // one band: one map of the whole grid
    PanoRenderer whole(rig, o);
    whole.set_frames(frames);
    const cv::Mat a = whole.render_image();
    o.band_rows = 48;  // 5 bands, not a multiple of the tile height
    PanoRenderer banded(rig, o);
    EXPECT_EQ(banded.bands(), 5);
    banded.set_frames(frames);
    const cv::Mat b = banded.render_image();
    EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0) << pano::to_string(m);
    // Everything inside polar 0..100 deg is seen by some camera: no black output pixel.
    cv::Mat gray;
    cv::cvtColor(b, gray, cv::COLOR_BGR2GRAY);
    EXPECT_LT(cv::countNonZero(gray == 0), b.total() / 200) << pano::to_string(m);
  }
}

TEST(PanoRender, OfflineBlendMatchesTheEngineAndTiffHoldsIt) {
  const Rig rig = *design::builtin_rig("gigaeye-44-skip5");
  const auto frames = random_frames(rig, 5);
  PanoRenderOptions o;
  o.grid = PanoGrid{Projection::kEquirect100, 360, 100};
  o.method = pano::Method::kLinear;
  o.cache_dir.clear();
  o.progress = false;
  o.band_rows = 40;
  PanoRenderer engine(rig, o);
  engine.set_frames(frames);
  const cv::Mat fast = engine.render_image();
  o.offline = true;
  PanoRenderer hq(rig, o);
  hq.set_frames(frames);
  const fs::path dir = fs::temp_directory_path() / "omma_pano_render_test";
  fs::create_directories(dir);
  render_to_file(hq, dir / "hq.tif");
  const cv::Mat back = read_tiff_rows(dir / "hq.tif");
  ASSERT_EQ(back.size(), fast.size());
  // 8-bit fixed-point taps (1/128) against the double-precision blend: within 1-2 levels.
  EXPECT_GT(psnr_u8(back, fast), 45.0);
  EXPECT_EQ(tiff_size(dir / "hq.tif"), cv::Size(360, 100));
  EXPECT_EQ(cv::norm(read_tiff_rows(dir / "hq.tif", 37, 20), back.rowRange(37, 57), cv::NORM_INF), 0);
  EXPECT_GT(hq.memory().store_bytes, size_t(44) * 432 * 324 * 6);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace omma::engine
