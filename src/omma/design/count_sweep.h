// Sweeps of the camera count (thesis Fig. 3.3, 3.9: cameras vs angle of view for several R_vir;
// Fig. 3.7: cameras vs R_vir / R_phy at a fixed angle of view), as tables, CSV and SVG plots.
#pragma once

#include <string>
#include <vector>

#include "omma/design/placement.h"

namespace omma::design {

struct CountSweepOptions {
  double r_phys_mm = 5.0;
  std::vector<double> r_virtual_mm = {8, 10, 12, 25, 30, 40};  // Fig. 3.3 / 3.9 panels
  double aov_min_deg = 40, aov_max_deg = 120, aov_step_deg = 4;
  std::vector<Method> aov_methods = {Method::kLayered, Method::kCvt, Method::kMinCameras};
  double fixed_aov_deg = 64;                                   // Fig. 3.7
  double ratio_min = 1.6, ratio_max = 10.0, ratio_step = 0.2;  // R_vir / R_phy: 8/5 .. 50/5
  std::vector<Method> ratio_methods = {Method::kLayered, Method::kMinCameras};
  double check_step_deg = 0.5;

  // False (with the reason in *why) when a value lies outside the range the code relies on.
  bool IsValid(std::string* why = nullptr) const;
};

struct SweepRow {
  std::string figure;  // "aov" (Fig. 3.3/3.9) or "ratio" (Fig. 3.7)
  Method method = Method::kLayered;
  double aov_deg = 0, r_virtual_mm = 0, ratio = 0;
  int cameras = -1;  // -1: no design (R_vir too close for this AOV)
};

// Runs every design (in parallel, oneTBB), with a progress bar on stderr.
std::vector<SweepRow> run_sweep(const CountSweepOptions& p);

std::string sweep_csv(const std::vector<SweepRow>& rows);
// Fig. 3.3/3.9: one panel per R_vir, cameras vs AOV, one line per method.
std::string sweep_aov_svg(const std::vector<SweepRow>& rows, const CountSweepOptions& p);
// Fig. 3.7: cameras vs R_vir / R_phy at the fixed AOV.
std::string sweep_ratio_svg(const std::vector<SweepRow>& rows, const CountSweepOptions& p);

}  // namespace omma::design
