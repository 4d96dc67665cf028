// Speed of the reference stitcher (pano/stitch.h) per method, against a peer in the same run:
// cv::remap of one 250x250 camera onto the same output size (a lower bound for any renderer that
// samples each output pixel once). Scene: 15-camera test rig, 250 px cameras, vr180 540x540.
#include <benchmark/benchmark.h>
#include <opencv2/imgproc.hpp>

#include "omma/core/progress.h"
#include "omma/pano/stitch.h"
#include "omma/testing/test_scenes.h"

namespace {
using namespace omma;

struct Fixture {
  Rig rig = testing::small_rig(250);
  std::vector<cv::Mat> frames = testing::render_frames(rig, testing::smooth_texture());
  PanoGrid grid{Projection::kVr180, 540, 540};
};
const Fixture& fixture() {
  static const Fixture f;
  return f;
}

void BM_ReferenceStitch(benchmark::State& state) {
  set_progress_enabled(false);
  const Fixture& f = fixture();
  pano::StitchOptions opt;
  opt.method = pano::all_methods()[state.range(0)];
  opt.grid = f.grid;
  opt.progress = false;
  state.SetLabel(pano::to_string(opt.method));
  for (auto _ : state) benchmark::DoNotOptimize(pano::stitch(f.rig, f.frames, opt));
  state.SetItemsProcessed(state.iterations() * f.grid.width * f.grid.height);
}
BENCHMARK(BM_ReferenceStitch)->DenseRange(0, 5)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_PeerRemapOneCamera(benchmark::State& state) {
  const Fixture& f = fixture();
  cv::Mat mapx(f.grid.height, f.grid.width, CV_32FC1), mapy(f.grid.height, f.grid.width, CV_32FC1);
  cv::randu(mapx, 0, 249);
  cv::randu(mapy, 0, 249);
  cv::Mat out;
  for (auto _ : state) cv::remap(f.frames[0], out, mapx, mapy, cv::INTER_LINEAR);
  state.SetItemsProcessed(state.iterations() * f.grid.width * f.grid.height);
}
BENCHMARK(BM_PeerRemapOneCamera)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
