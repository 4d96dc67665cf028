// omma resolution: the thesis's USAF 1951 measurement (§5.5.2, Fig. 5.23) in simulation. The chart
// stands 25 mm ahead of the dome; the dome's cameras are simulated, stitched, and the panorama is
// read element by element (omma/sim/usaf.h): the smallest element resolved (with every coarser one)
// and the angle of one of its bars is the angular resolution (thesis: group 1 element 2, 0.5 deg).
#include <chrono>
#include <filesystem>
#include <iostream>

#include <fmt/format.h>

#include "apps/command.h"
#include "omma/core/frames.h"
#include "omma/core/grid.h"
#include "omma/core/io.h"
#include "omma/core/rig.h"
#include "omma/design/prototype.h"
#include "omma/pano/stitch.h"
#include "omma/sim/simulate.h"
#include "omma/sim/usaf.h"

namespace omma::app {
namespace {

struct ResolutionArgs {
  std::string rig, method = "nn", size = "1080x1080", out;
  double distance = 25, contrast = 0.1;
  int supersample = 3;
  uint64_t seed = 1;
  bool ideal = false, json = false;
};

nlohmann::json reading_json(const sim::UsafReading* r) {
  if (!r) return nullptr;
  return {{"group", r->element.group},
          {"element", r->element.element},
          {"lp_per_mm", r->element.lp_per_mm},
          {"bar_mm", r->element.bar_mm},
          {"bar_deg", r->bar_deg},
          {"line_pair_deg", 2 * r->bar_deg},
          {"bar_deg_from_centre", r->bar_deg_centre},
          {"contrast_x", r->contrast_x},
          {"contrast_y", r->contrast_y}};
}

void run_resolution(const ResolutionArgs& a) {
  set_json_mode(a.json);
  const auto t0 = std::chrono::steady_clock::now();
  const pano::Method method = pano::parse_method(a.method);
  const Size2 size = parse_size(a.size);
  if (!(a.distance > 5 && a.distance < 1000)) throw std::invalid_argument("--distance must be 5..1000 mm");
  if (!(a.contrast > 0 && a.contrast < 1)) throw std::invalid_argument("--contrast must be in (0, 1)");
  const Rig rig = a.rig.empty() ? design::thesis_prototype_rig() : design::load_rig_or_builtin(a.rig);
  if (rig.cameras.empty()) throw RigError("the rig has no cameras");
  const auto scene = sim::make_usaf_scene(a.distance);
  sim::SimulateOptions o;
  o.effects = a.ideal ? sim::CameraEffects::ideal(a.supersample) : sim::CameraEffects{};
  o.effects.supersample = a.supersample;
  o.effects.seed = a.seed;
  o.truth_grid = PanoGrid{Projection::kVr180, size.width, size.height};
  o.progress = !a.json;
  const sim::SimulateSummary sim = sim::simulate(rig, *scene, o);
  std::vector<cv::Mat> frames;
  for (const auto& f : sim.frames) frames.push_back(f.image);
  pano::StitchOptions so;
  so.method = method;
  so.grid = o.truth_grid;
  so.progress = !a.json;
  const cv::Mat pano = pano::stitch(rig, frames, so);
  std::vector<sim::UsafViewpoint> views;
  for (const auto& c : sim.true_rig.cameras) views.push_back({c.position_mm, c.frame.t});
  const sim::UsafMeasurement m = sim::measure_usaf(pano, so.grid, a.distance, a.contrast, views);
  const sim::UsafMeasurement mt = sim::measure_usaf(sim.truth, so.grid, a.distance, a.contrast);
  if (!a.out.empty()) {
    sim::write_frames_folder(a.out, sim, o, *scene);
    write_image(std::filesystem::path(a.out) / "pano.png", to_u8(pano));
  }
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const double cam_deg_per_px = rad2deg(rig.cameras[0].in.aov) / rig.cameras[0].in.width;
  if (a.json) {
    nlohmann::json elements = nlohmann::json::array();
    for (const auto& r : m.readings)
      elements.push_back({{"group", r.element.group},
                          {"element", r.element.element},
                          {"bar_deg", r.bar_deg},
                          {"contrast_x", r.contrast_x},
                          {"contrast_y", r.contrast_y},
                          {"resolved", r.resolved}});
    print_json({{"method", pano::to_string(method)},
                {"distance_mm", a.distance},
                {"min_contrast", a.contrast},
                {"pano_width", size.width},
                {"pano_height", size.height},
                {"camera_deg_per_px", cam_deg_per_px},
                {"pano_deg_per_px", 180.0 / size.width},
                {"limit", reading_json(m.limit())},
                {"strict_limit", reading_json(m.strict_limit())},
                {"truth_limit", reading_json(mt.limit())},
                {"elements", elements},
                {"ms", ms}});
    return;
  }
  std::cout << fmt::format(
      "USAF 1951 chart at {} mm, {} cameras, {} stitch on vr180 {}x{} (contrast >= {}):\n", a.distance,
      rig.cameras.size(), pano::to_string(method), size.width, size.height, a.contrast);
  for (const auto& r : m.readings)
    std::cout << fmt::format(
        "  group {:2d} element {}: {:6.3f} lp/mm, bar {:.3f} deg, contrast x {:5.2f} y {:5.2f} {}\n",
        r.element.group, r.element.element, r.element.lp_per_mm, r.bar_deg, r.contrast_x, r.contrast_y,
        r.resolved ? "resolved" : "-");
  if (const auto* l = m.strict_limit())
    std::cout << fmt::format("every element down to group {} element {} is resolved\n", l->element.group,
                             l->element.element);
  if (const auto* l = m.limit())
    std::cout << fmt::format(
        "smallest resolved: group {} element {} -> angular resolution {:.2f} deg per bar "
        "as seen by its camera ({:.2f} deg from the dome centre, the thesis's convention); "
        "thesis: group 1 element 2, 0.5 deg\n",
        l->element.group, l->element.element, l->bar_deg, l->bar_deg_centre);
  else
    std::cout << "no element resolved\n";
  if (const auto* l = mt.limit())
    std::cout << fmt::format("ground truth on the same grid resolves group {} element {} ({:.2f} deg)\n",
                             l->element.group, l->element.element, l->bar_deg);
}

}  // namespace

void add_resolution_command(CLI::App& root) {
  static ResolutionArgs a;
  auto* cmd = root.add_subcommand(
      "resolution",
      "USAF 1951 resolution in simulation (thesis §5.5.2): simulate the dome looking at the chart,\n"
      "stitch, and find the smallest element whose bars keep a modulation >= --contrast in both\n"
      "directions (and every coarser one); its bar angle is the angular resolution.");
  cmd->add_option("--rig", a.rig, "Rig file (default: the thesis 24-camera prototype)");
  cmd->add_option("--distance", a.distance, "Chart distance from the dome centre along +z, mm")
      ->capture_default_str();
  cmd->add_option("--method", a.method, "Stitching method: nn|linear|gaussian|mrf|mrf-spherical|sad")
      ->capture_default_str();
  cmd->add_option("--size", a.size, "vr180 panorama size WxH")->capture_default_str();
  cmd->add_option("--contrast", a.contrast,
                  "Minimum modulation (Igap - Ibar) / (Igap + Ibar) to count as resolved")
      ->capture_default_str();
  cmd->add_option("--supersample", a.supersample, "N x N rays per camera pixel (optical blur)")
      ->capture_default_str();
  cmd->add_option("--seed", a.seed, "Simulation seed")->capture_default_str();
  cmd->add_flag("--ideal", a.ideal, "Ideal cameras (no vignetting, gains, noise, quantisation)");
  cmd->add_option("--out", a.out, "Also write the frames folder here, with pano.png");
  cmd->add_flag("--json", a.json, "Print one JSON object on stdout");
  cmd->callback([] { run_resolution(a); });
}

}  // namespace omma::app
