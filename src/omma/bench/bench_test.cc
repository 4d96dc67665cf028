// bench_ratios: the comparisons `omma bench` reports.
#include "omma/bench/bench.h"

#include <gtest/gtest.h>

namespace omma::bench {
namespace {

TEST(EngineBench, RatiosCompareOursWithThePeersOfTheSameSize) {
  const std::vector<BenchEntry> e = {
      {"omma-mrf-1080x1080", 300, {}, {}},     {"omma-mrf-1080x1080-1thread", 160, {}, {}},
      {"opencv-remap-1080x1080", 60, {}, {}},  {"opencv-multiband-1080x1080", 10, {}, {}},
      {"memcpy-bound-1080x1080", 900, {}, {}}, {"omma-nn-1920x512", 500, {}, {}},
      {"opencv-remap-1920x512", 25, {}, {}},   {"memcpy-bound-1920x512", 750, {}, {}}};
  const auto r = bench_ratios(e);
  ASSERT_EQ(r.size(), 2u);  // the -1thread entry and the peers are not compared
  EXPECT_EQ(r[0].name, "omma-mrf-1080x1080");
  EXPECT_DOUBLE_EQ(r[0].vs_remap, 5.0);
  EXPECT_DOUBLE_EQ(r[0].vs_multiband, 30.0);
  EXPECT_DOUBLE_EQ(r[0].bound_over, 3.0);
  const auto j = r[0].to_json();
  EXPECT_FALSE(j["target_400fps_met"].get<bool>());
  EXPECT_FALSE(j["target_10x_opencv_remap_met"].get<bool>());
  EXPECT_FALSE(j["target_within_2x_bound_met"].get<bool>());
  EXPECT_EQ(r[1].name, "omma-nn-1920x512");
  EXPECT_DOUBLE_EQ(r[1].vs_remap, 20.0);
  EXPECT_DOUBLE_EQ(r[1].vs_multiband, 0.0);  // no peer B of that size in this run
  EXPECT_DOUBLE_EQ(r[1].bound_over, 1.5);
  const auto j1 = r[1].to_json();
  EXPECT_TRUE(j1["target_10x_opencv_remap_met"].get<bool>());
  EXPECT_TRUE(j1["target_within_2x_bound_met"].get<bool>());
  EXPECT_FALSE(j1.contains("vs_opencv_multiband"));
  EXPECT_FALSE(j1.contains("target_400fps_met"));
  EXPECT_TRUE(r[0].vs_multiband_rounds.empty());  // no rounds recorded
}

// Per-round ratios: ours / peer of the same round, where both have the same rounds.
TEST(EngineBench, PerRoundRatiosPairTheSameRounds) {
  const std::vector<BenchEntry> e = {{"omma-mrf-1080x1080", 300, {}, {200, 300, 400}},
                                     {"opencv-multiband-1080x1080", 3, {}, {2, 3, 5}},
                                     {"opencv-remap-1080x1080", 30, {}, {20, 30}}};
  const auto r = bench_ratios(e);
  ASSERT_EQ(r.size(), 1u);
  ASSERT_EQ(r[0].vs_multiband_rounds.size(), 3u);
  EXPECT_DOUBLE_EQ(r[0].vs_multiband_rounds[0], 100.0);
  EXPECT_DOUBLE_EQ(r[0].vs_multiband_rounds[1], 100.0);
  EXPECT_DOUBLE_EQ(r[0].vs_multiband_rounds[2], 80.0);
  EXPECT_TRUE(r[0].vs_remap_rounds.empty());  // rounds do not pair up
  EXPECT_EQ(r[0].to_json()["vs_opencv_multiband_rounds"].size(), 3u);
}

// Bad options are refused by name before any workload is set up.
TEST(EngineBench, BadOptionsAreRefused) {
  BenchOptions o;
  o.rounds = 0;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("rounds"), std::string::npos);
  EXPECT_THROW(run_bench_suite(Rig{}, o), std::invalid_argument);
  o.rounds = 1;
  o.min_seconds = -1;
  EXPECT_FALSE(o.IsValid());
}

}  // namespace
}  // namespace omma::bench
