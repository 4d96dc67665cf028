// Compiled maps and the fast renderer against the reference.
#include "omma/render/render.h"

#include <filesystem>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "omma/core/frames.h"
#include "omma/design/prototype.h"
#include "omma/pano/stitch.h"
#include "omma/render/compiled_map.h"
#include "omma/sim/panorama_views.h"
#include "omma/testing/synthetic.h"

namespace omma::render {
namespace {

// Camera views of the Louvre photograph, downsampled to about the cameras' resolution first
// (250 px / 64 deg ~ 3.9 px/deg) so that the frames are not aliased.
std::vector<cv::Mat> louvre_frames(const Rig& rig) {
  static const cv::Mat pano = [] {
    cv::Mat p = cv::imread(std::string(OMMA_DATA_DIR) + "/louvre.jpg", cv::IMREAD_COLOR);
    EXPECT_FALSE(p.empty());
    cv::resize(p, p, cv::Size(1440, 720), 0, 0, cv::INTER_AREA);
    return p;
  }();
  return sim::views_of_panorama(rig, pano, 0.3);
}

FrameStore store_of(const CompiledMap& map, const std::vector<cv::Mat>& frames) {
  FrameStore store(map.layout);
  for (size_t c = 0; c < frames.size(); ++c) store.set(int(c), frames[c]);
  return store;
}

// Methods pano implements so far: static_taps throws std::logic_error for the others.
bool implemented(const Rig& rig, pano::Method m) {
  try {
    pano::static_taps(rig, PanoGrid{}, 540, 540, m);
    return true;
  } catch (const std::logic_error&) {
    return false;
  }
}

TEST(EngineRender, MatchesReferenceForEveryStaticMethodAtLeast50dB) {
  const Rig rig = testing::test_rig_24();
  const auto frames = louvre_frames(rig);
  int tested = 0;
  for (pano::Method m : pano::all_methods()) {
    if (!implemented(rig, m)) continue;
    for (Projection p : {Projection::kVr180, Projection::kEquirect}) {
      MapOptions opt;
      opt.grid = PanoGrid{p, p == Projection::kVr180 ? 270 : 480, p == Projection::kVr180 ? 270 : 128};
      opt.method = m;
      const CompiledMap map = compile_map(rig, opt);
      const FrameStore store = store_of(map, frames);
      cv::Mat fast;
      render(map, store, fast);
      const cv::Mat ref = reference_render(rig, opt, frames);
      const double db = psnr_u8(fast, ref);
      SCOPED_TRACE(pano::to_string(m) + " " + to_string(p));
      EXPECT_GE(db, 50.0);
      // Every output pixel is covered by this rig, so the panorama is not black anywhere.
      cv::Mat gray;
      cv::cvtColor(fast, gray, cv::COLOR_BGR2GRAY);
      EXPECT_GT(cv::mean(gray)[0], 40.0);
      RecordProperty(pano::to_string(m) + "_" + to_string(p) + "_psnr_db", std::to_string(db));
      std::printf("  %s %s: PSNR fast vs reference %.2f dB, %.2f bytes/pixel, %.2f taps/pixel\n",
                  pano::to_string(m).c_str(), to_string(p).c_str(), db, map.bytes_per_pixel(),
                  double(map.taps()) / (map.width * map.height));
      ++tested;
    }
  }
  EXPECT_EQ(tested, 12);  // all six methods, two projections
}

// Against pano's reference stitcher itself (pano/stitch.h), on the thesis prototype rig.
TEST(EngineRender, MatchesPanoStitchOnThePrototypeRigAtLeast50dB) {
  const Rig rig = design::thesis_prototype_rig();
  cv::Mat photo = cv::imread(std::string(OMMA_DATA_DIR) + "/lake.jpg", cv::IMREAD_COLOR);
  cv::resize(photo, photo, cv::Size(1440, 720), 0, 0, cv::INTER_AREA);
  const auto frames = sim::views_of_panorama(rig, photo, 1.0);
  for (pano::Method m : pano::all_methods()) {
    MapOptions opt;
    opt.grid = PanoGrid{Projection::kVr180, 180, 180};
    opt.method = m;
    const CompiledMap map = compile_map(rig, opt);
    cv::Mat fast;
    render(map, store_of(map, frames), fast);
    pano::StitchOptions so;
    so.method = m;
    so.grid = opt.grid;
    so.progress = false;
    const cv::Mat ref = to_u8(pano::stitch(rig, frames, so));
    const double db = psnr_u8(fast, ref);
    std::printf("  %s vs pano::stitch: %.2f dB\n", pano::to_string(m).c_str(), db);
    EXPECT_GE(db, 50.0) << pano::to_string(m);
  }
}

TEST(EngineRender, SimdKernelsAreBitIdenticalToScalarKernelAndThreadCountDoesNotMatter) {
  const Rig rig = testing::test_rig_24();
  std::printf("  kernels here: best %s\n", to_string(best_kernel()).c_str());
  // 200 x 200: tiles cut at the right and bottom edges (64 x 32 tiles).
  for (pano::Method m : {pano::Method::kNearest, pano::Method::kLinear, pano::Method::kMrf}) {
    MapOptions opt;
    opt.grid = PanoGrid{Projection::kVr180, 200, 200};
    opt.method = m;
    const CompiledMap map = compile_map(rig, opt);
    const FrameStore store = store_of(map, testing::random_frames(rig, 7));
    cv::Mat scalar, threaded;
    render(map, store, scalar, {.threads = 1, .kernel = Kernel::kScalar});
    render(map, store, threaded, {.threads = 2});
    EXPECT_EQ(cv::norm(scalar, threaded, cv::NORM_INF), 0.0) << pano::to_string(m);
    for (Kernel k : {Kernel::kAvx2, Kernel::kAvx512Vnni}) {
      if (!kernel_available(k)) continue;
      cv::Mat simd;
      render(map, store, simd, {.threads = 1, .kernel = k});
      EXPECT_EQ(cv::norm(scalar, simd, cv::NORM_INF), 0.0) << pano::to_string(m) << " " << to_string(k);
    }
  }
}

// The scalar kernel is the definition of the map's arithmetic: (sum of w * v + 64) >> 7 over the
// four neighbours of every tap, checked here against that formula written out from visit().
TEST(EngineRender, ScalarKernelComputesTheMapsFormula) {
  const Rig rig = testing::test_rig_24();
  MapOptions opt;
  opt.grid = PanoGrid{Projection::kEquirect, 150, 40};
  opt.method = pano::Method::kGaussian;
  const CompiledMap map = compile_map(rig, opt);
  const auto frames = testing::random_frames(rig, 9);
  const FrameStore store = store_of(map, frames);
  cv::Mat fast;
  render(map, store, fast, {.threads = 1, .kernel = Kernel::kScalar});
  cv::Mat expect(map.height, map.width, CV_8UC3, cv::Scalar::all(0));
  const StoreLayout& L = map.layout;
  map.visit([&](int col, int row, int n, const MapTap* taps) {
    int acc[3] = {64, 64, 64};
    for (int t = 0; t < n; ++t) {
      const int c = L.camera_at(taps[t].offset);
      const size_t rel = taps[t].offset - L.offset(c, 0, 0);
      const int y = int(rel / L.stride_bytes()), x = int(rel % L.stride_bytes()) / 6;
      const cv::Mat& f = frames[c];
      auto at = [&](int xi, int yi, int ch) {
        return int(f.at<cv::Vec3b>(std::min(yi, f.rows - 1), std::min(xi, f.cols - 1))[ch]);
      };
      for (int ch = 0; ch < 3; ++ch)
        acc[ch] += taps[t].w[0] * at(x, y, ch) + taps[t].w[1] * at(x, y + 1, ch) +
                   (taps[t].w[2] ? taps[t].w[2] * at(x + 1, y, ch) : 0) +
                   (taps[t].w[3] ? taps[t].w[3] * at(x + 1, y + 1, ch) : 0);
    }
    for (int ch = 0; ch < 3; ++ch) expect.at<cv::Vec3b>(row, col)[ch] = n ? uint8_t(acc[ch] >> 7) : 0;
  });
  EXPECT_EQ(cv::norm(fast, expect, cv::NORM_INF), 0.0);
}

TEST(EngineMap, WeightsSumTo128AndBytesPerPixelIsCompact) {
  const Rig rig = testing::test_rig_24();
  for (pano::Method m : {pano::Method::kNearest, pano::Method::kLinear}) {
    MapOptions opt;
    opt.grid = PanoGrid{Projection::kVr180, 216, 216};
    opt.method = m;
    const CompiledMap map = compile_map(rig, opt);
    ASSERT_TRUE(map.IsValid());
    size_t k = 0, pixels = 0;
    map.visit([&](int, int, int n, const MapTap* taps) {
      int sum = 0;
      for (int t = 0; t < n; ++t) {
        sum += taps[t].weight();
        ASSERT_GT(taps[t].weight(), 0);
        ASSERT_LE(taps[t].offset + 16, map.layout.bytes());
      }
      ASSERT_TRUE(n == 0 || sum == 128) << "pixel " << pixels;
      k += n;
      ++pixels;
    });
    EXPECT_EQ(pixels, size_t(map.width) * map.height);
    EXPECT_EQ(k, map.taps());
    if (m == pano::Method::kNearest) {
      EXPECT_EQ(map.taps(), pixels);  // one tap per pixel
    }
    // 6 bytes per tap (int16 offset delta + 4 weight bytes), 2 per run, 4 per run and tap for the
    // run's start offsets, 4 per prefetched line, 16 per tile.
    EXPECT_EQ(map.bytes(), 6 * map.taps() + map.runs.size() + 4 * map.base.size() + 4 * map.lines.size() +
                               16 * (size_t(map.tiles()) + 1));
  }
}

// The memory aim, at its scale (the thesis prototype rig, 1080x1080): at most 12 bytes per
// output pixel for mrf (nn: 6 bytes per tap and little else). The runs and prefetch lists cost
// more per pixel on coarse grids, where neighbouring output pixels are further apart in the cameras.
TEST(EngineMap, BytesPerPixelAt1080x1080) {
  const Rig rig = design::thesis_prototype_rig();
  for (pano::Method m : {pano::Method::kNearest, pano::Method::kMrf}) {
    MapOptions opt;
    opt.grid = PanoGrid{Projection::kVr180, 1080, 1080};
    opt.method = m;
    const CompiledMap map = compile_map(rig, opt);
    const double px = double(map.width) * map.height;
    std::printf("  %s 1080x1080: %.3f taps/pixel, %.2f bytes/pixel\n", pano::to_string(m).c_str(),
                map.taps() / px, map.bytes_per_pixel());
    EXPECT_LE(map.bytes_per_pixel(), m == pano::Method::kNearest ? 6.5 : 12.0);
  }
}

// MapOptions::min_weight: the faint mrf taps go, the rest still sum to 128, the map shrinks by a
// fifth or more (12 bytes per pixel at 1080x1080: EngineMap.BytesPerPixelAt1080x1080) and the
// output stays within 50 dB of the all-taps reference, on the thesis prototype rig.
TEST(EngineMap, MinWeightDropsFaintTapsWithinTheReferencePsnr) {
  const Rig rig = design::thesis_prototype_rig();
  MapOptions all;
  all.grid = PanoGrid{Projection::kVr180, 270, 270};
  all.method = pano::Method::kMrf;
  all.min_weight = 0;
  MapOptions pruned = all;
  pruned.min_weight = MapOptions{}.min_weight;  // the default
  const CompiledMap a = compile_map(rig, all), p = compile_map(rig, pruned);
  const double px = double(p.width) * p.height;
  std::printf("  mrf taps per pixel: all %.3f, min_weight %.4f %.3f; bytes per pixel %.2f -> %.2f\n",
              a.taps() / px, pruned.min_weight, p.taps() / px, a.bytes_per_pixel(), p.bytes_per_pixel());
  EXPECT_LT(double(p.taps()), 0.8 * double(a.taps()));
  EXPECT_LT(p.bytes_per_pixel(), 0.8 * a.bytes_per_pixel());
  int faint = 0;
  const int faint_below = int(128 * pruned.min_weight);  // in 1/128
  p.visit([&](int col, int row, int n, const MapTap* taps) {
    int sum = 0;
    for (int t = 0; t < n; ++t) {
      sum += taps[t].weight();
      faint += taps[t].weight() < faint_below;  // renormalising only raises the kept weights
    }
    ASSERT_TRUE(n == 0 || sum == 128) << "pixel " << col << "," << row;
  });
  EXPECT_EQ(faint, 0);
  EXPECT_NE(map_key(rig, all), map_key(rig, pruned));
  for (const auto& frames : {testing::random_frames(rig, 3), louvre_frames(rig)}) {
    cv::Mat fast;
    render(p, store_of(p, frames), fast);
    const double db = psnr_u8(fast, reference_render(rig, all, frames));
    std::printf("  min_weight %.4f vs the all-taps reference: %.2f dB\n", pruned.min_weight, db);
    EXPECT_GE(db, 50.0);
  }
}

TEST(EngineMap, CacheRoundTripIsExactAndKeyedByOptions) {
  const Rig rig = testing::test_rig_24();
  MapOptions opt;
  opt.grid = PanoGrid{Projection::kEquirect, 240, 60};
  const auto dir = std::filesystem::temp_directory_path() / "omma_engine_map_cache_test";
  std::filesystem::remove_all(dir);
  const MapLoad first = compile_map_cached(rig, opt, dir);
  EXPECT_FALSE(first.from_cache);
  const MapLoad second = compile_map_cached(rig, opt, dir);
  EXPECT_TRUE(second.from_cache);
  EXPECT_EQ(first.map.runs, second.map.runs);
  EXPECT_EQ(first.map.base, second.map.base);
  EXPECT_EQ(first.map.delta, second.map.delta);
  EXPECT_EQ(first.map.weight, second.map.weight);
  EXPECT_EQ(first.map.lines, second.map.lines);
  EXPECT_EQ(first.map.tile_tap, second.map.tile_tap);
  MapOptions other = opt;
  other.method = pano::Method::kNearest;
  EXPECT_NE(map_key(rig, opt), map_key(rig, other));
  Rig moved = rig;
  moved.cameras[3].position_mm.x() += 0.01;
  EXPECT_NE(map_key(rig, opt), map_key(moved, opt));
  // A truncated cache file is not trusted: it is recompiled.
  std::filesystem::resize_file(first.file, std::filesystem::file_size(first.file) / 2);
  EXPECT_FALSE(load_map(first.file, rig, opt).has_value());
  EXPECT_FALSE(compile_map_cached(rig, opt, dir).from_cache);
  std::filesystem::remove_all(dir);
}

TEST(EngineMap, DroppedCameraIsFilledFromNeighbours) {
  const Rig rig = testing::test_rig_24();
  const auto frames = louvre_frames(rig);
  MapOptions opt;
  opt.grid = PanoGrid{Projection::kVr180, 240, 240};
  opt.method = pano::Method::kNearest;
  opt.active.assign(rig.cameras.size(), true);
  opt.active[5] = false;
  const CompiledMap map = compile_map(rig, opt);
  map.visit([&](int, int, int n, const MapTap* taps) {
    for (int t = 0; t < n; ++t) ASSERT_NE(map.layout.camera_at(taps[t].offset), 5);
  });
  cv::Mat fast;
  render(map, store_of(map, frames), fast);
  cv::Mat gray;
  cv::cvtColor(fast, gray, cv::COLOR_BGR2GRAY);
  EXPECT_EQ(cv::countNonZero(gray == 0), 0);  // no hole where camera 5 was
  EXPECT_GE(psnr_u8(fast, reference_render(rig, opt, frames)), 50.0);
}

TEST(EngineRender, BadOptionsAreRefused) {
  const Rig rig = testing::test_rig_24(32, 32);
  MapOptions mo;
  mo.grid = PanoGrid{Projection::kVr180, 64, 64};
  const CompiledMap map = compile_map(rig, mo);
  FrameStore store(map.layout);
  cv::Mat out;
  RenderOptions ro;
  ro.threads = -1;
  std::string why;
  EXPECT_FALSE(ro.IsValid(&why));
  EXPECT_NE(why.find("threads"), std::string::npos);
  EXPECT_THROW(render(map, store, out, ro), std::invalid_argument);
  ro.threads = 1;
  EXPECT_TRUE(ro.IsValid());
  EXPECT_NO_THROW(render(map, store, out, ro));
}

}  // namespace
}  // namespace omma::render
