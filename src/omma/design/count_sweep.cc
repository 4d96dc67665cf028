#include "omma/design/count_sweep.h"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "omma/core/progress.h"
#include "omma/core/valid.h"
#include "omma/design/svg_plot.h"

namespace omma::design {

bool CountSweepOptions::IsValid(std::string* why) const {
  if (!(r_phys_mm > 0)) return invalid(why, "r_phys must be positive");
  for (double rv : r_virtual_mm)
    if (!(rv > 0) || !std::isfinite(rv))
      return invalid(why, fmt::format("R_vir {} mm must be a positive number", rv));
  // The ranges are walked from min to max in steps: a step <= 0 would never end.
  if (!(aov_min_deg > 0 && aov_max_deg >= aov_min_deg && aov_max_deg < 360 && aov_step_deg > 0))
    return invalid(why,
                   "angle of view range: need 0 < aov_min_deg <= aov_max_deg < 360 and aov_step_deg > 0");
  if (!(fixed_aov_deg > 0 && fixed_aov_deg < 360)) return invalid(why, "fixed_aov_deg must be in (0, 360)");
  if (!(ratio_min > 0 && ratio_max >= ratio_min && ratio_step > 0))
    return invalid(why, "ratio range: need 0 < ratio_min <= ratio_max and ratio_step > 0");
  if (!(check_step_deg > 0)) return invalid(why, "check_step_deg must be positive");
  return true;
}

namespace {

std::vector<double> range(double lo, double hi, double step) {
  if (!(step > 0) || !(hi >= lo)) throw std::invalid_argument("sweep: bad range or step");
  std::vector<double> v;
  const int n = static_cast<int>(std::floor((hi - lo) / step + 1e-9));
  for (int i = 0; i <= n; ++i) v.push_back(lo + i * step);
  return v;
}

std::string method_color(Method m) {
  switch (m) {
    case Method::kLayered:
      return "#1f5fd6";  // the earlier method, blue as in Fig. 3.7
    case Method::kMinCameras:
      return "#d62728";  // the proposed method, red as in Fig. 3.7
    case Method::kCvt:
      return "#2ca02c";
    case Method::kMaxVolume:
      return "#9467bd";
  }
  return "black";
}

std::string method_label(Method m) {
  switch (m) {
    case Method::kLayered:
      return "layered [65]";
    case Method::kMinCameras:
      return "min-cameras";
    case Method::kCvt:
      return "CVT";
    case Method::kMaxVolume:
      return "max-volume";
  }
  return "?";
}

}  // namespace

std::vector<SweepRow> run_sweep(const CountSweepOptions& p) {
  std::string why;
  if (!p.IsValid(&why)) throw std::invalid_argument("sweep: " + why);
  std::vector<SweepRow> rows;
  for (double rv : p.r_virtual_mm)
    for (Method m : p.aov_methods)
      for (double aov : range(p.aov_min_deg, p.aov_max_deg, p.aov_step_deg))
        rows.push_back({"aov", m, aov, rv, rv / p.r_phys_mm, -1});
  for (Method m : p.ratio_methods)
    for (double ratio : range(p.ratio_min, p.ratio_max, p.ratio_step))
      rows.push_back({"ratio", m, p.fixed_aov_deg, ratio * p.r_phys_mm, ratio, -1});
  Progress progress("sweep", rows.size(), progress_enabled());
  tbb::parallel_for(size_t{0}, rows.size(), [&](size_t i) {
    SweepRow& r = rows[i];
    DesignParams d;
    d.aov_rad = deg2rad(r.aov_deg);
    d.r_phys_mm = p.r_phys_mm;
    d.r_virtual_mm = r.r_virtual_mm;
    d.check_step_rad = deg2rad(p.check_step_deg);
    try {
      r.cameras = cameras_needed(r.method, d);
    } catch (const std::invalid_argument&) {
      r.cameras = -1;  // R_vir unreachable at this AOV
    }
    progress.step();
  });
  progress.finish();
  return rows;
}

std::string sweep_csv(const std::vector<SweepRow>& rows) {
  std::string s = "figure,method,aov_deg,r_virtual_mm,r_virtual_over_r_phys,cameras\n";
  for (const SweepRow& r : rows)
    s += fmt::format("{},{},{:g},{:g},{:g},{}\n", r.figure, to_string(r.method), r.aov_deg, r.r_virtual_mm,
                     r.ratio, r.cameras < 0 ? std::string() : std::to_string(r.cameras));
  return s;
}

std::string sweep_aov_svg(const std::vector<SweepRow>& rows, const CountSweepOptions& p) {
  std::vector<Plot> plots;
  const char* letters = "abcdefghijklmnopqrstuvwxyz";
  for (size_t k = 0; k < p.r_virtual_mm.size(); ++k) {
    const double rv = p.r_virtual_mm[k];
    Plot plot;
    plot.title = fmt::format("({}) R_vir = {:g} mm, R_phy = {:g} mm", letters[k % 26], rv, p.r_phys_mm);
    plot.x_label = "angle of view of each camera (deg)";
    plot.y_label = "cameras needed";
    for (Method m : p.aov_methods) {
      PlotSeries s{method_label(m), method_color(m), {}, {}, false};
      for (const SweepRow& r : rows)
        if (r.figure == "aov" && r.method == m && r.r_virtual_mm == rv) {
          s.x.push_back(r.aov_deg);
          s.y.push_back(r.cameras < 0 ? NAN : r.cameras);
        }
      plot.series.push_back(s);
    }
    plots.push_back(plot);
  }
  return svg_plot_grid(plots, 3, "Cameras needed vs angle of view (thesis Fig. 3.3 / 3.9)");
}

std::string sweep_ratio_svg(const std::vector<SweepRow>& rows, const CountSweepOptions& p) {
  Plot plot;
  plot.title = fmt::format("Cameras vs R_vir / R_phy at AOV = {:g} deg (thesis Fig. 3.7)", p.fixed_aov_deg);
  plot.x_label = fmt::format("R_vir / R_phy   (R_phy = {:g} mm)", p.r_phys_mm);
  plot.y_label = "cameras needed";
  for (Method m : p.ratio_methods) {
    PlotSeries s{method_label(m), method_color(m), {}, {}, false};
    for (const SweepRow& r : rows)
      if (r.figure == "ratio" && r.method == m) {
        s.x.push_back(r.ratio);
        s.y.push_back(r.cameras < 0 ? NAN : r.cameras);
      }
    plot.series.push_back(s);
  }
  return svg_plot(plot, 760, 480);
}

}  // namespace omma::design
