#include "omma/sim/simulate.h"

#include <unistd.h>

#include <chrono>
#include <system_error>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "omma/core/frames.h"
#include "omma/core/io.h"
#include "omma/core/progress.h"
#include "omma/core/valid.h"

namespace omma::sim {
namespace fs = std::filesystem;

bool SimulateOptions::IsValid(std::string* why) const {
  if (truth && (truth_grid.width <= 0 || truth_grid.height <= 0))
    return invalid(why, "truth size must be positive");
  if (shots < 1 || shots > 1000) return invalid(why, fmt::format("shots must be 1..1000, got {}", shots));
  if (truth_supersample < 0 || truth_supersample > 16)
    return invalid(why,
                   fmt::format("truth supersample must be 0 (auto) or 1..16, got {}", truth_supersample));
  return true;
}

namespace {
double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

SimulateSummary simulate(const Rig& nominal, const Scene& scene, const SimulateOptions& o) {
  if (nominal.cameras.empty()) throw RigError("the rig has no cameras");
  nominal.validate();
  std::string why;
  if (!o.IsValid(&why)) throw std::invalid_argument(why);
  SimulateSummary res;
  res.nominal = nominal;
  res.true_rig = perturb_rig(nominal, o.perturb, o.effects.seed);
  res.frames.resize(nominal.cameras.size());
  res.more_shots.assign(size_t(o.shots - 1), std::vector<CameraFrame>(nominal.cameras.size()));
  {
    Progress progress("simulate cameras", nominal.cameras.size(), o.progress);
    const auto t0 = std::chrono::steady_clock::now();
    tbb::parallel_for(size_t{0}, res.true_rig.cameras.size(), [&](size_t i) {
      // The scene is static: its radiance once, the sensor (noise) once per shot.
      const RigCamera& cam = res.true_rig.cameras[i];
      const cv::Mat radiance = render_radiance(scene, cam, o.pose, o.effects.supersample);
      res.frames[i] = apply_sensor(radiance, cam, o.effects, o.raw);
      for (int k = 1; k < o.shots; ++k) {
        CameraEffects e = o.effects;
        e.shot = k;
        res.more_shots[size_t(k - 1)][i] = apply_sensor(radiance, cam, e, o.raw);
      }
      progress.step();
    });
    progress.finish();
    res.cameras_ms = ms_since(t0);
  }
  if (o.truth) {
    const auto t0 = std::chrono::steady_clock::now();
    const int n = o.truth_supersample > 0 ? o.truth_supersample : auto_truth_supersample(o.truth_grid);
    Progress progress("simulate truth", o.truth_grid.height, o.progress);
    res.truth = render_truth(scene, o.truth_grid, o.pose, n, o.effects.exposure, &progress);
    res.truth_depth = render_truth_depth(scene, o.truth_grid, o.pose);
    progress.finish();
    res.truth_ms = ms_since(t0);
  }
  return res;
}

ColonCase colon_case(uint64_t seed) {
  ColonCase c;
  c.options.effects.seed = seed;
  c.options.pose.translation_mm = Vec3(0, 0, 12.0 * (static_cast<double>(seed) - 1));
  return c;
}

nlohmann::json simulation_summary(const SimulateSummary& r, const SimulateOptions& o, const Scene& scene,
                                  int shot) {
  nlohmann::json cams = nlohmann::json::array();
  for (size_t i = 0; i < r.frames.size(); ++i) {
    const auto& c = r.true_rig.cameras[i];
    const auto& g = r.frames[i].gains;
    double fit_err = 0;
    const Photometric ph = true_photometric(c, o.effects, &fit_err);
    cams.push_back({{"id", c.id},
                    {"width", c.in.width},
                    {"height", c.in.height},
                    {"gains_bgr", {g[0], g[1], g[2]}},
                    {"vignetting_fit", ph.vignetting},
                    {"vignetting_fit_max_error", fit_err}});
  }
  const auto& e = o.effects;
  return {
      {"format", "omma-sim"},
      {"version", 1},
      {"scene", scene.spec()},
      {"seed", e.seed},
      {"shot", shot},
      {"shots", o.shots},
      {"encoding", "srgb"},
      {"effects",
       {{"supersample", e.supersample},
        {"exposure", e.exposure},
        {"vignetting", e.vignetting},
        {"color_gain", e.color_gain},
        {"full_scale_electrons", e.full_scale_electrons},
        {"read_noise_dn", e.read_noise_dn},
        {"bits", e.bits}}},
      {"perturb",
       {{"orient_deg", o.perturb.orient_deg},
        {"focal_rel", o.perturb.focal_rel},
        {"center_px", o.perturb.center_px},
        {"k1", o.perturb.k1},
        {"pos_mm", o.perturb.position_mm}}},
      {"truth",
       o.truth
           ? nlohmann::json{{"projection", to_string(o.truth_grid.projection)},
                            {"width", o.truth_grid.width},
                            {"height", o.truth_grid.height},
                            {"depth", "truth_depth.tiff: float32 mm from the dome centre, inf = none"},
                            {"supersample", o.truth_supersample > 0 ? o.truth_supersample
                                                                    : auto_truth_supersample(o.truth_grid)}}
           : nlohmann::json(nullptr)},
      {"dome_translation_mm",
       {o.pose.translation_mm.x(), o.pose.translation_mm.y(), o.pose.translation_mm.z()}},
      {"raw", o.raw},
      {"cameras", cams},
      {"cameras_ms", r.cameras_ms},
      {"truth_ms", r.truth_ms}};
}

namespace {

// Writes one shot's frames folder into `target` (which exists).
void write_shot(const fs::path& target, const SimulateSummary& r, const SimulateOptions& o,
                const Scene& scene, int shot) {
  const std::vector<CameraFrame>& frames = shot == 0 ? r.frames : r.more_shots[size_t(shot - 1)];
  for (size_t i = 0; i < frames.size(); ++i) {
    const int id = r.true_rig.cameras[i].id;
    write_image(target / frame_filename(id), frames[i].image);
    if (o.raw) write_image(target / raw_frame_filename(id), frames[i].raw);
  }
  if (!r.truth.empty()) write_image(target / "truth.png", r.truth);
  if (!r.truth_depth.empty()) write_image(target / "truth_depth.tiff", r.truth_depth);
  save_rig(r.nominal, target / "rig.json");
  save_rig(r.true_rig, target / "rig_true.json");
  write_text_atomically(target / "sim.json", simulation_summary(r, o, scene, shot).dump(2) + "\n");
}

// Runs write(target) into `dir`: a fresh folder is written as a temporary sibling and renamed at the
// end (all or nothing); an existing folder is written in place.
template <typename Write>
void write_folder(const fs::path& dir, Write write) {
  if (fs::exists(dir) && !fs::is_directory(dir))
    throw IoError(fmt::format("output '{}' exists and is not a folder", dir.string()));
  const bool fresh = !fs::exists(dir);
  fs::path target = dir;
  if (fresh) {
    const fs::path parent = dir.has_parent_path() ? dir.parent_path() : fs::path(".");
    if (!fs::is_directory(parent))
      throw IoError(
          fmt::format("cannot create '{}': folder '{}' does not exist", dir.string(), parent.string()));
    target = parent / fmt::format(".{}.tmp-{}", dir.filename().string(), ::getpid());
    std::error_code ec;
    fs::remove_all(target, ec);
    if (!fs::create_directory(target, ec) || ec)
      throw IoError(fmt::format("cannot create folder '{}': {}", target.string(), ec.message()));
  }
  try {
    write(target);
    if (fresh) {
      std::error_code ec;
      fs::rename(target, dir, ec);
      if (ec)
        throw IoError(
            fmt::format("cannot rename '{}' to '{}': {}", target.string(), dir.string(), ec.message()));
    }
  } catch (...) {
    if (fresh) {
      std::error_code ec;
      fs::remove_all(target, ec);
    }
    throw;
  }
}

}  // namespace

void write_frames_folder(const fs::path& dir, const SimulateSummary& r, const SimulateOptions& o,
                         const Scene& scene) {
  write_folder(dir, [&](const fs::path& target) { write_shot(target, r, o, scene, 0); });
}

std::string shot_folder_name(int shot) { return fmt::format("shot_{:02d}", shot); }

void write_shots_folder(const fs::path& dir, const SimulateSummary& r, const SimulateOptions& o,
                        const Scene& scene) {
  write_folder(dir, [&](const fs::path& target) {
    for (int k = 0; k <= static_cast<int>(r.more_shots.size()); ++k) {
      const fs::path sub = target / shot_folder_name(k);
      std::error_code ec;
      fs::create_directories(sub, ec);
      if (ec) throw IoError(fmt::format("cannot create folder '{}': {}", sub.string(), ec.message()));
      write_shot(sub, r, o, scene, k);
    }
  });
}

}  // namespace omma::sim
