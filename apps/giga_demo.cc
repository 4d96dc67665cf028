// omma demo --rig gigaeye-44: the Giga-Eye end to end (thesis ch. 7). The recording plan of Table
// 7.2, the coverage maps, a short simulated recording by the 44 free-running cameras (raw 12-bit,
// HDF5) of a rig whose cameras are off their nominal poses, its calibration from the recording's
// first frame set, and the 21.6 MP panoramas rendered from the recording with the calibrated rig,
// measured against the simulator's truth. Writes OUT/report.md and the pictures.
#include "apps/giga_demo.h"

#include <chrono>
#include <filesystem>
#include <iostream>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <opencv2/imgproc.hpp>

#include "apps/command.h"
#include "omma/calib/calibrate.h"
#include "omma/calib/rig_diff.h"
#include "omma/core/io.h"
#include "omma/core/log.h"
#include "omma/design/coverage.h"
#include "omma/design/dome.h"
#include "omma/design/prototype.h"
#include "omma/design/recording_plan.h"
#include "omma/io/pano_file.h"
#include "omma/io/tiff_writer.h"
#include "omma/live/recorder.h"
#include "omma/pano/quality.h"
#include "omma/render/pano_render.h"
#include "omma/sim/perturb.h"
#include "omma/sim/render.h"
#include "omma/sim/simulate.h"

