// Speed of calibration: geometric plus photometric calibration of the 24-camera
// prototype dome from 8 shots of the calibration tube (thesis §3.6), with the parts measured alone
// and a peer in the same run: the same geometric calibration from ONE shot (what the 7 more shots
// cost: the averaging, and a refinement that aligns more patches on cleaner images).
// Frames: the simulator's tube scene, --perturb orient=2,focal=0.03,center=5,k1=0.05, default
// sensor effects. Run: build/omma_calib_bench (each benchmark runs once; minutes on 2 cores).
#include <benchmark/benchmark.h>

#include "omma/calib/calibrate.h"
#include "omma/calib/photometric.h"
#include "omma/core/progress.h"
#include "omma/design/prototype.h"
#include "omma/sim/perturb.h"
#include "omma/sim/simulate.h"

namespace {
using namespace omma;

struct Fixture {
  Rig nominal = design::thesis_prototype_rig();
  Rig true_rig;
  std::vector<std::vector<cv::Mat>> shots, flats;
  Fixture() {
    set_progress_enabled(false);
    sim::SimulateOptions so;
    so.perturb = sim::parse_perturb("orient=2,focal=0.03,center=5,k1=0.05");
    so.truth = false;
    so.progress = false;
    so.shots = 8;
    const auto tube = sim::make_tube_scene();
    const sim::SimulateSummary r = sim::simulate(nominal, *tube, so);
    true_rig = r.true_rig;
    auto images = [](const std::vector<sim::CameraFrame>& fs) {
      std::vector<cv::Mat> out;
      for (const auto& f : fs) out.push_back(f.image);
      return out;
    };
    shots.push_back(images(r.frames));
    for (const auto& s : r.more_shots) shots.push_back(images(s));
    const auto flat = sim::make_flat_scene();
    const sim::SimulateSummary fr = sim::simulate(nominal, *flat, so);
    flats.push_back(images(fr.frames));
    for (const auto& s : fr.more_shots) flats.push_back(images(s));
  }
};
const Fixture& fixture() {
  static const Fixture f;
  return f;
}

calib::CalibrationOptions tube_options() {
  calib::CalibrationOptions o;
  o.tube_diameter_mm = 35;
  o.scene = calib::SceneModel::kNear;
  return o;
}

void BM_GeometricTube8Shots(benchmark::State& state) {
  const Fixture& f = fixture();
  for (auto _ : state)
    benchmark::DoNotOptimize(
        calib::calibrate_rig(f.nominal, calib::average_frame_sets(f.shots), tube_options()));
}
BENCHMARK(BM_GeometricTube8Shots)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

void BM_GeometricTube1ShotPeer(benchmark::State& state) {
  const Fixture& f = fixture();
  for (auto _ : state) benchmark::DoNotOptimize(calib::calibrate_rig(f.nominal, f.shots[0], tube_options()));
}
BENCHMARK(BM_GeometricTube1ShotPeer)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

void BM_AverageShots(benchmark::State& state) {
  const Fixture& f = fixture();
  for (auto _ : state) benchmark::DoNotOptimize(calib::average_frame_sets(f.shots));
}
BENCHMARK(BM_AverageShots)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_PhotometricOverlaps8Shots(benchmark::State& state) {
  const Fixture& f = fixture();
  for (auto _ : state) benchmark::DoNotOptimize(calib::calibrate_photometric(f.true_rig, f.shots));
}
BENCHMARK(BM_PhotometricOverlaps8Shots)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

void BM_PhotometricFlatField8Shots(benchmark::State& state) {
  const Fixture& f = fixture();
  for (auto _ : state) benchmark::DoNotOptimize(calib::calibrate_flat_field(f.true_rig, f.flats));
}
BENCHMARK(BM_PhotometricFlatField8Shots)->Iterations(3)->Unit(benchmark::kMillisecond)->UseRealTime();

// The whole job as `omma calibrate --frames SHOTS --tube 35 --flat FLATS` runs it.
void BM_GeometricPlusPhotometric8Shots(benchmark::State& state) {
  const Fixture& f = fixture();
  for (auto _ : state) {
    const calib::CalibrationSummary g =
        calib::calibrate_rig(f.nominal, calib::average_frame_sets(f.shots), tube_options());
    benchmark::DoNotOptimize(calib::calibrate_flat_field(g.rig, f.flats));
  }
}
BENCHMARK(BM_GeometricPlusPhotometric8Shots)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
