// Speed of the dome simulator: one 250x250 camera and a truth panorama, per scene (the photo scene
// is the cheap peer: one bilinear lookup per ray; the colon marches a height field).
#include <benchmark/benchmark.h>
#include <opencv2/imgcodecs.hpp>

#include "omma/sim/render.h"

namespace {

omma::RigCamera bench_camera() {
  omma::RigCamera c;
  c.frame =
      omma::frame_looking_at(omma::direction_from_spherical(omma::deg2rad(50), 0.3), -omma::Vec3::UnitZ());
  c.position_mm = 5 * c.frame.t;
  c.in.aov = omma::deg2rad(64);
  c.in.fu = c.in.fv = omma::Intrinsics::focal_for_aov(250, c.in.aov);
  return c;
}

const omma::sim::Scene& scene(int which) {
  static const auto photo = omma::sim::make_scene(std::string("photo:") + OMMA_DATA_DIR + "/louvre.jpg");
  static const auto colon = omma::sim::make_colon_scene();
  return which == 0 ? *photo : *colon;
}

// Arguments: scene (0 photo, 1 colon), supersample N.
void BM_RenderCamera250(benchmark::State& state) {
  const auto& s = scene(static_cast<int>(state.range(0)));
  omma::sim::CameraEffects e;
  e.supersample = static_cast<int>(state.range(1));
  const auto cam = bench_camera();
  for (auto _ : state) benchmark::DoNotOptimize(omma::sim::render_camera(s, cam, {}, e).image.data);
  state.counters["rays/s"] = benchmark::Counter(
      250.0 * 250 * e.supersample * e.supersample * state.iterations(), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_RenderCamera250)
    ->Args({0, 3})
    ->Args({1, 1})
    ->Args({1, 2})
    ->Args({1, 3})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_Truth1080(benchmark::State& state) {
  const auto& s = scene(static_cast<int>(state.range(0)));
  const omma::PanoGrid grid{omma::Projection::kVr180, 1080, 1080};
  for (auto _ : state) benchmark::DoNotOptimize(omma::sim::render_truth(s, grid, {}, 1).data);
}
BENCHMARK(BM_Truth1080)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
