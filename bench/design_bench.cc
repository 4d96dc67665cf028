// Speed of the design stage: coverage analysis of the 24-camera prototype on a 0.1 deg grid
// (target < 1 s on 2 cores), with the plain reference as the peer, and the whole default sweep
// (target < 60 s). Run: build/omma_design_bench [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include "omma/core/grid.h"
#include "omma/design/count_sweep.h"
#include "omma/design/coverage.h"
#include "omma/design/placement.h"
#include "omma/design/prototype.h"

namespace omma::design {
namespace {

// Counts at 18 mm and R_vir in one pass, 0.1 deg sampling (3601 x 901 directions).
void BM_Coverage24_0p1deg(benchmark::State& state) {
  const Rig rig = thesis_prototype_rig();
  for (auto _ : state) benchmark::DoNotOptimize(analyze_coverage(rig, 18.0, deg2rad(0.1)));
}
BENCHMARK(BM_Coverage24_0p1deg)->Unit(benchmark::kMillisecond)->UseRealTime();

// R_vir alone (closed form, eq. 3.1 per direction), 0.1 deg.
void BM_VirtualRadius24_0p1deg(benchmark::State& state) {
  const Rig rig = thesis_prototype_rig();
  for (auto _ : state) benchmark::DoNotOptimize(virtual_radius(rig, deg2rad(0.1)));
}
BENCHMARK(BM_VirtualRadius24_0p1deg)->Unit(benchmark::kMillisecond)->UseRealTime();

// Peer: the plain reference (bisection on the per-point angle test) on a 1 deg grid only --
// at 0.1 deg it would take minutes.
void BM_VirtualRadiusBisectionReference24_1deg(benchmark::State& state) {
  const Rig rig = thesis_prototype_rig();
  for (auto _ : state) benchmark::DoNotOptimize(virtual_radius_bisection(rig, deg2rad(1.0), 1e-3));
}
BENCHMARK(BM_VirtualRadiusBisectionReference24_1deg)->Unit(benchmark::kMillisecond)->UseRealTime();

// The fast path on the same 1 deg grid, for the comparison with the reference.
void BM_VirtualRadius24_1deg(benchmark::State& state) {
  const Rig rig = thesis_prototype_rig();
  for (auto _ : state) benchmark::DoNotOptimize(virtual_radius(rig, deg2rad(1.0)));
}
BENCHMARK(BM_VirtualRadius24_1deg)->Unit(benchmark::kMillisecond)->UseRealTime();

// The coverage-count map of the demo (equirect 1440 x 360).
void BM_CoverageMap24_1440x360(benchmark::State& state) {
  const Rig rig = thesis_prototype_rig();
  const PanoGrid grid{Projection::kEquirect, 1440, 360};
  for (auto _ : state) benchmark::DoNotOptimize(coverage_count_map(rig, grid, 18.0));
}
BENCHMARK(BM_CoverageMap24_1440x360)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_DesignMinCameras15(benchmark::State& state) {
  DesignParams p;
  p.r_virtual_mm = 15;
  for (auto _ : state) benchmark::DoNotOptimize(design_min_cameras(p));
}
BENCHMARK(BM_DesignMinCameras15)->Unit(benchmark::kMillisecond)->UseRealTime();

// The whole default `omma sweep` (Fig. 3.3/3.9 and Fig. 3.7), without writing files.
void BM_WholeSweep(benchmark::State& state) {
  const CountSweepOptions p;
  for (auto _ : state) benchmark::DoNotOptimize(run_sweep(p));
}
BENCHMARK(BM_WholeSweep)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

}  // namespace
}  // namespace omma::design

BENCHMARK_MAIN();
