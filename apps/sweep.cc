// omma sweep: camera counts vs angle of view and vs R_vir / R_phy (thesis Fig. 3.3, 3.7, 3.9).
#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>

#include <fmt/format.h>

#include "apps/command.h"
#include "omma/core/io.h"
#include "omma/core/log.h"
#include "omma/design/count_sweep.h"

namespace omma::app {

void add_sweep_command(CLI::App& root) {
  struct Opts {
    std::string out_dir = "sweep";
    design::CountSweepOptions p;
    bool json = false;
  };
  auto o = std::make_shared<Opts>();
  auto* cmd = root.add_subcommand(
      "sweep",
      "Reproduce the thesis's placement sweeps: cameras needed vs angle of view for R_vir = 8, 10,\n"
      "12, 25, 30, 40 mm (Fig. 3.3 / 3.9: layered, cvt, min-cameras) and vs R_vir / R_phy at a\n"
      "fixed AOV (Fig. 3.7: layered vs min-cameras). Writes OUT/sweep.csv, OUT/cameras_vs_aov.svg\n"
      "and OUT/cameras_vs_ratio.svg.");
  cmd->add_option("--out,--out-dir", o->out_dir, "Output folder (created if missing)")->capture_default_str();
  cmd->add_option("--r-phys", o->p.r_phys_mm, "Dome radius, mm")->capture_default_str();
  cmd->add_option("--r-virtual", o->p.r_virtual_mm, "R_vir values of the AOV sweep, mm")
      ->capture_default_str();
  cmd->add_option("--aov-min", o->p.aov_min_deg, "Smallest AOV of the AOV sweep, degrees")
      ->capture_default_str();
  cmd->add_option("--aov-max", o->p.aov_max_deg, "Largest AOV of the AOV sweep, degrees")
      ->capture_default_str();
  cmd->add_option("--aov-step", o->p.aov_step_deg, "AOV step, degrees")->capture_default_str();
  cmd->add_option("--aov", o->p.fixed_aov_deg, "AOV of the R_vir / R_phy sweep, degrees")
      ->capture_default_str();
  cmd->add_option("--ratio-min", o->p.ratio_min, "Smallest R_vir / R_phy")->capture_default_str();
  cmd->add_option("--ratio-max", o->p.ratio_max, "Largest R_vir / R_phy")->capture_default_str();
  cmd->add_option("--ratio-step", o->p.ratio_step, "R_vir / R_phy step")->capture_default_str();
  cmd->add_option("--step", o->p.check_step_deg, "Angular sampling of the coverage checks, degrees")
      ->capture_default_str();
  cmd->add_flag("--json", o->json, "Print one JSON object (rows, seconds, files) on stdout");
  cmd->callback([o] {
    set_json_mode(o->json);
    const auto& p = o->p;
    if (!(p.aov_min_deg > 0 && p.aov_max_deg < 180 && p.aov_min_deg <= p.aov_max_deg && p.aov_step_deg > 0))
      throw std::invalid_argument("the AOV range must lie in (0, 180) degrees with a positive step");
    if (!(p.ratio_min > 1 && p.ratio_min <= p.ratio_max && p.ratio_step > 0))
      throw std::invalid_argument("the R_vir / R_phy range must be > 1 with a positive step");
    if (!(p.fixed_aov_deg > 0 && p.fixed_aov_deg < 180))
      throw std::invalid_argument("--aov must be in (0, 180) degrees");
    if (!(p.check_step_deg > 0 && p.check_step_deg <= 5))
      throw std::invalid_argument("--step must be in (0, 5] degrees");
    for (double rv : p.r_virtual_mm)
      if (!(rv > p.r_phys_mm)) throw std::invalid_argument("every --r-virtual must exceed --r-phys");
    const auto t0 = std::chrono::steady_clock::now();
    const auto rows = design::run_sweep(p);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const std::filesystem::path dir = o->out_dir;
    std::filesystem::create_directories(dir);
    const auto csv = dir / "sweep.csv", aov = dir / "cameras_vs_aov.svg",
               ratio = dir / "cameras_vs_ratio.svg";
    write_text_atomically(csv, design::sweep_csv(rows));
    write_text_atomically(aov, design::sweep_aov_svg(rows, p));
    write_text_atomically(ratio, design::sweep_ratio_svg(rows, p));
    spdlog::info("sweep of {} designs in {:.1f} s: wrote {}, {}, {}", rows.size(), seconds, csv.string(),
                 aov.string(), ratio.string());
    if (o->json) {
      print_json({{"rows", rows.size()},
                  {"seconds", seconds},
                  {"files", {csv.string(), aov.string(), ratio.string()}}});
    } else {
      std::cout << fmt::format("{} designs in {:.1f} s -> {}, {}, {}\n", rows.size(), seconds, csv.string(),
                               aov.string(), ratio.string());
    }
  });
}

}  // namespace omma::app
