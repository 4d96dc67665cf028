// omma simulate: render every camera of a rig looking at a scene, plus the ground-truth panorama.
#include "omma/sim/simulate.h"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <vector>

#include <fmt/format.h>

#include "apps/command.h"
#include "omma/core/grid.h"
#include "omma/core/io.h"
#include "omma/core/parse.h"
#include "omma/core/rig.h"
#include "omma/design/prototype.h"

namespace omma::app {
namespace {

struct SimulateArgs {
  std::string rig, scene, out, truth_size = "1080x1080", projection = "vr180", perturb;
  bool raw = false, json = false, ideal = false, no_truth = false;
  uint64_t seed = 1;
  int supersample = 3, truth_supersample = 0, bits = 10, shots = 1;
  double vignetting = 0.5, color_gain = 0.10, electrons = 4000, read_noise = 2.0, exposure = 1.0;
  double dome_z = 0;
  std::string dome_at;  // "X,Y,Z" mm
};

// "--dome-at X,Y,Z": three numbers in mm, each within +-kMaxSceneMm.
Vec3 parse_dome_at(const std::string& text) {
  std::vector<double> v;
  size_t start = 0;
  while (true) {
    const size_t comma = text.find(',', start);
    const std::string part =
        text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const std::optional<double> x = parse_double(part);
    if (!x || !(std::abs(*x) <= sim::kMaxSceneMm))
      throw std::invalid_argument(fmt::format(
          "--dome-at must be X,Y,Z: three numbers of mm within +-{}, got '{}'", sim::kMaxSceneMm, text));
    v.push_back(*x);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (v.size() != 3)
    throw std::invalid_argument(fmt::format("--dome-at must be X,Y,Z (three numbers, mm), got '{}'", text));
  return Vec3(v[0], v[1], v[2]);
}

void run_simulate(const SimulateArgs& a) {
  set_json_mode(a.json);
  namespace fs = std::filesystem;
  const auto t0 = std::chrono::steady_clock::now();
  // Validate everything before rendering or writing anything.
  sim::SimulateOptions o;
  o.raw = a.raw;
  o.truth = !a.no_truth;
  const Size2 ts = parse_size(a.truth_size);
  o.truth_grid = PanoGrid{parse_projection(a.projection), ts.width, ts.height};
  o.truth_supersample = a.truth_supersample;
  if (a.truth_supersample < 0 || a.truth_supersample > 16)
    throw std::invalid_argument(
        fmt::format("--truth-supersample must be 0 (auto) or 1..16, got {}", a.truth_supersample));
  o.perturb = sim::parse_perturb(a.perturb);
  o.effects = a.ideal ? sim::CameraEffects::ideal(a.supersample) : sim::CameraEffects{};
  o.effects.supersample = a.supersample;
  o.effects.exposure = a.exposure;
  o.effects.seed = a.seed;
  if (!a.ideal) {
    o.effects.vignetting = a.vignetting;
    o.effects.color_gain = a.color_gain;
    o.effects.full_scale_electrons = a.electrons;
    o.effects.read_noise_dn = a.read_noise;
    o.effects.bits = a.bits;
  } else if (a.raw) {
    o.effects.bits = a.bits;
  }
  o.pose.translation_mm = a.dome_at.empty() ? Vec3(0, 0, a.dome_z) : parse_dome_at(a.dome_at);
  o.progress = !a.json;
  if (a.shots < 1 || a.shots > 1000)
    throw std::invalid_argument(fmt::format("--shots must be 1..1000, got {}", a.shots));
  o.shots = a.shots;
  if (fs::exists(a.out) && !fs::is_directory(a.out))
    throw IoError(fmt::format("--out '{}' exists and is not a folder", a.out));
  const Rig rig = a.rig.empty() ? design::thesis_prototype_rig() : design::load_rig_or_builtin(a.rig);
  if (rig.cameras.empty()) throw RigError(fmt::format("rig '{}' has no cameras", a.rig));
  const std::unique_ptr<sim::Scene> scene = sim::make_scene(a.scene);
  const sim::SimulateSummary res = sim::simulate(rig, *scene, o);
  if (a.shots > 1)
    sim::write_shots_folder(a.out, res, o, *scene);
  else
    sim::write_frames_folder(a.out, res, o, *scene);
  const double total_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (a.json) {
    nlohmann::json j = {
        {"out", a.out},
        {"scene", scene->spec()},
        {"cameras", rig.cameras.size()},
        {"camera_width", rig.cameras[0].in.width},
        {"camera_height", rig.cameras[0].in.height},
        {"truth",
         o.truth ? nlohmann::json{{"projection", a.projection}, {"width", ts.width}, {"height", ts.height}}
                 : nlohmann::json(nullptr)},
        {"raw", a.raw},
        {"seed", a.seed},
        {"shots", a.shots},
        {"perturbed", o.perturb.any()},
        {"cameras_ms", res.cameras_ms},
        {"truth_ms", res.truth_ms},
        {"ms", total_ms}};
    print_json(j);
  } else {
    std::cout << fmt::format(
        "{}: {} cameras ({}x{}){}{}{} of scene '{}' in {:.0f} ms\n", a.out, rig.cameras.size(),
        rig.cameras[0].in.width, rig.cameras[0].in.height,
        a.shots > 1 ? fmt::format(", {} shots (shot_00 .. shot_{:02d})", a.shots, a.shots - 1) : "",
        a.raw ? " + raw Bayer" : "",
        o.truth ? fmt::format(" + {} {}x{} truth", a.projection, ts.width, ts.height) : "", scene->spec(),
        total_ms);
  }
}

}  // namespace

void add_simulate_command(CLI::App& root) {
  static SimulateArgs a;
  auto* cmd = root.add_subcommand(
      "simulate",
      "Render every camera of a rig looking at a scene (the dome simulator) and the ideal panorama seen\n"
      "from the dome centre (ground truth). Writes the frames folder OUT: cam_XX.png (8-bit sRGB),\n"
      "cam_XX_raw.png (--raw: 16-bit RGGB Bayer, 10-bit values), truth.png, rig.json (nominal),\n"
      "rig_true.json (rendered, with --perturb errors), sim.json (what was simulated).");
  cmd->add_option(
      "--rig", a.rig,
      "Rig file (JSON, omma-rig) or built-in rig (thesis-24, gigaeye-44, gigaeye-44-skip1, ...); default: "
      "thesis-24");
  cmd->add_option(
         "--scene", a.scene,
         "Scene: photo:PATH (far-field 360x180 equirect photo), colon (procedural tube), "
         "usaf[:DIST_MM] (USAF 1951 chart, default 25 mm ahead), checker[:RADIUS_MM] (textured sphere, "
         "default 100 mm), tube[:DIAMETER_MM] (the thesis's textured calibration tube, default 35 mm), "
         "flat[:LEVEL] (uniformly lit white target, for flat-field photometric calibration), room (a "
         "corridor around the rig, objects 0.5-10 m, data/scenes/room.json built in), room:PATH.json (a room "
         "file of one's own, format in data/scenes/README.md)")
      ->required();
  cmd->add_option("--out", a.out, "Output frames folder (created; all or nothing)")->required();
  cmd->add_option("--truth-size", a.truth_size, "Ground-truth panorama size WxH (pixels)")
      ->capture_default_str();
  cmd->add_option(
         "--projection", a.projection,
         "Ground-truth grid: equirect (360x90 deg) | vr180 | equirect-full | equirect-100 (360x100 deg)")
      ->capture_default_str();
  cmd->add_flag("--no-truth", a.no_truth, "Do not render truth.png");
  cmd->add_flag("--raw", a.raw, "Also write 16-bit RGGB Bayer raw frames cam_XX_raw.png");
  cmd->add_option("--seed", a.seed, "Seed of noise, colour gains and perturbation")->capture_default_str();
  cmd->add_option("--perturb", a.perturb,
                  "Errors of the true rig, e.g. orient=0.5,focal=0.02,center=3,k1=-0.05,pos=0.1 (degrees, "
                  "relative, pixels, unitless, mm; exact magnitudes, random directions)");
  cmd->add_option("--supersample", a.supersample, "N: N x N rays per camera pixel (optical blur), 1..16")
      ->capture_default_str();
  cmd->add_option(
         "--truth-supersample", a.truth_supersample,
         "N x N rays per truth pixel, 1..16; 0 = auto: rays at most 0.09 deg apart (2 for vr180 1080x1080)")
      ->capture_default_str();
  cmd->add_option("--vignetting", a.vignetting, "Vignetting strength s in [0,1]: V = 1 - s (1 - cos^4 angle)")
      ->capture_default_str();
  cmd->add_option("--color-gain", a.color_gain, "Per-camera per-channel gain spread: gains in [1-g, 1+g]")
      ->capture_default_str();
  cmd->add_option("--full-well", a.electrons, "Electrons at full scale (shot noise); 0 = no shot noise")
      ->capture_default_str();
  cmd->add_option("--read-noise", a.read_noise, "Read noise sigma in quantiser steps (DN); 0 = none")
      ->capture_default_str();
  cmd->add_option("--bits", a.bits, "Quantiser bits 8..16, 0 = none")->capture_default_str();
  cmd->add_option("--exposure", a.exposure, "Scale of the scene radiance before the sensor")
      ->capture_default_str();
  cmd->add_flag("--ideal", a.ideal,
                "Ideal cameras: no vignetting, gains, noise or quantisation (--supersample still applies)");
  auto* dome_z = cmd->add_option("--dome-z", a.dome_z, "Move the dome along the scene z axis by this many mm")
                     ->capture_default_str();
  cmd->add_option(
         "--dome-at", a.dome_at,
         "Put the dome (the rig centre) at X,Y,Z mm in the scene frame, e.g. 1500,0,0 for 1.5 m along "
         "the room's corridor (the rig keeps its orientation)")
      ->excludes(dome_z);
  cmd->add_option(
         "--shots", a.shots,
         "Exposures of the (static) scene, 1..1000: the same rig and colour gains, fresh sensor noise per "
         "shot; with N > 1, OUT holds one frames folder per shot: OUT/shot_00 .. OUT/shot_<N-1>")
      ->capture_default_str();
  cmd->add_flag("--json", a.json, "Print one JSON summary on stdout");
  cmd->callback([] { run_simulate(a); });
}

}  // namespace omma::app
