// Design-space exploration the thesis does not publish: PSNR of the bit-accurate pipeline against
// the floating-point reference stitcher (same RGB565 frames) as each width of HwConfig varies alone
// around a base configuration, and the smallest set of widths that keeps a target PSNR.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/core/grid.h"
#include "omma/core/rig.h"
#include "omma/hw/hw_config.h"
#include "omma/pano/method.h"

namespace omma::hw {

struct SweepParam {
  std::string name;         // HwConfig field
  std::vector<int> values;  // swept values, ascending
};
// The default parameters and ranges (angle bits, table size and word width, projection fraction
// bits, pixel fraction bits, distance and vector fraction bits, reciprocal, sample and mantissa widths).
std::vector<SweepParam> default_sweep_params();

struct WidthSweepOptions {
  HwConfig base;
  PanoGrid grid{Projection::kVr180, 540, 540};
  pano::Method method = pano::Method::kLinear;
  double target_db = 45;
  std::vector<SweepParam> params = default_sweep_params();
  std::function<void(const std::string&)> progress;  // called once per configuration rendered

  // False (with the reason in *why) when a value lies outside the range the code relies on.
  bool IsValid(std::string* why = nullptr) const;
};

struct SweepPoint {
  std::string param;
  int value = 0;
  double psnr_db = 0;
  bool valid = true;  // false if the configuration was rejected (IsValid / check_rig)
};

struct WidthSweepSummary {
  std::vector<SweepPoint> points;
  double base_psnr_db = 0;
  HwConfig minimal;  // smallest widths that keep target_db together
  double minimal_psnr_db = 0;
  std::vector<std::string> minimal_steps;  // what the search did, for the report
};

// Sets HwConfig field `name` to `value` (and adjusts the fields it constrains: proj_bits grows with
// proj_frac_bits, pos_frac_bits shrinks to dist_frac_bits, sincos_addr_bits to angle_bits - 2).
// Throws std::invalid_argument for an unknown name.
HwConfig with_param(HwConfig cfg, const std::string& name, int value);
int get_param(const HwConfig& cfg, const std::string& name);

// PSNR (dB) of the pipeline at `cfg` against `reference` (CV_8UC3, the float stitch of the same
// RGB565 frames on `grid`).
double psnr_against(const HwConfig& cfg, const Rig& rig, const std::vector<cv::Mat>& frames,
                    const PanoGrid& grid, pano::Method method, const cv::Mat& reference);

WidthSweepSummary run_sweep(const Rig& rig, const std::vector<cv::Mat>& frames,
                            const WidthSweepOptions& options);

// CSV (param,value,psnr_db,meets_target) and an SVG grid of PSNR-vs-width plots.
std::string sweep_csv(const WidthSweepSummary& r, double target_db);
std::string sweep_svg(const WidthSweepSummary& r, double target_db);

}  // namespace omma::hw
