// Band-by-band panoramas (pano_render.h) on the Giga-Eye rig at a simulation size.
#include "omma/render/pano_render.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "omma/design/prototype.h"
#include "omma/testing/synthetic.h"

namespace omma::render {
namespace {

// testing::random_frames (synthetic.h): random-texture frames, cameras disagree entirely, the
// hardest case for a blend, so any difference in taps shows.

TEST(PanoRender, BandsGiveTheSamePanoramaAsOneMap) {
  const Rig rig = *design::builtin_rig("gigaeye-44-skip5");  // 432 x 324 per camera
  const auto frames = testing::random_frames(rig, 3);
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

}  // namespace
}  // namespace omma::render