namespace omma::app {
namespace fs = std::filesystem;

namespace {

using clock = std::chrono::steady_clock;
double secs(clock::time_point a) { return std::chrono::duration<double>(clock::now() - a).count(); }

// The report as it grows: Markdown for report.md and stdout, JSON for --json.
struct GigaReport {
  std::string md = "# omma demo: Giga-Eye (thesis ch. 7)\n\n";
  nlohmann::json js;
};

void plan_section(GigaReport& r) {
  std::string& md = r.md;
  nlohmann::json& js = r.js;
  // The plan of Table 7.2 (option 5): 44 cameras, 1296x972, 12 bit, 30 fps, 66 MHz, 17 min.
  const design::RecordingPlan plan = design::make_plan(design::plan_input(design::table71()[4]));
  md += fmt::format(
      "## Recording plan (Table 7.2)\n\n44 cameras 1296x972 at 30 fps, 12 bit: {:.2f} MiB/s per camera, "
      "{:.1f} MB/s per "
      "SSD (2 cameras, 150 MB/s), {:.3f} GB/s for the rig; a 128 GB SSD holds {:.1f} min (thesis: 17 min "
      "planned); "
      "{}.\n\n",
      plan.camera_mib_per_s, plan.device_bytes_per_s / 1e6, plan.rig_bytes_per_s / 1e9, plan.max_minutes,
      plan.feasible() ? "every constraint holds" : "FAILS: " + plan.failed());
  js["plan"] = {{"feasible", plan.feasible()},
                {"max_minutes", plan.max_minutes},
                {"rig_gb_per_s", plan.rig_bytes_per_s / 1e9}};
}

void coverage_section(const fs::path& dir, GigaReport& r) {
  std::string& md = r.md;
  nlohmann::json& js = r.js;
  // Coverage at 1 m and far away (Fig. 7.5).
  md +=
      "## Coverage (Fig. 7.5)\n\n| distance | >= 2 cameras, polar | cameras there | max "
      "|\n|---|---|---|---|\n";
  for (double d : {1000.0, design::kInfinity}) {
    const auto st = design::analyze_coverage(design::gigaeye_rig(), d, deg2rad(0.5), deg2rad(100));
    const auto band = st.polar_band(2);
    const std::string name = std::isinf(d) ? "inf" : "1m";
    md += fmt::format("| {} | {:.1f}..{:.1f} deg | {}..{} | {} |\n", name, rad2deg(band.from_rad),
                      rad2deg(band.to_rad), band.min_cameras, band.max_cameras, st.max_cameras);
    const cv::Mat counts =
        design::coverage_count_map(design::gigaeye_rig(), PanoGrid{Projection::kEquirect100, 1800, 500}, d);
    write_image(
        dir / ("coverage_" + name + ".png"),
        design::render_coverage_map(counts, fmt::format("gigaeye-44: cameras per direction at {}", name)));
    js["coverage"][name] = {{"band_from_deg", rad2deg(band.from_rad)},
                            {"band_to_deg", rad2deg(band.to_rad)},
                            {"max_cameras", st.max_cameras}};
  }
  md += "\n![coverage](coverage_inf.png)\n\n";
}

// The recording: 44 free-running cameras (the perturbed rig) delivering raw 12-bit frames at 2 fps.
// The simulator cannot render 44 cameras in real time on a small machine, so each camera replays its
// simulated raw frame (sensor noise, vignetting, gains; the scene stands still). Returns its folder.
fs::path recording_section(const GigaDemoOptions& o, const Rig& nominal, const Rig& truth_rig,
                           const sim::Scene& scene, const fs::path& dir, GigaReport& r) {
  std::string& md = r.md;
  nlohmann::json& js = r.js;
  const fs::path rec_dir = dir / "recording";
  fs::remove_all(rec_dir);
  auto t = clock::now();
  sim::SimulateOptions sopt;
  sopt.raw = true;
  sopt.truth = false;
  sopt.effects.supersample = 1;
  sopt.effects.bits = 12;
  sopt.effects.seed = o.seed;
  sopt.progress = !o.json;
  const sim::SimulateSummary sr = sim::simulate(truth_rig, scene, sopt);
  std::vector<std::unique_ptr<live::CameraSource>> sources;
  for (const auto& f : sr.frames) sources.push_back(live::still_source(f.raw, 2, o.frame_sets));
  live::RecordOptions ro;
  ro.frames = o.frame_sets;
  ro.fps = 2;
  ro.sensor_mode = o.mode;
  ro.clock_mhz = 66;
  ro.progress = !o.json;
  io::RecordingManifest m;
  m.rig = nominal;
  const auto rs = live::record(std::move(sources), rec_dir, m, ro);
  if (!rs.error.empty()) throw std::runtime_error("recording: " + rs.error);
  io::RecordingReader rec(rec_dir);
  md += fmt::format(
      "## Recording\n\n{} frame sets of 44 x {}x{} raw 12-bit frames in {:.1f} s ({:.1f} MB, HDF5, "
      "`omma recording check {}`): {} complete sets, {} frames dropped.\n\n",
      rec.frame_sets(), nominal.cameras[0].in.width, nominal.cameras[0].in.height, secs(t), rs.bytes / 1e6,
      rec_dir.string(), rec.match().complete_sets, [&] {
        int64_t d = 0;
        for (const auto& c : rec.match().cameras) d += c.dropped;
        return d;
      }());
  js["recording"] = {
      {"frame_sets", rec.frame_sets()}, {"complete_sets", rec.match().complete_sets}, {"seconds", secs(t)}};

  return rec_dir;
}

// Calibration from the first frame of every stream (far field: rotation only), against the true rig.
calib::CalibrationSummary calibration_section(const io::RecordingReader& rec, const Rig& nominal,
                                              const Rig& truth_rig, const sim::PerturbSpec& spec,
                                              const isp::IspOptions& iso, const fs::path& dir,
                                              GigaReport& r) {
  std::string& md = r.md;
  nlohmann::json& js = r.js;
  const auto t = clock::now();
  // The first frame of every stream (the scene stands still).
  std::vector<cv::Mat> raws;
  for (int c = 0; c < rec.cameras(); ++c) {
    if (rec.frames(c) == 0) throw std::runtime_error("camera " + std::to_string(c) + " recorded nothing");
    raws.push_back(rec.read(c, 0));
  }
  const std::vector<cv::Mat> developed = isp::develop_all(raws, iso);
  calib::CalibrationOptions co;
  co.scene = calib::SceneModel::kFar;
  const calib::CalibrationSummary cal = calib::calibrate_rig(nominal, developed, co);
  const calib::RigDiff before = calib::diff_rigs(nominal, truth_rig, true);
  const calib::RigDiff after = calib::diff_rigs(cal.rig, truth_rig, true);
  save_rig(cal.rig, dir / "rig_calibrated.json");
  md += fmt::format(
      "## Calibration (`omma calibrate`, far field, from the first frame of every stream)\n\nTrue rig: "
      "nominal + {}. Global rotation "
      "removed (`rig-diff --align`). Orientation error median {:.3f} deg (max {:.3f}), focal {:.3f} %, "
      "centre {:.2f} px, "
      "ray error {:.3f} deg (nominal rig: {:.3f} deg / ray {:.3f} deg); RMS {:.3f} px, {} tracks, {:.1f} s; "
      "{} "
      "camera(s) kept nominal for too few matches{}.\n\n",
      sim::to_string(spec), after.orientation_error_deg.median, after.orientation_error_deg.max,
      100 * after.focal_error_rel.median, after.center_error_px.median, after.ray_error_deg.median,
      before.orientation_error_deg.median, before.ray_error_deg.median, cal.rms_px, cal.tracks, secs(t),
      cal.uncalibrated_ids.size(),
      cal.uncalibrated_ids.empty() ? "" : fmt::format(" (ids {})", fmt::join(cal.uncalibrated_ids, ", ")));
  js["calibration"] = {{"orientation_median_deg", after.orientation_error_deg.median},
                       {"orientation_max_deg", after.orientation_error_deg.max},
                       {"focal_median_rel", after.focal_error_rel.median},
                       {"center_median_px", after.center_error_px.median},
                       {"ray_median_deg", after.ray_error_deg.median},
                       {"rms_px", cal.rms_px},
                       {"uncalibrated_ids", cal.uncalibrated_ids},
                       {"seconds", secs(t)}};

  return cal;
}

// The 21.6 MP panoramas from the recording with the calibrated rig (BigTIFF), against the truth.
void panorama_section(const io::RecordingReader& rec, const Rig& rig, const isp::IspOptions& iso,
                      const sim::Scene& scene, const Size2& size, const fs::path& dir, clock::time_point t0,
                      bool progress, GigaReport& r) {
  std::string& md = r.md;
  nlohmann::json& js = r.js;
  render::PanoRenderOptions po;
  po.grid = PanoGrid{Projection::kEquirect100, size.width, size.height};
  po.method = pano::Method::kMrf;
  po.progress = progress;
  render::PanoRenderer renderer(rig, po);
  // The complete frame sets (a camera missing from a set would leave its part black).
  std::vector<int64_t> sets;
  for (int64_t s = 0; s < rec.frame_sets(); ++s) {
    bool complete = true;
    for (int64_t f : rec.match().sets[s].frame) complete = complete && f >= 0;
    if (complete) sets.push_back(s);
  }
  if (sets.empty()) sets.push_back(0);
  double render_s = 0;
  for (int64_t s : sets)
    render_s += io::render_frame_set(rec, s, renderer, iso, dir / fmt::format("pano_{:05d}.tif", s)).render;
  const cv::Mat pano = io::read_tiff_rows(dir / fmt::format("pano_{:05d}.tif", sets[0]));
  const PanoGrid small{Projection::kEquirect100, 1800, 480};
  cv::Mat preview;
  cv::resize(pano, preview, cv::Size(small.width, small.height), 0, 0, cv::INTER_AREA);
  write_image(dir / "pano_preview.jpg", preview);
  const cv::Mat truth = sim::render_truth(scene, small, {}, 3);
  write_image(dir / "truth_preview.jpg", truth);
  const double psnr = pano::psnr_db(preview, truth);
  md += fmt::format(
      "## Panoramas\n\n{} panoramas of {}x{} ({:.1f} MP, mrf, 360 x 100 deg, BigTIFF `pano_XXXXX.tif`), maps "
      "{:.1f} s, "
      "render {:.2f} s each; memory {:.0f} MB. Against the truth (both at 1800x480): PSNR {:.2f} dB.\n\n"
      "![panorama](pano_preview.jpg)\n\n![truth](truth_preview.jpg)\n\nTotal {:.1f} s.\n",
      sets.size(), size.width, size.height, size.width * double(size.height) / 1e6, renderer.maps_seconds(),
      render_s / sets.size(), renderer.memory().total() / 1e6, psnr, secs(t0));
  js["panorama"] = {{"width", size.width},
                    {"height", size.height},
                    {"render_s", render_s / sets.size()},
                    {"maps_s", renderer.maps_seconds()},
                    {"psnr_db_preview", psnr},
                    {"memory_bytes", renderer.memory().total()}};
}

}  // namespace

void run_giga_demo(const GigaDemoOptions& opts) {
  set_json_mode(opts.json);
  GigaDemoOptions o = opts;
  if (o.scene.empty())
    o.scene = fs::exists("../shared/data/lake.jpg") ? "photo:../shared/data/lake.jpg" : "checker:50000";
  const auto t0 = clock::now();
  const Size2 size = parse_size(o.size);
  if (o.frame_sets < 1 || o.frame_sets > 100) throw std::invalid_argument("--frame-sets must be 1..100");
  const Rig nominal =
      design::load_rig_or_builtin("gigaeye-44" + (o.mode == "full" ? std::string() : "-" + o.mode));
  const sim::PerturbSpec spec = sim::parse_perturb(o.perturb);
  const Rig truth_rig = sim::perturb_rig(nominal, spec, o.seed);
  const fs::path dir = o.out;
  if (fs::exists(dir) && !fs::is_directory(dir)) throw IoError("--out '" + o.out + "' is not a folder");
  fs::create_directories(dir);
  GigaReport r;
  std::string& md = r.md;
  nlohmann::json& js = r.js;
  plan_section(r);
  coverage_section(dir, r);

  const auto scene = sim::make_scene(o.scene);
  io::RecordingReader rec(recording_section(o, nominal, truth_rig, *scene, dir, r));
  isp::IspOptions iso;
  iso.bits = 12;
  iso.srgb = true;
  const calib::CalibrationSummary cal = calibration_section(rec, nominal, truth_rig, spec, iso, dir, r);
  panorama_section(rec, cal.rig, iso, *scene, size, dir, t0, !o.json, r);
  js["seconds"] = secs(t0);
  write_text_atomically(dir / "report.md", md);
  if (o.json) {
    js["out"] = o.out;
    print_json(js);
  } else {
    std::cout << md << "\ndemo written to " << fs::absolute(dir).string() << "/ (report.md)\n";
  }
}

}  // namespace omma::app
