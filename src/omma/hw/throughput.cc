#include "omma/hw/throughput.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "omma/core/valid.h"

namespace omma::hw {

bool ThroughputOptions::IsValid(std::string* error) const {
  if (cameras < 1 || cameras > 4096)
    return invalid(error, fmt::format("cameras = {} must be in [1, 4096]", cameras));
  if (max_contributors < 1 || max_contributors > cameras)
    return invalid(
        error, fmt::format("max_contributors = {} must be in [1, cameras = {}]", max_contributors, cameras));
  if (angle_th < 1 || memory_th < 1) return invalid(error, "angle_th and memory_th must be >= 1");
  if (table_sets != 1 && table_sets != 3)
    return invalid(error, fmt::format("table_sets = {} must be 1 or 3", table_sets));
  if (width < 1 || height < 1) return invalid(error, "width and height must be >= 1");
  if (!(fps > 0)) return invalid(error, "fps must be > 0");
  if (!(clock_mhz > 0)) return invalid(error, "clock_mhz must be > 0");
  return true;
}

ThroughputSummary throughput(const ThroughputOptions& o) {
  std::string err;
  if (!o.IsValid(&err)) throw std::invalid_argument("throughput model: " + err);
  ThroughputSummary s;
  s.blocks = {{"angle generation", o.angle_th},
              {"cartesian vector", 9 / o.table_sets},
              {"camera search", o.unrolled ? o.max_contributors : o.cameras},
              {"frame memory", o.memory_th},
              {"pixel value", o.max_contributors}};
  for (const auto& b : s.blocks) s.th_sys = std::max(s.th_sys, b.th);
  const double pixels = static_cast<double>(o.width) * o.height;
  s.fmin_mhz = o.fps * pixels * s.th_sys * 1e-6;
  s.fps_at_clock = o.clock_mhz * 1e6 / (pixels * s.th_sys);
  s.pixels_per_frame_at_clock = o.clock_mhz * 1e6 / (o.fps * s.th_sys);
  s.square_side_at_clock = static_cast<int>(std::floor(std::sqrt(s.pixels_per_frame_at_clock)));
  return s;
}

int pixel_cycles(const ThroughputOptions& o, int n) {
  const int search = o.unrolled ? std::max(1, n) : o.cameras;
  return std::max({o.angle_th, 9 / o.table_sets, o.memory_th, search, std::max(1, n)});
}

}  // namespace omma::hw
