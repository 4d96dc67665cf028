// omma coverage: coverage analysis of a rig (thesis §2.4.2, §3.4, Fig. 7.5).
#include "omma/design/coverage.h"

#include <cmath>
#include <iostream>
#include <memory>
#include <vector>

#include <fmt/format.h>

#include "apps/command.h"
#include "omma/core/grid.h"
#include "omma/core/io.h"
#include "omma/core/limits.h"
#include "omma/core/log.h"
#include "omma/core/parse.h"
#include "omma/core/rig.h"
#include "omma/design/dome.h"
#include "omma/design/prototype.h"

namespace omma::app {
namespace {

// "inf" / "infinity" or a positive number of mm.
double parse_distance(const std::string& text) {
  if (text == "inf" || text == "infinity") return design::kInfinity;
  const double d = parse_double(text).value_or(0);  // core/parse.h
  if (!(d > 0 && d <= kMaxPositionMm))
    throw std::invalid_argument(fmt::format(
        "--distance must be a number of mm in (0, {}] or 'inf' (beyond 1 km every direction is at infinity), "
        "got '{}'",
        kMaxPositionMm, text));
  return d;
}

std::string distance_label(double d) { return std::isinf(d) ? "inf" : fmt::format("{:g}mm", d); }

nlohmann::json number_or_null(double x) {
  return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr);
}

// Fewest and most cameras over the sample rows with polar angle in [lo, hi] (radians).
std::pair<int, int> counts_between(const design::CoverageSummary& st, double lo, double hi) {
  int mn = 1 << 30, mx = 0;
  for (size_t j = 0; j < st.row_theta_rad.size(); ++j)
    if (st.row_theta_rad[j] >= lo - 1e-12 && st.row_theta_rad[j] <= hi + 1e-12) {
      mn = std::min(mn, st.row_min[j]);
      mx = std::max(mx, st.row_max[j]);
    }
  return {mn == (1 << 30) ? 0 : mn, mx};
}

}  // namespace

