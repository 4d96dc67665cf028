// omma design: place cameras on a dome (thesis §3.3-3.4): layered, min-cameras, max-volume, cvt.
#include <cmath>
#include <iostream>
#include <memory>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "apps/command.h"
#include "omma/core/log.h"
#include "omma/core/rig.h"
#include "omma/design/placement.h"

namespace omma::app {

void add_design_command(CLI::App& root) {
  struct Opts {
    std::string method = "max-volume", cam_size = "1x1x2", out;
    double aov = 64, r_phys = 5, r_virtual = 18, step = 0.5;
    bool sphere = false, json = false;
  };
  auto o = std::make_shared<Opts>();
  auto* cmd = root.add_subcommand(
      "design",
      "Design a dome: place cameras with one of four methods (thesis §3.3-3.4) and report the\n"
      "cameras per layer and the overlap distance R_vir of the result (coverage analysis).\n"
      "  layered      earlier 'Panoptic' floors from the pole, whole floors added until covered\n"
      "  min-cameras  §3.4.1: fewest cameras that cover the field of view at --r-virtual\n"
      "  max-volume   §3.4.2: most cameras of --cam-size that fit on the dome (ignores --r-virtual)\n"
      "  cvt          §3.4.3, Algorithm 1: centroidal Voronoi tessellation, one more camera until\n"
      "               covered at --r-virtual\n"
      "The thesis prototype (3+9+12 = 24 cameras) is: omma design --method max-volume --cam-size 1x1x2");
  cmd->add_option("--method", o->method, "layered | min-cameras | max-volume | cvt")
      ->capture_default_str()
      ->check(CLI::IsMember({"layered", "min-cameras", "max-volume", "cvt"}));
  cmd->add_option("--aov", o->aov, "Angle of view of every camera, degrees, in (0, 180)")
      ->capture_default_str();
  cmd->add_option("--r-phys", o->r_phys, "Outer dome radius (the pinholes sit on it), mm")
      ->capture_default_str();
  cmd->add_option("--cam-size", o->cam_size,
                  "Camera size WxHxL in mm (sensor face W x H, length L from pinhole to the back); "
                  "max-volume only. 1x1x2 gives the prototype's 3+9+12; Table 3.1's 1x1x1.85 gives "
                  "3+9+13")
      ->capture_default_str();
  cmd->add_option("--r-virtual", o->r_virtual,
                  "Overlap distance to reach (mm from the dome centre) for layered, min-cameras, cvt")
      ->capture_default_str();
  cmd->add_option("--step", o->step, "Angular sampling of the coverage checks, degrees")
      ->capture_default_str();
  cmd->add_flag("--sphere", o->sphere, "Design a full sphere instead of the hemisphere around +z");
  cmd->add_option("--out", o->out, "Write the rig file (JSON) here");
  cmd->add_flag("--json", o->json, "Print one JSON object {method, cameras, layers, r_virtual_mm} on stdout");
  cmd->callback([o] {
    set_json_mode(o->json);
    design::DesignParams p;
    if (!(o->aov > 0 && o->aov < 180)) throw std::invalid_argument("--aov must be in (0, 180) degrees");
    if (!(o->r_phys > 0)) throw std::invalid_argument("--r-phys must be a positive number of mm");
    if (!(o->step > 0 && o->step <= 5)) throw std::invalid_argument("--step must be in (0, 5] degrees");
    p.aov_rad = deg2rad(o->aov);
    p.r_phys_mm = o->r_phys;
    p.r_virtual_mm = o->r_virtual;
    p.cam = design::parse_camera_size(o->cam_size);
    p.sphere = o->sphere;
    p.check_step_rad = deg2rad(o->step);
    const design::Method m = design::parse_method(o->method);
    const design::Design d = design::design_rig(m, p);
    if (!o->out.empty()) {
      save_rig(d.rig, o->out);
      spdlog::info("wrote {}", o->out);
    }
    if (o->json) {
      print_json({{"method", o->method},
                  {"cameras", d.rig.cameras.size()},
                  {"layers", d.layers},
                  {"r_virtual_mm", d.r_virtual_mm}});
    } else {
      std::cout << fmt::format(
          "{}: {} cameras on a {} of radius {:g} mm, AOV {:g} deg\n  layers (from the pole): {}\n"
          "  R_vir (no gap from this distance on): {:.2f} mm{}\n",
          o->method, d.rig.cameras.size(), p.sphere ? "sphere" : "hemisphere", p.r_phys_mm, o->aov,
          fmt::join(d.layers, " + "), d.r_virtual_mm,
          m == design::Method::kMaxVolume ? "" : fmt::format(" (target {:g} mm)", o->r_virtual));
    }
  });
}

}  // namespace omma::app
