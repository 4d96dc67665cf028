// Engine benchmarks: map compile time, our renderer against OpenCV
// cv::remap (peer A), cv::detail::MultiBandBlender (peer B) and the memcpy bandwidth bound, on the
// thesis prototype rig with random-texture frames, at 1080x1080 vr180 and 1920x512 equirect.
// `omma bench --json` runs the same workloads (omma/bench/bench.h) and prints fps.
#include <map>
#include <memory>

#include <benchmark/benchmark.h>

#include "omma/bench/bench.h"
#include "omma/design/prototype.h"
#include "omma/testing/synthetic.h"

namespace {
using namespace omma;
using namespace omma::render;
using namespace omma::bench;
using omma::testing::random_frames;

const Rig& rig() {
  static const Rig r = design::thesis_prototype_rig();
  return r;
}
const std::vector<cv::Mat>& frames() {
  static const auto f = random_frames(rig(), 42);
  return f;
}
PanoGrid grid(int g) {
  return g == 0 ? PanoGrid{Projection::kVr180, 1080, 1080} : PanoGrid{Projection::kEquirect, 1920, 512};
}
const pano::Method kMethods[] = {pano::Method::kNearest, pano::Method::kLinear, pano::Method::kMrf};

void run_workload(benchmark::State& state, const Workload& w) {
  for (auto _ : state) w.run();
  state.counters["fps"] = benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
}

void BM_Compile(benchmark::State& state) {
  MapOptions opt;
  opt.grid = grid(int(state.range(1)));
  opt.method = kMethods[state.range(0)];
  double bpp = 0;
  for (auto _ : state) bpp = compile_map(rig(), opt).bytes_per_pixel();
  state.counters["bytes_per_pixel"] = bpp;
  state.SetLabel(pano::to_string(opt.method) + " " + to_string(opt.grid.projection));
}
BENCHMARK(BM_Compile)->ArgsProduct({{0, 1, 2}, {0, 1}})->Unit(benchmark::kMillisecond)->Iterations(2);

void BM_Render(benchmark::State& state) {
  MapOptions opt;
  opt.grid = grid(int(state.range(2)));
  opt.method = kMethods[state.range(0)];
  const auto w = omma_workload(rig(), opt, int(state.range(1)), frames());
  state.SetLabel(w.name + (state.range(1) == 1 ? " 1 thread" : " all threads"));
  run_workload(state, w);
}
BENCHMARK(BM_Render)->ArgsProduct({{0, 1, 2}, {1, 0}, {0, 1}})->Unit(benchmark::kMillisecond)->MinTime(0.5);

// Diagnostic: the mrf map at 1080x1080 on one thread with each kernel this CPU runs, with and
// without the prefetch of the next tile's camera pixels: separates the kernels' arithmetic from the
// cost of gathering camera pixels from the frame store.
void BM_RenderKernel(benchmark::State& state) {
  const Kernel k = static_cast<Kernel>(state.range(0));
  if (!kernel_available(k)) {
    state.SkipWithError("kernel not available on this CPU");
    return;
  }
  MapOptions opt;
  opt.grid = grid(0);
  opt.method = pano::Method::kMrf;
  const CompiledMap map = compile_map(rig(), opt);
  FrameStore store(map.layout);
  for (size_t c = 0; c < frames().size(); ++c) store.set(int(c), frames()[c]);
  cv::Mat out;
  const RenderOptions ro{.threads = 1, .kernel = k, .prefetch = state.range(1) != 0};
  for (auto _ : state) render::render(map, store, out, ro);
  state.SetLabel(to_string(k) + (ro.prefetch ? " prefetch" : " no prefetch"));
  state.counters["fps"] = benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_RenderKernel)
    ->ArgsProduct({{int(Kernel::kScalar), int(Kernel::kAvx2), int(Kernel::kAvx512Vnni)}, {1, 0}})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(0.5);

// Storing a frame into the row-pair store (per camera frame; the live engine does it for every
// new frame of every camera).
void BM_FrameStoreSet(benchmark::State& state) {
  FrameStore store(render::StoreLayout::for_rig(rig()));
  int c = 0;
  for (auto _ : state) {
    store.set(c, frames()[c]);
    c = (c + 1) % int(frames().size());
  }
  state.counters["frames_per_s"] =
      benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_FrameStoreSet)->Unit(benchmark::kMicrosecond);

void BM_OpenCvRemap(benchmark::State& state) {
  const auto w = opencv_remap_workload(rig(), grid(int(state.range(0))), frames());
  state.SetLabel(w.name);
  run_workload(state, w);
}
BENCHMARK(BM_OpenCvRemap)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->MinTime(0.5);

void BM_OpenCvMultiBand(benchmark::State& state) {
  const auto w = opencv_multiband_workload(rig(), grid(int(state.range(0))), frames());
  state.SetLabel(w.name);
  run_workload(state, w);
}
BENCHMARK(BM_OpenCvMultiBand)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(3);

void BM_MemcpyBound(benchmark::State& state) {
  MapOptions opt;
  opt.grid = grid(int(state.range(0)));
  opt.method = pano::Method::kMrf;
  const CompiledMap map = compile_map(rig(), opt);
  const auto w = memcpy_workload(map, std::to_string(opt.grid.width) + "x" + std::to_string(opt.grid.height));
  state.SetLabel(w.name);
  run_workload(state, w);
}
BENCHMARK(BM_MemcpyBound)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->MinTime(0.5);

}  // namespace

BENCHMARK_MAIN();
