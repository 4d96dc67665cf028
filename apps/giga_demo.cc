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
#include "apps/sheet.h"
#include "apps/view3d.h"
#include "omma/calib/calibrate.h"
#include "omma/calib/rig_diff.h"
#include "omma/core/frames.h"
#include "omma/core/io.h"
#include "omma/core/log.h"
#include "omma/design/coverage.h"
#include "omma/design/dome.h"
#include "omma/design/prototype.h"
#include "omma/design/recording_plan.h"
#include "omma/io/depth_pano.h"
#include "omma/io/pano_file.h"
#include "omma/io/point_cloud.h"
#include "omma/io/tiff_writer.h"
#include "omma/live/recorder.h"
#include "omma/pano/maps.h"
#include "omma/pano/quality.h"
#include "omma/pano/refocus.h"
#include "omma/pano/surface.h"
#include "omma/render/pano_render.h"
#include "omma/sim/perturb.h"
#include "omma/sim/render.h"
#include "omma/sim/room.h"
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

// A preview of a panorama for measurement and pictures, area-averaged to the grid `small`
// (1800 x 480 in the far-field section, the panorama's size / 5 in the near one).
cv::Mat preview_of(const cv::Mat& full, const PanoGrid& small) {
  cv::Mat p;
  cv::resize(full, p, cv::Size(small.width, small.height), 0, 0, cv::INTER_AREA);
  return p;
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
  const cv::Mat preview = preview_of(pano, small);
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

// ---- Near scenes: parallax at Giga-Eye's scale, refocusing, 3D ------------------------------------

// A crop of each image around `centre` (full-size pixels), all the same size, labelled, 2 per row.
cv::Mat crops(const std::vector<cv::Mat>& images, const std::vector<std::string>& labels, const Vec2& centre,
              cv::Size size) {
  std::vector<cv::Mat> cut;
  for (const cv::Mat& image : images) {
    const cv::Rect full(0, 0, image.cols, image.rows);
    cv::Rect r(int(centre.x()) - size.width / 2, int(centre.y()) - size.height / 2, size.width, size.height);
    r.x = std::clamp(r.x, 0, full.width - r.width);
    r.y = std::clamp(r.y, 0, full.height - r.height);
    cut.push_back(image(r & full));
  }
  return labelled_sheet(cut, labels, 2);
}

// The rig's view of a room object: the direction of its centre.
Vec3 towards(const sim::RoomObject& ob) { return ob.centre.normalized(); }

void near_section(const GigaDemoOptions& o, const Rig& rig, const sim::Scene& scene, const Size2& size,
                  const fs::path& dir, GigaReport& r) {
  std::string& md = r.md;
  nlohmann::json& js = r.js;
  const auto t0 = clock::now();
  const PanoGrid full{Projection::kEquirect100, size.width, size.height};
  const PanoGrid small{Projection::kEquirect100, size.width / 5, size.height / 5};
  // The frames (noise, vignetting-free developed frames: the near section is about geometry) and the
  // truths: the ideal panorama and its depth at the preview size, the depth at the full size.
  sim::SimulateOptions so;
  so.truth = false;
  so.effects.supersample = 2;
  so.effects.seed = o.seed;
  so.effects.vignetting = 0;
  so.progress = !o.json;
  const sim::SimulateSummary sr = sim::simulate(rig, scene, so);
  std::vector<cv::Mat> frames;
  for (const auto& f : sr.frames) frames.push_back(f.image);
  const cv::Mat truth = sim::render_truth(scene, small, {}, 3);
  const cv::Mat truth_depth_small = sim::render_truth_depth(scene, small);
  const cv::Mat truth_depth = sim::render_truth_depth(scene, full);
  const double sim_s = secs(t0);
  write_image(dir / "near_truth.jpg", truth);
  const cv::Mat seam = pano::seam_mask(pano::coverage_map(rig, small), false);

  // Renders: infinity (the static maps), spheres, the estimate, the true depth.
  render::PanoRenderOptions po;
  po.grid = full;
  po.method = pano::Method::kMrf;
  po.progress = !o.json;
  render::PanoRenderer at_inf(rig, po);
  at_inf.set_frames(frames);
  auto t = clock::now();
  const cv::Mat inf_full = at_inf.render_image();
  const double static_s = secs(t);
  po.depth = true;
  po.estimate_depth = true;
  po.cache_dir.clear();
  t = clock::now();
  render::PanoRenderer deep(rig, po);
  const double depth_maps_s = secs(t);
  deep.set_frames(frames);  // estimates the depth
  const double estimate_s = deep.estimate_seconds();
  const cv::Mat coarse_inverse = deep.coarse_inverse().clone();
  t = clock::now();
  const cv::Mat est_full = deep.render_image();
  const double depth_render_s = secs(t);
  struct Row {
    std::string name;
    cv::Mat full, small;
    double psnr = 0, seam_psnr = 0;
  };
  std::vector<Row> rows;
  auto add = [&](const std::string& name, const cv::Mat& img) {
    Row row{name, img, preview_of(img, small)};
    row.psnr = pano::psnr_db(row.small, truth);
    row.seam_psnr = pano::psnr_db(row.small, truth, seam);
    rows.push_back(row);
  };
  add("infinity", inf_full);
  size_t best = 0;
  for (double radius : {1000.0, 2000.0, 4000.0}) {
    deep.set_depth(pano::sphere_depth(rig, deep.coarsest_grid(), radius));  // one distance
    add(fmt::format("sphere {:.0f} m", radius / 1000), deep.render_image());
    if (rows.back().psnr > rows[best].psnr || best == 0) best = rows.size() - 1;
  }
  add("estimated depth", est_full);
  deep.set_depth(truth_depth);
  add("true depth", deep.render_image());
  const Row& b = rows[best];
  const Row& e = rows[rows.size() - 2];
  const Row& tr = rows.back();
  const double closes = (e.psnr - b.psnr) / (tr.psnr - b.psnr),
               closes_seam = (e.seam_psnr - b.seam_psnr) / (tr.seam_psnr - b.seam_psnr);
  md += fmt::format(
      "## A near scene: depth at Giga-Eye's scale\n\nScene `{}` ({}), {} cameras {}x{}, rendered at {}x{} "
      "({:.1f} "
      "MP) and measured at {}x{} against the ideal panorama (PSNR, whole and seam band; the cameras' "
      "pinholes "
      "are 200 mm from the centre, so a near object lands at different places in neighbouring cameras).\n\n"
      "| surface | PSNR dB | seam band dB |\n|---|---|---|\n",
      scene.spec(), "data/scenes/room.json", rig.cameras.size(), rig.cameras[0].in.width,
      rig.cameras[0].in.height, full.width, full.height, full.width * double(full.height) / 1e6, small.width,
      small.height);
  nlohmann::json jr = nlohmann::json::array();
  for (const Row& row : rows) {
    md += fmt::format("| {}{} | {:.2f} | {:.2f} |\n", row.name, &row == &b ? " (best sphere)" : "", row.psnr,
                      row.seam_psnr);
    jr.push_back({{"surface", row.name}, {"psnr_db", row.psnr}, {"seam_psnr_db", row.seam_psnr}});
  }
  md += fmt::format(
      "\nThe estimate closes {:.0f} % of the gap between the best sphere and the true depth ({:.0f} % in the "
      "seam "
      "band; target 70 %). Times: simulation {:.1f} s; static render {:.2f} s; depth band maps {:.1f} s "
      "(once "
      "per rig and size); per panorama the estimate {:.2f} s ({}x{} grid, {} candidates) + the depth render "
      "{:.2f} s = {:.2f} panoramas/s.\n\n",
      100 * closes, 100 * closes_seam, sim_s, static_s, depth_maps_s, estimate_s, coarse_inverse.cols,
      coarse_inverse.rows, po.sweep.steps, depth_render_s, 1 / (estimate_s + depth_render_s));
  // Pictures: the whole previews, the crops where parallax shows, the depth maps.
  write_image(dir / "near_infinity.jpg", rows[0].small);
  write_image(dir / "near_best_sphere.jpg", b.small);
  write_image(dir / "near_estimate.jpg", e.small);
  write_image(dir / "near_true_depth.jpg", tr.small);
  cv::Mat est_depth_small;
  {
    cv::Mat inv;
    cv::resize(coarse_inverse, inv, cv::Size(small.width, small.height), 0, 0, cv::INTER_LINEAR);
    est_depth_small = cv::Mat(inv.size(), CV_32FC1);
    for (int y = 0; y < inv.rows; ++y)
      for (int x = 0; x < inv.cols; ++x) {
        const float v = inv.at<float>(y, x);
        est_depth_small.at<float>(y, x) = v > 0 ? 1 / v : std::numeric_limits<float>::infinity();
      }
  }
  write_image(dir / "near_depth_estimate.png",
              pano::depth_colormap(est_depth_small, 400, 10000, "estimated depth"));
  write_image(dir / "near_depth_truth.png",
              pano::depth_colormap(truth_depth_small, 400, 10000, "true depth"));
  const auto objects = sim::room_objects(scene);
  Vec2 crop_at(full.width / 2.0, full.height / 2.0);
  for (const auto& ob : objects)
    if (ob.type == "grid")
      if (const auto px = full.pixel(towards(ob))) crop_at = *px;
  write_image(dir / "near_crops.jpg",
              crops({rows[0].full, b.full, e.full, tr.full},
                    {"infinity", b.name + " (best sphere)", "estimated depth", "true depth"}, crop_at,
                    cv::Size(std::min(900, full.width), std::min(600, full.height))));
  md +=
      "![near: crops](near_crops.jpg)\n\n| infinity | estimated depth |\n|---|---|\n"
      "| ![](near_infinity.jpg) | ![](near_estimate.jpg) |\n\n"
      "![estimated depth](near_depth_estimate.png)\n\n![true depth](near_depth_truth.png)\n\n";
  js["near"] = {{"scene", scene.spec()},
                {"rows", jr},
                {"closes", closes},
                {"closes_seam", closes_seam},
                {"static_render_s", static_s},
                {"depth_maps_s", depth_maps_s},
                {"estimate_s", estimate_s},
                {"depth_render_s", depth_render_s},
                {"panoramas_per_s_with_depth", 1 / (estimate_s + depth_render_s)}};

  // Refocusing at the preview size: a focal stack on the room's targets, edge widths, the grid.
  t = clock::now();
  pano::RefocusOptions ro;
  ro.grid = small;
  ro.progress = false;
  std::vector<std::pair<std::string, double>> focus;
  const sim::RoomObject *edge_near = nullptr, *edge_far = nullptr, *grid = nullptr, *grid_target = nullptr;
  for (const auto& ob : objects) {
    if (ob.pattern == "edge" && (!edge_near || ob.centre.norm() < edge_near->centre.norm())) edge_near = &ob;
    if (ob.pattern == "edge" && (!edge_far || ob.centre.norm() > edge_far->centre.norm())) edge_far = &ob;
    if (ob.type == "grid") grid = &ob;
  }
  if (grid)  // the card behind the grid: the nearest card on the grid's axis beyond it
    for (const auto& ob : objects)
      if (ob.type == "card" && &ob != grid && ob.centre.norm() > grid->centre.norm() &&
          towards(ob).dot(towards(*grid)) > std::cos(deg2rad(10)) &&
          (!grid_target || ob.centre.norm() < grid_target->centre.norm()))
        grid_target = &ob;
  std::vector<cv::Mat> stack;
  std::vector<std::string> labels;
  nlohmann::json jf = nlohmann::json::array();
  md +=
      "## Synthetic-aperture refocusing (`omma refocus`)\n\nEvery camera that sees a direction's point on "
      "the "
      "focal sphere, averaged (aperture: all of them). Edge 10-90 % widths in preview pixels (0.2 deg):\n\n"
      "| focus | near edge | far edge |\n|---|---|---|\n";
  auto width_at = [&](const cv::Mat& img, const sim::RoomObject* ob) {
    if (!ob) return std::numeric_limits<double>::quiet_NaN();
    const auto px = small.pixel(towards(*ob));
    if (!px) return std::numeric_limits<double>::quiet_NaN();
    const cv::Rect roi(int(px->x()) - 20, int(px->y()) - 20, 40, 40);
    if ((roi & cv::Rect(0, 0, img.cols, img.rows)) != roi) return std::numeric_limits<double>::quiet_NaN();
    return pano::edge_width_10_90(img, roi);
  };
  std::vector<double> fs_mm;
  if (edge_near) fs_mm.push_back(edge_near->centre.norm());
  if (grid_target) fs_mm.push_back(grid_target->centre.norm());
  if (edge_far) fs_mm.push_back(edge_far->centre.norm());
  fs_mm.push_back(std::numeric_limits<double>::infinity());
  for (double f : fs_mm) {
    ro.focus_mm = f;
    const cv::Mat img = to_u8(pano::refocus(rig, frames, ro).image);
    const double wn = width_at(img, edge_near), wf = width_at(img, edge_far);
    const std::string label = std::isinf(f) ? "focus inf" : fmt::format("focus {:.2f} m", f / 1000);
    auto px_text = [](double w) {
      return std::isnan(w) ? std::string("> 30 px") : fmt::format("{:.1f} px", w);
    };
    md += fmt::format("| {} | {} | {} |\n", label, px_text(wn), px_text(wf));
    jf.push_back({{"focus_mm", std::isinf(f) ? -1.0 : f}, {"near_edge_px", wn}, {"far_edge_px", wf}});
    stack.push_back(img);
    labels.push_back(label);
  }
  js["refocus"] = {{"stack", jf}};
  // Seeing through the grid: the card behind it, refocused with and without the grid in the scene.
  if (grid && grid_target && scene.spec() == "room") {
    nlohmann::json room = nlohmann::json::parse(sim::default_room_json());
    nlohmann::json kept = nlohmann::json::array();
    for (const auto& ob : room["objects"])
      if (ob.value("type", "") != "grid") kept.push_back(ob);
    room["objects"] = kept;
    const auto clear_scene =
        sim::make_room_scene_from_text(room.dump(), "the room without its grid", "room-no-grid");
    sim::SimulateOptions cs = so;
    cs.progress = false;
    const sim::SimulateSummary cr = sim::simulate(rig, *clear_scene, cs);
    std::vector<cv::Mat> clear;
    for (const auto& f : cr.frames) clear.push_back(f.image);
    const auto c = small.pixel(towards(*grid_target));
    const double half_deg = rad2deg(
        std::atan(0.4 * std::min(grid_target->size.x(), grid_target->size.y()) / grid_target->centre.norm()));
    const int half = int(half_deg / 0.2);
    const cv::Rect roi = cv::Rect(int(c->x()) - half, int(c->y()) - half, 2 * half, 2 * half) &
                         cv::Rect(0, 0, small.width, small.height);
    ro.focus_mm = grid_target->centre.norm();
    md += fmt::format(
        "\nThe card {:.2f} m away behind the grid ({} mm bars every {} mm, {:.2f} m away): PSNR of its "
        "region against the same refocus without the grid:\n\n| aperture | combine | PSNR dB "
        "|\n|---|---|---|\n",
        grid_target->centre.norm() / 1000, grid->bar_mm, grid->pitch_mm, grid->centre.norm() / 1000);
    nlohmann::json jg = nlohmann::json::array();
    for (auto [aperture, comb] :
         {std::pair{0.0, pano::RefocusCombine::kMean},
          std::pair{std::numeric_limits<double>::infinity(), pano::RefocusCombine::kMean},
          std::pair{std::numeric_limits<double>::infinity(), pano::RefocusCombine::kMedian}}) {
      ro.aperture_mm = aperture;
      ro.combine = comb;
      const cv::Mat with = pano::refocus(rig, frames, ro).image,
                    without = pano::refocus(rig, clear, ro).image;
      const double p = pano::psnr_db(with(roi), without(roi));
      const std::string name = aperture == 0 ? "0 (nearest camera)" : "inf (all)";
      md += fmt::format("| {} | {} | {:.2f} |\n", name, pano::to_string(comb), p);
      jg.push_back({{"aperture", name}, {"combine", pano::to_string(comb)}, {"psnr_db", p}});
      if (aperture > 0) {
        stack.push_back(to_u8(with));
        labels.push_back("behind the grid, " + pano::to_string(comb));
      }
    }
    js["refocus"]["grid"] = jg;
    ro.aperture_mm = std::numeric_limits<double>::infinity();
    ro.combine = pano::RefocusCombine::kMean;
  }
  write_image(dir / "near_refocus_stack.jpg", labelled_sheet(stack, labels, 1));  // the stack as one picture
  md += fmt::format("\n![refocus stack](near_refocus_stack.jpg)\n\nRefocusing: {:.1f} s.\n\n", secs(t));

  // 3D: the estimated depth as a point cloud and a depth panorama.
  const cv::Mat colour = e.small;
  const io::PointCloud cloud = io::depth_to_points(est_depth_small, colour, small);
  io::write_ply(dir / "near_cloud.ply", cloud);
  io::write_depth_png(dir / "near_depth.png", est_depth_small, small);
  const View3dPage page =
      write_view3d_page(dir / "near_cloud.ply", dir / "near_3d", 2000000, 2, "omma: the room in 3D");
  md += fmt::format(
      "## 3D\n\nThe estimated depth as a coloured point cloud, `near_cloud.ply` ({} points, mm in the rig "
      "frame), "
      "shown in `near_3d/index.html` (three.js, works offline: drag to turn, wheel to zoom; `omma view3d`), "
      "and "
      "as a 16-bit 360-degree depth panorama `near_depth.png` (mm, GDepth and GPano XMP).\n\n",
      cloud.size());
  js["near"]["page"] = page.index.string();
  js["near"]["cloud_points"] = cloud.size();
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
  // A near scene (a room): parallax, depth, refocusing and 3D with the nominal rig. The recording and
  // the calibration of the far-field demo assume a far scene (rotation-only calibration).
  if (!sim::room_objects(*scene).empty()) {
    near_section(o, nominal, *scene, size, dir, r);
  } else {
    io::RecordingReader rec(recording_section(o, nominal, truth_rig, *scene, dir, r));
    isp::IspOptions iso;
    iso.bits = 12;
    iso.srgb = true;
    const calib::CalibrationSummary cal = calibration_section(rec, nominal, truth_rig, spec, iso, dir, r);
    panorama_section(rec, cal.rig, iso, *scene, size, dir, t0, !o.json, r);
  }
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
