// Sweeps (Fig. 3.3, 3.7, 3.9) and the SVG writer.
#include "omma/design/count_sweep.h"

#include <cmath>
#include <sstream>

#include <gtest/gtest.h>

#include "omma/design/svg_plot.h"
#include "omma/testing/expect.h"

namespace omma::design {
namespace {

size_t count(const std::string& s, const std::string& what) {
  size_t n = 0;
  for (size_t p = s.find(what); p != std::string::npos; p = s.find(what, p + 1)) ++n;
  return n;
}

TEST(Sweep, SmallSweepTablesAndPlots) {
  CountSweepOptions p;
  p.r_virtual_mm = {12, 30};
  p.aov_min_deg = 56;
  p.aov_max_deg = 72;
  p.aov_step_deg = 8;
  p.ratio_min = 2.2;
  p.ratio_max = 3.8;
  p.ratio_step = 0.8;
  const auto rows = run_sweep(p);
  ASSERT_EQ(rows.size(), 2u * 3 * 3 + 2 * 3);
  for (const SweepRow& r : rows) EXPECT_GT(r.cameras, 0);
  // More cameras for a smaller AOV and for a closer R_vir (per method).
  auto find = [&](const std::string& fig, Method m, double aov, double rv) {
    for (const SweepRow& r : rows)
      if (r.figure == fig && r.method == m && std::abs(r.aov_deg - aov) < 1e-9 &&
          std::abs(r.r_virtual_mm - rv) < 1e-9)
        return r.cameras;
    return -1;
  };
  for (Method m : {Method::kLayered, Method::kCvt, Method::kMinCameras}) {
    EXPECT_GE(find("aov", m, 56, 12), find("aov", m, 72, 12));
    EXPECT_GE(find("aov", m, 64, 12), find("aov", m, 64, 30));
  }
  EXPECT_EQ(find("ratio", Method::kLayered, 64, 15), 29);
  EXPECT_LE(find("ratio", Method::kMinCameras, 64, 15), 25);
  const std::string csv = sweep_csv(rows);
  EXPECT_EQ(count(csv, "\n"), rows.size() + 1);
  EXPECT_EQ(csv.rfind("figure,method,aov_deg,r_virtual_mm,r_virtual_over_r_phys,cameras\n", 0), 0u);
  const std::string svg = sweep_aov_svg(rows, p);
  EXPECT_EQ(svg.rfind("<?xml", 0), 0u);
  EXPECT_EQ(count(svg, "<path"), 2u * 3);  // one line per method and panel
  EXPECT_NE(svg.find("angle of view of each camera (deg)"), std::string::npos);
  EXPECT_NE(svg.find("layered [65]"), std::string::npos);
  EXPECT_NE(svg.find("R_vir = 30 mm"), std::string::npos);
  const std::string ratio = sweep_ratio_svg(rows, p);
  EXPECT_EQ(count(ratio, "<path"), 2u);
  EXPECT_NE(ratio.find("min-cameras"), std::string::npos);
}

TEST(Sweep, UnreachableDistancesAreEmptyCells) {
  CountSweepOptions p;
  p.r_virtual_mm = {6};
  p.aov_min_deg = p.aov_max_deg = 20;  // cones of 20 deg from 5 mm never meet at 6 mm
  p.aov_methods = {Method::kLayered};
  p.ratio_methods = {};
  const auto rows = run_sweep(p);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].cameras, -1);
  EXPECT_NE(sweep_csv(rows).find(",6,1.2,\n"), std::string::npos);
}

TEST(SvgPlot, NiceTicksAndEscaping) {
  EXPECT_EQ(nice_ticks(0, 10, 6), (std::vector<double>{0, 2, 4, 6, 8, 10}));
  const auto t = nice_ticks(1.6, 10, 6);
  EXPECT_LE(t.front(), 1.6);
  EXPECT_GE(t.back(), 10);
  Plot plot{"a < b & c", "x", "y", {{"s", "red", {0, 1, 2}, {1, NAN, 3}, false}}};
  const std::string svg = svg_plot(plot);
  EXPECT_NE(svg.find("a &lt; b &amp; c"), std::string::npos);
  EXPECT_EQ(count(svg, "<circle"), 2u);  // the NaN point is skipped
  EXPECT_EQ(count(svg, " M"), 2u);       // and breaks the line
}

using testing::refusal;

TEST(CountSweep, OptionsRefuseBadValues) {
  CountSweepOptions p;
  EXPECT_TRUE(p.IsValid());
  p.aov_step_deg = 0;  // the range would never end
  std::string why;
  EXPECT_FALSE(p.IsValid(&why));
  EXPECT_NE(why.find("aov_step_deg"), std::string::npos);
  EXPECT_NE(refusal([&] { run_sweep(p); }).find("aov_step_deg"), std::string::npos);
  p = {};
  p.r_phys_mm = -1;
  EXPECT_EQ(refusal([&] { run_sweep(p); }), "sweep: r_phys must be positive");
}

}  // namespace
}  // namespace omma::design
