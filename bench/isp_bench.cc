// ISP speed (thesis §5.1.2, mission §4): one set = the dome's 24 raw frames of 250x250 (10-bit RGGB).
// Ours: develop() = demosaicing + white balance + 8 MSBs, oneTBB over the 24 frames; the peer:
// OpenCV's cvtColor bilinear Bayer conversion (16-bit in, no white balance) on the same frames,
// also over the frames with oneTBB, in the same run. The target is >= 100 sets/s on 2 cores.
// Also: the plain reference path, and the sensor-link decoder (one 250x250 frame).
#include <filesystem>
#include <vector>

#include <benchmark/benchmark.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <tbb/parallel_for.h>

#include "omma/isp/isp.h"

namespace {

using omma::isp::Awb;
using omma::isp::Demosaic;

// 24 raw frames: 250x250 crops of a real photograph (scaled to 10 bits) when available, else noise.
const std::vector<cv::Mat>& frames() {
  static const std::vector<cv::Mat> f = [] {
    std::vector<cv::Mat> out;
    const cv::Mat photo = cv::imread(std::string(OMMA_DATA_DIR) + "/louvre.jpg", cv::IMREAD_COLOR);
    for (int i = 0; i < 24; ++i) {
      cv::Mat raw;
      if (!photo.empty()) {
        cv::Mat crop16;
        photo(cv::Rect(100 + 160 * i, 700 + 20 * (i % 5), 250, 250)).convertTo(crop16, CV_16UC3, 4.0);
        raw = omma::isp::mosaic_rggb(crop16);
      } else {
        raw.create(250, 250, CV_16UC1);
        cv::RNG(i).fill(raw, cv::RNG::UNIFORM, 0, 1024);
      }
      out.push_back(raw);
    }
    return out;
  }();
  return f;
}

void set_counters(benchmark::State& state) {
  state.counters["sets_per_s"] = benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["Mpix_per_s"] =
      benchmark::Counter(double(state.iterations()) * 24 * 250 * 250 / 1e6, benchmark::Counter::kIsRate);
}

void BM_IspSet(benchmark::State& state) {
  omma::isp::IspOptions o;
  o.demosaic = Demosaic(state.range(0));
  o.awb = Awb(state.range(1));
  const auto& in = frames();
  for (auto _ : state) {
    auto out = omma::isp::develop_all(in, o);
    benchmark::DoNotOptimize(out.data());
  }
  set_counters(state);
  state.SetLabel(omma::isp::demosaic_name(o.demosaic) + "+" + omma::isp::awb_name(o.awb));
}
BENCHMARK(BM_IspSet)
    ->ArgNames({"method", "awb"})
    ->Args({int(Demosaic::kBilinear), int(Awb::kGrayWorld)})
    ->Args({int(Demosaic::kHybrid), int(Awb::kGrayWorld)})
    ->Args({int(Demosaic::kHybrid), int(Awb::kWhitePatch)})
    ->Args({int(Demosaic::kAdamsHamilton), int(Awb::kGrayWorld)})
    ->Args({int(Demosaic::kColourCorrelation), int(Awb::kGrayWorld)})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

void BM_OpenCvBilinearSet(benchmark::State& state) {
  const auto& in = frames();
  std::vector<cv::Mat> out(in.size());
  for (auto _ : state) {
    tbb::parallel_for(size_t(0), in.size(),
                      [&](size_t i) { cv::cvtColor(in[i], out[i], cv::COLOR_BayerBG2BGR); });
    benchmark::DoNotOptimize(out.data());
  }
  set_counters(state);
}
BENCHMARK(BM_OpenCvBilinearSet)->UseRealTime()->Unit(benchmark::kMillisecond);

// One frame on one thread (CPU cost per frame, for the fast path's tuning).
void BM_IspFrame(benchmark::State& state) {
  omma::isp::IspOptions o;
  o.demosaic = Demosaic(state.range(0));
  o.awb = Awb::kGrayWorld;
  const cv::Mat& f = frames()[3];
  for (auto _ : state) benchmark::DoNotOptimize(omma::isp::develop(f, o).data);
  state.SetLabel(omma::isp::demosaic_name(o.demosaic) + "+grayworld");
}
BENCHMARK(BM_IspFrame)->ArgName("method")->DenseRange(0, 3)->Unit(benchmark::kMicrosecond);

void BM_OpenCvBilinearFrame(benchmark::State& state) {
  const cv::Mat& f = frames()[3];
  cv::Mat out;
  for (auto _ : state) {
    cv::cvtColor(f, out, cv::COLOR_BayerBG2BGR);
    benchmark::DoNotOptimize(out.data);
  }
}
BENCHMARK(BM_OpenCvBilinearFrame)->Unit(benchmark::kMicrosecond);

// The plain per-pixel reference (one thread), for scale.
void BM_IspReferenceSet(benchmark::State& state) {
  omma::isp::IspOptions o;
  o.demosaic = Demosaic::kHybrid;
  const auto& in = frames();
  for (auto _ : state)
    for (const auto& f : in) benchmark::DoNotOptimize(omma::isp::develop_reference(f, o).data);
  set_counters(state);
}
BENCHMARK(BM_IspReferenceSet)->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_LinkDecodeFrame(benchmark::State& state) {
  const omma::isp::LinkConfig c;
  const auto stream = omma::isp::encode_link({omma::isp::to_link_frame(frames()[0], 10)}, c);
  for (auto _ : state) {
    const auto st = omma::isp::decode_link(stream.bytes, c, [](const omma::isp::LinkFrame&) {});
    benchmark::DoNotOptimize(st.rows_ok);
  }
  state.counters["frames_per_s"] =
      benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_LinkDecodeFrame)->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
