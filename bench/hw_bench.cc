// Speed of the bit-accurate hardware model (src/omma/hw): the 24-camera prototype rendered to a
// 1080 x 1080 vr180 panorama (target: < 2 s on the 2-core machine), against a peer in the
// same run: the float reference stitcher (pano::stitch) on the same frames and grid.
#include <benchmark/benchmark.h>

#include "omma/core/frames.h"
#include "omma/core/progress.h"
#include "omma/design/prototype.h"
#include "omma/hw/pipeline.h"
#include "omma/pano/stitch.h"
#include "omma/testing/test_scenes.h"

namespace {
using namespace omma;

const pano::Method kMethods[3] = {pano::Method::kNearest, pano::Method::kLinear, pano::Method::kMrf};

struct Fixture {
  Rig rig = design::thesis_prototype_rig();
  std::vector<cv::Mat> frames;
  PanoGrid grid{Projection::kVr180, 1080, 1080};
  Fixture() {
    const cv::Mat tex = testing::photo_texture(std::string(OMMA_DATA_DIR) + "/louvre.jpg", 1440);
    frames = testing::render_frames_u8(rig, tex);
  }
};
const Fixture& fixture() {
  static const Fixture f;
  return f;
}

void BM_HwModel1080(benchmark::State& state) {
  set_progress_enabled(false);
  const Fixture& f = fixture();
  hw::Pipeline p(hw::HwConfig{}, f.rig, f.grid);
  p.load_frames(f.frames);
  const pano::Method m = kMethods[state.range(0)];
  state.SetLabel(pano::to_string(m));
  for (auto _ : state) benchmark::DoNotOptimize(p.render(m, false));
  state.SetItemsProcessed(state.iterations() * f.grid.width * f.grid.height);
}
BENCHMARK(BM_HwModel1080)->DenseRange(0, 2)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

void BM_PeerFloatStitch1080(benchmark::State& state) {
  set_progress_enabled(false);
  const Fixture& f = fixture();
  pano::StitchOptions opt;
  opt.method = kMethods[state.range(0)];
  opt.grid = f.grid;
  opt.progress = false;
  state.SetLabel(pano::to_string(opt.method));
  for (auto _ : state) benchmark::DoNotOptimize(pano::stitch(f.rig, f.frames, opt));
  state.SetItemsProcessed(state.iterations() * f.grid.width * f.grid.height);
}
BENCHMARK(BM_PeerFloatStitch1080)
    ->DenseRange(0, 2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);

}  // namespace

BENCHMARK_MAIN();
