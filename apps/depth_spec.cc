#include "apps/depth_spec.h"

#include <cmath>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>

#include "omma/core/log.h"
#include "omma/core/parse.h"
#include "omma/pano/surface.h"

namespace omma::app {

const char* const kDepthSpecHelp =
    "  inf                   the scene at infinity (the thesis's model)\n"
    "  sphere:R              a fixed stitching distance: a sphere of R mm around the dome centre\n"
    "  truth:FILE            a depth file of the panorama's size (the simulator's truth_depth.tiff:\n"
    "                        float TIFF, mm; or 16-bit in 1/100 mm)\n"
    "  estimate[:NEAR,FAR,STEPS]  estimated from the cameras' overlaps by a sphere sweep\n";

namespace {

// Parses "NEAR,FAR,STEPS" (any suffix may be left out).
pano::PlaneSweepOptions parse_sweep_into(const std::string& text, pano::PlaneSweepOptions so) {
  if (text.empty()) return so;
  std::vector<double> v;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = text.find(',', start);
    const std::string part =
        text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const std::optional<double> x = parse_double(part);  // core/parse.h
    if (!x) throw std::invalid_argument("--depth estimate:NEAR,FAR,STEPS: '" + part + "' is not a number");
    v.push_back(*x);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (v.size() > 3)
    throw std::invalid_argument("--depth estimate:NEAR,FAR,STEPS takes at most three numbers");
  if (v.size() > 0) so.near_mm = v[0];
  if (v.size() > 1) so.far_mm = v[1];
  if (v.size() > 2) {
    if (v[2] != std::floor(v[2]) || !(v[2] >= 2 && v[2] <= pano::kMaxSteps))
      throw std::invalid_argument(
          fmt::format("--depth estimate: STEPS must be a whole number 2..{}, got {}", pano::kMaxSteps, v[2]));
    so.steps = static_cast<int>(v[2]);
  }
  std::string why;
  if (!so.IsValid(&why)) throw std::invalid_argument("--depth estimate: " + why);
  return so;
}

}  // namespace

// --depth-pitch: the sweep grid's pitch in degrees, or "camera" (the finest camera's pixel pitch at its
// centre, pano::camera_pitch_deg). Sets pitch_deg with factor 0 (the coarse factor nearest to it).
void apply_depth_pitch(const std::string& pitch, const Rig& rig, pano::PlaneSweepOptions& so) {
  if (pitch.empty()) return;
  if (pitch == "camera") {
    so.pitch_deg = pano::camera_pitch_deg(rig);
  } else {
    const std::optional<double> deg = parse_double(pitch);  // core/parse.h
    if (!deg || !(*deg > 0) || !(*deg <= 90))
      throw std::invalid_argument("--depth-pitch must be an angle in (0, 90] degrees or 'camera', got '" +
                                  pitch + "'");
    so.pitch_deg = *deg;
  }
  so.factor = 0;
}

bool is_estimate_spec(const std::string& spec) {
  return spec == "estimate" || spec.rfind("estimate:", 0) == 0;
}

void check_depth_spec(const std::string& spec) {
  if (spec != "inf" && spec.rfind("sphere:", 0) != 0 && spec.rfind("truth:", 0) != 0 &&
      !is_estimate_spec(spec))
    throw std::invalid_argument(
        "--depth must be inf, sphere:R, truth:FILE or estimate[:NEAR,FAR,STEPS], got '" + spec + "'");
}

pano::PlaneSweepOptions parse_estimate_spec(const std::string& spec, pano::PlaneSweepOptions base) {
  if (!is_estimate_spec(spec)) throw std::invalid_argument("--depth '" + spec + "' is not an estimate");
  return parse_sweep_into(spec == "estimate" ? "" : spec.substr(std::string("estimate:").size()), base);
}

DepthChoice choose_depth(const std::string& spec, const std::string& pitch, const Rig& rig,
                         const std::vector<cv::Mat>& frames, const PanoGrid& grid) {
  check_depth_spec(spec);
  const bool estimate = is_estimate_spec(spec);
  if (!pitch.empty() && !estimate)
    throw std::invalid_argument("--depth-pitch applies to --depth estimate only, got --depth " + spec);
  DepthChoice d;
  auto after = [&](const std::string& prefix) { return spec.substr(prefix.size()); };
  if (spec == "inf") {
    d.info = {{"mode", "inf"}};
  } else if (spec.rfind("sphere:", 0) == 0) {
    const std::optional<double> parsed = parse_double(after("sphere:"));  // core/parse.h
    if (!parsed) throw std::invalid_argument("--depth sphere:R needs a radius in mm, got '" + spec + "'");
    const double r = *parsed;
    d.depth = pano::sphere_depth(rig, grid, r);
    d.info = {{"mode", "sphere"}, {"radius_mm", r}};
  } else if (spec.rfind("truth:", 0) == 0) {
    d.depth = pano::read_depth(after("truth:"), grid);
    pano::check_depth_outside_dome(d.depth, rig, grid, Vec3::Zero(), "depth file " + after("truth:"));
    d.info = {{"mode", "truth"}, {"file", after("truth:")}};
  } else {  // an estimate (check_depth_spec)
    pano::PlaneSweepOptions so = parse_estimate_spec(spec);
    apply_depth_pitch(pitch, rig, so);
    const pano::DepthSweep sweep(rig, grid, so);
    const pano::DepthEstimate e = sweep.estimate(frames);
    // A range that excludes the scene piles the confident estimates up at one of its ends.
    // (at infinity the far end is the scene's own place: only a finite FAR can exclude it)
    if (e.confident > 0 && (e.at_near > 0.5 || (std::isfinite(so.far_mm) && e.at_far > 0.5)))
      throw std::invalid_argument(
          fmt::format("--depth {}: the sweep range {}..{} mm excludes the scene: {:.0f} % of the confident "
                      "directions lie at "
                      "its {} end (widen NEAR,FAR)",
                      spec, so.near_mm, so.far_mm, 100 * std::max(e.at_near, e.at_far),
                      e.at_near > e.at_far ? "near" : "far"));
    if (e.confident == 0)
      spdlog::warn(
          "--depth estimate: no direction could be measured; the prior distance {:.1f} mm is used everywhere",
          e.prior_mm);
    d.depth = e.depth;
    d.estimate = e;
    d.info = {
        {"mode", "estimate"},
        {"near_mm", so.near_mm},
        {"far_mm", so.far_mm},
        {"steps", so.steps},
        {"coarse", {sweep.coarse_grid().width, sweep.coarse_grid().height}},
        {"pitch_deg", so.pitch_deg},
        {"prior_mm", e.prior_mm},
        {"confident_fraction", double(e.confident) / sweep.coarse_grid().width / sweep.coarse_grid().height},
        {"at_near", e.at_near},
        {"at_far", e.at_far},
        {"mean_confidence", cv::mean(e.confidence)[0]}};
  }
  return d;
}

}  // namespace omma::app
