// omma coverage: coverage analysis of a rig (thesis §2.4.2, §3.4, Fig. 7.5).
#include <cmath>
#include <iostream>
#include <memory>
#include <optional>

#include <fmt/format.h>

#include "apps/command.h"
#include "omma/core/grid.h"
#include "omma/core/io.h"
#include "omma/core/log.h"
#include "omma/core/rig.h"
#include "omma/design/coverage.h"

namespace omma::app {

void add_coverage_command(CLI::App& root) {
  struct Opts {
    std::string rig, map;
    std::optional<double> distance;
    double step = 0.1;
    int map_width = 1440;
    bool json = false;
  };
  auto o = std::make_shared<Opts>();
  auto* cmd = root.add_subcommand(
      "coverage",
      "Coverage analysis of a rig: how many cameras see each direction at a distance, and R_vir,\n"
      "the smallest distance (mm from the dome centre) from which on no direction is missed.\n"
      "A point X is seen by camera i when angle(X - p_i, t_i) <= aov_i / 2 (p_i on the dome).");
  cmd->add_option("RIG", o->rig, "Rig file (JSON)")->required();
  cmd->add_option("--distance", o->distance,
                  "Distance from the dome centre at which to count, mm (default: the rig's R_vir)");
  cmd->add_option("--step", o->step, "Angular sampling of the field of view, degrees")
      ->capture_default_str();
  cmd->add_option("--map", o->map,
                  "Write a colour-coded coverage-count map (equirectangular, with legend), e.g. map.png");
  cmd->add_option("--map-width", o->map_width, "Width of the map in pixels")->capture_default_str();
  cmd->add_flag("--json", o->json,
                "Print one JSON object {distance_mm, covered_fraction, min_cameras, max_cameras, "
                "mean_cameras, r_virtual_mm} on stdout (r_virtual_mm is null if never covered)");
  cmd->callback([o] {
    set_json_mode(o->json);
    if (!(o->step > 0 && o->step <= 10))
      throw std::invalid_argument("--step must be in (0, 10] degrees");
    if (o->distance && !(*o->distance > 0))
      throw std::invalid_argument("--distance must be a positive number of mm");
    if (o->map_width < 16 || o->map_width > 16384)
      throw std::invalid_argument("--map-width must be in [16, 16384]");
    const Rig rig = load_rig(o->rig);
    const double step = deg2rad(o->step);
    double distance = 0;
    if (o->distance) {
      distance = *o->distance;
    } else {
      distance = design::virtual_radius(rig, step);
      if (!std::isfinite(distance))
        throw std::runtime_error("the rig never covers its whole field of view; give --distance");
    }
    const design::CoverageStats st = design::analyze_coverage(rig, distance, step);
    if (!o->map.empty()) {
      PanoGrid grid;
      grid.projection = rig.dome.sphere ? Projection::kEquirectFull : Projection::kEquirect;
      grid.width = o->map_width;
      grid.height = rig.dome.sphere ? o->map_width / 2 : o->map_width / 4;
      const cv::Mat counts = design::coverage_count_map(rig, grid, distance);
      const std::string title =
          fmt::format("{}: cameras per direction at {:.2f} mm (R_vir {:.2f} mm)",
                      rig.name.empty() ? o->rig : rig.name, distance, st.r_virtual_mm);
      write_image(o->map, design::render_coverage_map(counts, title));
      spdlog::info("wrote {}", o->map);
    }
    if (o->json) {
      nlohmann::json j = {{"distance_mm", st.distance_mm},
                          {"covered_fraction", st.covered_fraction},
                          {"min_cameras", st.min_cameras},
                          {"max_cameras", st.max_cameras},
                          {"mean_cameras", st.mean_cameras}};
      j["r_virtual_mm"] = std::isfinite(st.r_virtual_mm) ? nlohmann::json(st.r_virtual_mm)
                                                         : nlohmann::json(nullptr);
      print_json(j);
    } else {
      std::cout << fmt::format(
          "{}: {} cameras, at {:.2f} mm: {:.4f} % of the field of view covered, {}..{} cameras "
          "per direction (mean {:.2f}); R_vir = {:.2f} mm (step {:g} deg)\n",
          o->rig, rig.cameras.size(), distance, 100 * st.covered_fraction, st.min_cameras,
          st.max_cameras, st.mean_cameras, st.r_virtual_mm, o->step);
    }
  });
}

}  // namespace omma::app
