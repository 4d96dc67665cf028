// omma rig check RIG: load and validate a rig file, print a summary.
#include "omma/core/rig.h"

#include <cmath>
#include <iostream>

#include <fmt/format.h>

#include "apps/command.h"
#include "omma/design/prototype.h"

namespace omma::app {

void add_rig_command(CLI::App& root) {
  auto* cmd = root.add_subcommand("rig", "Inspect rig files");
  cmd->require_subcommand(1);
  auto* check = cmd->add_subcommand("check", "Load and validate a rig file, print a summary");
  static std::string path;
  static bool json = false;
  check->add_option("RIG", path, "Rig file (JSON)")->required();
  check->add_flag("--json", json, "Print one JSON object on stdout");
  check->callback([] {
    set_json_mode(json);
    const Rig rig = design::load_rig_or_builtin(path);
    double min_aov = 1e9, max_aov = 0;
    for (const auto& c : rig.cameras) {
      min_aov = std::min(min_aov, rad2deg(c.in.aov));
      max_aov = std::max(max_aov, rad2deg(c.in.aov));
    }
    if (json) {
      print_json({{"name", rig.name},
                  {"cameras", rig.cameras.size()},
                  {"radius_mm", rig.dome.radius_mm},
                  {"sphere", rig.dome.sphere},
                  {"aov_deg_min", min_aov},
                  {"aov_deg_max", max_aov},
                  {"valid", true}});
    } else {
      std::cout << fmt::format(
          "{}: valid rig '{}', {} cameras on a {} of radius {} mm, AOV {:.1f}-{:.1f} deg\n", path, rig.name,
          rig.cameras.size(), rig.dome.sphere ? "sphere" : "hemisphere", rig.dome.radius_mm, min_aov,
          max_aov);
    }
  });
}

}  // namespace omma::app