void add_coverage_command(CLI::App& root) {
  struct Opts {
    std::string rig, map;
    std::vector<std::string> distances;
    double step = 0.1, polar_max = 0;
    int map_width = 1440, min_count = 2;
    bool json = false;
  };
  auto o = std::make_shared<Opts>();
  auto* cmd = root.add_subcommand(
      "coverage",
      "Coverage analysis of a rig: how many cameras see each direction at a distance, the widest band\n"
      "of polar angles seen by at least --min-count cameras, and R_vir, the smallest distance (mm from\n"
      "the dome centre) from which on no direction is missed. A point X is seen by camera i when\n"
      "angle(X - p_i, t_i) <= aov_i / 2 (p_i on the dome), or, for rectangular fields (\"field\": "
      "\"image\"),\n"
      "when X - p_i lands inside camera i's image.");
  cmd->add_option("RIG", o->rig,
                  "Rig file (JSON) or built-in rig (thesis-24, gigaeye-44, gigaeye-44-skip1, ...)")
      ->required();
  cmd->add_option("--distance", o->distances,
                  "Distance(s) from the dome centre at which to count, mm, or 'inf' (repeatable; default: "
                  "the rig's R_vir)");
  cmd->add_option("--step", o->step, "Angular sampling of the field of view, degrees")->capture_default_str();
  cmd->add_option("--polar-max", o->polar_max,
                  "Field of view: polar angles 0..DEG (default: 90, or 180 for sphere rigs)");
  cmd->add_option("--min-count", o->min_count, "Cameras a direction needs for the polar band")
      ->capture_default_str();
  cmd->add_option(
      "--map", o->map,
      "Write a colour-coded coverage-count map (equirectangular, with legend), e.g. map.png; with "
      "several distances one map per distance, named map_<distance>.png");
  cmd->add_option("--map-width", o->map_width, "Width of the map in pixels")->capture_default_str();
  cmd->add_flag(
      "--json", o->json,
      "Print one JSON object on stdout: {distance_mm, covered_fraction, min_cameras, max_cameras, "
      "mean_cameras, r_virtual_mm, band: {min_count, from_deg, to_deg, min_cameras, max_cameras}} of the "
      "first distance and \"distances\": the same for every distance (null for infinite values)");
  cmd->callback([o] {
    set_json_mode(o->json);
    if (!(o->step > 0 && o->step <= 10)) throw std::invalid_argument("--step must be in (0, 10] degrees");
    if (!(o->polar_max >= 0 && o->polar_max <= 180))
      throw std::invalid_argument("--polar-max must be in (0, 180] degrees");
    if (o->map_width < 16 || o->map_width > 16384)
      throw std::invalid_argument("--map-width must be in [16, 16384]");
    if (o->min_count < 1) throw std::invalid_argument("--min-count must be >= 1");
    std::vector<double> distances;
    for (const std::string& d : o->distances) distances.push_back(parse_distance(d));
    const Rig rig = design::load_rig_or_builtin(o->rig);
    const double step = deg2rad(o->step);
    if (distances.empty()) {
      const double rvir = design::virtual_radius(rig, step);
      if (!std::isfinite(rvir))
        throw std::runtime_error("the rig never covers its whole field of view; give --distance");
      distances.push_back(rvir);
    }
    const std::string name = rig.name.empty() ? o->rig : rig.name;
    nlohmann::json all = nlohmann::json::array();
    nlohmann::json first;
    for (double distance : distances) {
      const design::CoverageSummary st = design::analyze_coverage(rig, distance, step, deg2rad(o->polar_max));
      const design::PolarBand band = st.polar_band(o->min_count);
      // Fig. 7.5's "2..7 cameras where theta < 60 deg", read as a polar angle and as an elevation.
      const auto [pmin, pmax] = counts_between(st, 0, deg2rad(60));
      const auto [emin, emax] =
          counts_between(st, deg2rad(30), std::min(deg2rad(150), deg2rad(st.theta_max_deg)));
      if (!o->map.empty()) {
        PanoGrid grid;
        const bool wide = rig.dome.sphere;
        const bool band100 = std::abs(st.theta_max_deg - 100) < 1e-9;  // the Giga-Eye's 360 x 100 deg
        grid.projection = band100 ? Projection::kEquirect100
                          : wide  ? Projection::kEquirectFull
                                  : Projection::kEquirect;
        grid.width = o->map_width;
        grid.height = band100 ? o->map_width * 100 / 360 : wide ? o->map_width / 2 : o->map_width / 4;
        const cv::Mat counts = design::coverage_count_map(rig, grid, distance);
        const std::string title =
            fmt::format("{}: cameras per direction at {} (R_vir {})", name,
                        std::isinf(distance) ? "infinity" : fmt::format("{:.0f} mm", distance),
                        std::isinf(st.r_virtual_mm) ? "none: gaps at every distance"
                                                    : fmt::format("{:.2f} mm", st.r_virtual_mm));
        std::filesystem::path path = o->map;
        if (distances.size() > 1)
          path.replace_filename(path.stem().string() + "_" + distance_label(distance) +
                                path.extension().string());
        write_image(path, design::render_coverage_map(counts, title));
        spdlog::info("wrote {}", path.string());
      }
      nlohmann::json j = {{"distance_mm", number_or_null(st.distance_mm)},
                          {"polar_max_deg", st.theta_max_deg},
                          {"covered_fraction", st.covered_fraction},
                          {"min_cameras", st.min_cameras},
                          {"max_cameras", st.max_cameras},
                          {"mean_cameras", st.mean_cameras},
                          {"r_virtual_mm", number_or_null(st.r_virtual_mm)}};
      j["band"] = band.empty() ? nlohmann::json(nullptr)
                               : nlohmann::json{{"min_count", o->min_count},
                                                {"from_deg", rad2deg(band.from_rad)},
                                                {"to_deg", rad2deg(band.to_rad)},
                                                {"min_cameras", band.min_cameras},
                                                {"max_cameras", band.max_cameras}};
      j["polar_below_60"] = {{"min_cameras", pmin}, {"max_cameras", pmax}};
      j["elevation_below_60"] = {{"min_cameras", emin}, {"max_cameras", emax}};
      all.push_back(j);
      if (first.is_null()) first = j;
      if (!o->json) {
        std::cout << fmt::format(
            "{}: {} cameras, at {}: {:.4f} % of polar 0..{:g} deg covered, {}..{} cameras per direction "
            "(mean {:.2f}); R_vir = {:.2f} mm (step {:g} deg)\n",
            name, rig.cameras.size(), std::isinf(distance) ? "infinity" : fmt::format("{:.2f} mm", distance),
            100 * st.covered_fraction, st.theta_max_deg, st.min_cameras, st.max_cameras, st.mean_cameras,
            st.r_virtual_mm, o->step);
        if (band.empty())
          std::cout << fmt::format("  no polar band is seen by >= {} cameras everywhere\n", o->min_count);
        else
          std::cout << fmt::format(
              "  seen by >= {} cameras: polar {:.1f}..{:.1f} deg ({}..{} cameras there)\n", o->min_count,
              rad2deg(band.from_rad), rad2deg(band.to_rad), band.min_cameras, band.max_cameras);
        std::cout << fmt::format(
            "  thesis Fig. 7.5 \"2..7 cameras where theta < 60 deg\": polar < 60 deg here {}..{}, elevation "
            "within 60 deg of the horizon (polar 30..{:g}) {}..{}\n",
            pmin, pmax, std::min(150.0, st.theta_max_deg), emin, emax);
      }
    }
    if (o->json) {
      first["distances"] = all;
      print_json(first);
    }
  });
}

}  // namespace omma::app
