// omma demo: the README's main job. The thesis's 24-camera dome (§3.4.2) inside the simulated colon,
// the 24 camera frames side by side (as Fig. 3.12b), the 180x180 panorama by every blending method
// (§2.4.2, ch. 4) measured against the simulator's ground truth, the object boundary overlay
// (eq. 4.12-4.16), the single-camera and coverage maps, the inter-camera PSNR (eq. 4.19-4.21) and an
// HTML + Markdown report that shows them.
#include <chrono>
#include <filesystem>
#include <iostream>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "apps/command.h"
#include "apps/demo_depth.h"
#include "apps/giga_demo.h"
#include "omma/bench/bench.h"
#include "omma/calib/photometric.h"
#include "omma/core/frames.h"
#include "omma/core/io.h"
#include "omma/core/log.h"
#include "omma/core/progress.h"
#include "omma/design/coverage.h"
#include "omma/design/prototype.h"
#include "omma/io/metadata.h"
#include "omma/isp/photometric.h"
#include "omma/pano/maps.h"
#include "omma/pano/quality.h"
#include "omma/pano/stitch.h"
#include "omma/render/compiled_map.h"
#include "omma/render/render.h"
#include "omma/sim/simulate.h"

namespace omma::app {
namespace {
namespace fs = std::filesystem;

struct DemoOptions {
  std::string out = "omma-demo";
  std::string scene = "colon";
  std::string size = "1080x1080";
  std::string projection = "vr180";
  double threshold = 0.15;
  unsigned seed = 1;
  bool json = false;
};

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// The camera frames tiled in a grid with their ids, like the side-by-side capture of Fig. 3.12b.
cv::Mat frame_mosaic(const Rig& rig, const std::vector<cv::Mat>& frames) {
  const int n = static_cast<int>(frames.size());
  const int cols = std::min(n, 6), rows = (n + cols - 1) / cols;
  int cw = 0, ch = 0;
  for (const auto& f : frames) {
    cw = std::max(cw, f.cols);
    ch = std::max(ch, f.rows);
  }
  const int gap = 4;
  cv::Mat mosaic(rows * (ch + gap) + gap, cols * (cw + gap) + gap, CV_8UC3, cv::Scalar(40, 40, 40));
  for (int i = 0; i < n; ++i) {
    const int x = gap + (i % cols) * (cw + gap), y = gap + (i / cols) * (ch + gap);
    frames[i].copyTo(mosaic(cv::Rect(x, y, frames[i].cols, frames[i].rows)));
    cv::putText(mosaic, std::to_string(rig.cameras[i].id), {x + 6, y + 22}, cv::FONT_HERSHEY_SIMPLEX, 0.7,
                cv::Scalar(255, 255, 255), 2, cv::LINE_AA);
  }
  return mosaic;
}

// The real-time engine on the same frames (thesis ch. 5): compiled mrf map, fast renderer, its
// agreement with the reference stitch and its speed.
struct EngineRow {
  double compile_s = 0;
  double fps = 0;  // all threads (bench::measure_fps)
  double psnr_vs_reference = 0;
  double bytes_per_pixel = 0;
};

EngineRow run_engine(const Rig& rig, const PanoGrid& grid, const std::vector<cv::Mat>& frames,
                     const cv::Mat& reference_mrf) {
  EngineRow e;
  render::MapOptions mo;
  mo.grid = grid;
  mo.method = pano::Method::kMrf;
  const auto t0 = std::chrono::steady_clock::now();
  const render::CompiledMap map = render::compile_map(rig, mo);
  e.compile_s = ms_since(t0) / 1000;
  e.bytes_per_pixel = map.bytes_per_pixel();
  render::FrameStore store(map.layout);
  for (size_t c = 0; c < frames.size(); ++c) store.set(int(c), frames[c]);
  cv::Mat out;
  const bench::Workload w{"omma-mrf", 0, [&] { render::render(map, store, out); }, {}};
  e.fps = bench::measure_fps(w, 0.2, 20);
  e.psnr_vs_reference = render::psnr_u8(out, reference_mrf);
  return e;
}

struct MethodRow {
  std::string method;
  pano::EvalSummary eval;
  double ms = 0;
};

// ---- Photometric calibration: its own section, before / after ------------------------------------
// The vignetting and colour gains estimated from the demo's own frames (the overlaps between
// cameras, calib/photometric.h), compared with the simulator's truth, and every method stitched
// again from the corrected frames (isp/photometric.h), against the same ground truth.
struct PhotometricDemo {
  calib::PhotometricSummary summary;
  double seconds = 0;
  double gain_error_max = 0, falloff_error_max = 0;  // against the simulator's truth (per-channel gauge)
  std::vector<MethodRow> after;                      // the same methods on the corrected frames
};

PhotometricDemo photometric_demo(const fs::path& dir, const Rig& rig, const std::vector<cv::Mat>& frames,
                                 const sim::SimulateSummary& simr, const sim::CameraEffects& effects,
                                 const PanoGrid& grid, const cv::Mat& seam, bool progress) {
  PhotometricDemo d;
  const auto t0 = std::chrono::steady_clock::now();
  d.summary = calib::calibrate_photometric(rig, {frames});
  d.seconds = ms_since(t0) / 1000;
  // Against the truth: gains up to one scale per channel, falloff over every pixel.
  const size_t n = rig.cameras.size();
  std::array<double, 3> le{}, lt{};
  for (size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) {
      le[k] += std::log(d.summary.rig.cameras[i].photometric->gains[k]) / n;
      lt[k] += std::log(simr.frames[i].gains[k]) / n;
    }
  for (size_t i = 0; i < n; ++i) {
    const RigCamera& c = simr.true_rig.cameras[i];
    const Photometric& p = *d.summary.rig.cameras[i].photometric;
    for (int k = 0; k < 3; ++k)
      d.gain_error_max = std::max(
          d.gain_error_max,
          std::abs(std::exp(std::log(p.gains[k]) - le[k] - std::log(simr.frames[i].gains[k]) + lt[k]) - 1));
    for (int r = 0; r < c.in.height; r += 3)
      for (int col = 0; col < c.in.width; col += 3)
        d.falloff_error_max = std::max(
            d.falloff_error_max, std::abs(vignetting_falloff(p, c.in.width, c.in.height, col + 0.5, r + 0.5) /
                                              sim::true_falloff(c, effects, Vec2(col + 0.5, r + 0.5)) -
                                          1));
  }
  save_rig(d.summary.rig, dir / "rig_photometric.json");
  const std::vector<cv::Mat> corrected = isp::correct_frames(d.summary.rig, frames);
  for (pano::Method m : pano::all_methods()) {
    pano::StitchOptions opt;
    opt.method = m;
    opt.grid = grid;
    opt.progress = progress;
    const auto t1 = std::chrono::steady_clock::now();
    const cv::Mat p = pano::stitch(rig, corrected, opt);
    MethodRow row{pano::to_string(m), {}, ms_since(t1)};
    row.eval = pano::evaluate(p, simr.truth, seam);
    if (m == pano::Method::kMrf) io::write_panorama(dir / "pano_mrf_photometric.png", to_u8(p), grid);
    d.after.push_back(row);
  }
  return d;
}

// The section of the report (Markdown; the HTML gets the same table).
std::string photometric_markdown(const PhotometricDemo& d, const std::vector<MethodRow>& before) {
  std::string md = fmt::format(
      "## Photometric calibration (vignetting and colour gains)\n\n"
      "Estimated from the overlaps of these frames alone ({} samples over {} camera pairs, {:.1f} s; RMS of "
      "the "
      "log ratio {:.3f} -> {:.3f}), stored in `rig_photometric.json`. Against the simulator's truth: gains "
      "within "
      "{:.2f} % (one scale per channel), falloff within {:.2f} % over every pixel. The same methods on the "
      "corrected frames:\n\n| method | PSNR before (dB) | PSNR after (dB) | SSIM before | SSIM after |\n"
      "|---|---|---|---|---|\n",
      d.summary.samples, d.summary.pairs, d.seconds, d.summary.initial_rms_log, d.summary.rms_log,
      100 * d.gain_error_max, 100 * d.falloff_error_max);
  for (size_t i = 0; i < before.size() && i < d.after.size(); ++i)
    md +=
        fmt::format("| {} | {:.2f} | {:.2f} | {:.4f} | {:.4f} |\n", before[i].method, before[i].eval.psnr_db,
                    d.after[i].eval.psnr_db, before[i].eval.ssim, d.after[i].eval.ssim);
  md += "\nBefore: ![mrf before](pano_mrf.png) After: ![mrf after](pano_mrf_photometric.png)\n";
  return md;
}

std::string photometric_html(const PhotometricDemo& d, const std::vector<MethodRow>& before) {
  std::string html = fmt::format(
      "<h2>Photometric calibration</h2><p>Vignetting and colour gains estimated from the overlaps of these "
      "frames "
      "({} samples, {} pairs, {:.1f} s), within {:.2f} % (gains) and {:.2f} % (falloff) of the simulator's "
      "truth."
      "</p><table><tr><th>method</th><th>PSNR before</th><th>PSNR after</th><th>SSIM before</th>"
      "<th>SSIM after</th></tr>",
      d.summary.samples, d.summary.pairs, d.seconds, 100 * d.gain_error_max, 100 * d.falloff_error_max);
  for (size_t i = 0; i < before.size() && i < d.after.size(); ++i)
    html += fmt::format("<tr><td>{}</td><td>{:.2f}</td><td>{:.2f}</td><td>{:.4f}</td><td>{:.4f}</td></tr>",
                        before[i].method, before[i].eval.psnr_db, d.after[i].eval.psnr_db,
                        before[i].eval.ssim, d.after[i].eval.ssim);
  html +=
      "</table><div class=\"row\"><div><h3>mrf before</h3><img src=\"pano_mrf.png\"></div><div><h3>mrf after"
      "</h3><img src=\"pano_mrf_photometric.png\"></div></div>";
  return html;
}

void write_report(const fs::path& dir, const DemoOptions& o, const Rig& rig,
                  const std::vector<MethodRow>& rows, const EngineRow& eng, double inter_psnr, double r_vir,
                  double total_s, const DepthDemo& depth, const PhotometricDemo& ph) {
  const std::string engine_text = fmt::format(
      "The real-time engine (`omma run`) renders the same mrf panorama from a compiled map ({:.1f} bytes per "
      "output pixel, compiled in {:.2f} s) at {:.0f} panoramas/s on this machine ({:.0f}x the thesis FPGA's "
      "25 fps); "
      "it matches the reference stitch to {:.1f} dB PSNR.",
      eng.bytes_per_pixel, eng.compile_s, eng.fps, eng.fps / 25, eng.psnr_vs_reference);
  std::string md = fmt::format(
      "# omma demo report\n\n"
      "Rig: `{}`, {} cameras of {}x{} px, AOV {:.0f} deg, on a {} mm dome (R_vir = {:.1f} mm).  \n"
      "Scene: `{}` (simulated, seed {}), panorama {} {}. Total time {:.1f} s.\n\n"
      "## Camera frames\n\n![frames](frames_mosaic.png)\n\n"
      "## Panorama (MRF, eq. 4.8-4.9)\n\n![panorama](pano_mrf.png)\n\n"
      "## Object boundaries (eq. 4.12-4.16, threshold {:.2f})\n\n![boundary](boundary_overlay.png)\n\n"
      "## Directions seen by one camera (white) / several (black)\n\n![single](single_camera.png)\n\n"
      "## Coverage count\n\n![coverage](coverage.png)\n\n"
      "## Every blending method against the ground truth\n\n"
      "Inter-camera PSNR (eq. 4.19-4.21): **{:.2f} dB** (the thesis reports 23.55 dB on its real dome).\n\n"
      "| method | PSNR (dB) | SSIM | seam PSNR (dB) | time (ms) |\n|---|---|---|---|---|\n",
      rig.name, rig.cameras.size(), rig.cameras[0].in.width, rig.cameras[0].in.height,
      rad2deg(rig.cameras[0].in.aov), rig.dome.radius_mm, r_vir, o.scene, o.seed, o.projection, o.size,
      total_s, o.threshold, inter_psnr);
  for (const auto& r : rows)
    md += fmt::format("| {} | {:.2f} | {:.4f} | {:.2f} | {:.0f} |\n", r.method, r.eval.psnr_db, r.eval.ssim,
                      r.eval.seam_psnr_db, r.ms);
  md +=
      "\nGround truth: the ideal panorama from the dome centre, rendered noise-free by the simulator "
      "(truth.png). Seam PSNR: the directions seen by two or more cameras. Times: the plain reference "
      "stitcher (pano::stitch).\n\n" +
      photometric_markdown(ph, rows) + "\n## Real-time engine (thesis ch. 5)\n\n" + engine_text + "\n\n" +
      depth.markdown;
  write_text_atomically(dir / "report.md", md);

  std::string html =
      "<!doctype html><html><head><meta charset=\"utf-8\"><title>omma demo report</title><style>"
      "body{font-family:sans-serif;max-width:1200px;margin:auto;background:#fafafa}"
      "img{max-width:100%;border:1px solid #ccc}table{border-collapse:collapse}"
      "td,th{border:1px solid #999;padding:4px 10px;text-align:right}th{background:#eee}"
      ".row{display:flex;gap:12px}.row>div{flex:1}</style></head><body>";
  html += fmt::format(
      "<h1>omma demo report</h1><p>Rig <code>{}</code>: {} cameras, {} mm dome, R_vir {:.1f} mm. "
      "Scene <code>{}</code>. Panorama {} {}. Total {:.1f} s.</p>",
      rig.name, rig.cameras.size(), rig.dome.radius_mm, r_vir, o.scene, o.projection, o.size, total_s);
  html += "<h2>Camera frames</h2><img src=\"frames_mosaic.png\">";
  html +=
      "<div class=\"row\"><div><h2>Panorama (MRF)</h2><img src=\"pano_mrf.png\"></div>"
      "<div><h2>Ground truth</h2><img src=\"truth.png\"></div></div>";
  html += fmt::format(
      "<div class=\"row\"><div><h2>Object boundaries (threshold {:.2f})</h2>"
      "<img src=\"boundary_overlay.png\"></div><div><h2>Boundary map</h2>"
      "<img src=\"boundary.png\"></div></div>",
      o.threshold);
  html +=
      "<div class=\"row\"><div><h2>Single-camera directions</h2><img src=\"single_camera.png\"></div>"
      "<div><h2>Coverage count</h2><img src=\"coverage.png\"></div></div>";
  html += fmt::format(
      "<h2>Blending methods against the ground truth</h2><p>Inter-camera PSNR "
      "(eq. 4.19-4.21): <b>{:.2f} dB</b></p><table><tr><th>method</th><th>PSNR (dB)</th>"
      "<th>SSIM</th><th>seam PSNR (dB)</th><th>time (ms)</th><th>panorama</th></tr>",
      inter_psnr);
  for (const auto& r : rows)
    html += fmt::format(
        "<tr><td>{0}</td><td>{1:.2f}</td><td>{2:.4f}</td><td>{3:.2f}</td><td>{4:.0f}</td>"
        "<td><a href=\"pano_{0}.png\">image</a></td></tr>",
        r.method, r.eval.psnr_db, r.eval.ssim, r.eval.seam_psnr_db, r.ms);
  html += "</table><p>Times: the plain reference stitcher (pano::stitch).</p>" + photometric_html(ph, rows) +
          "<h2>Real-time engine</h2><p>" + engine_text + "</p>" + depth.html + "</body></html>\n";
  write_text_atomically(dir / "report.html", html);
}

nlohmann::json photometric_json(const PhotometricDemo& d, const std::vector<MethodRow>& before) {
  nlohmann::json m = nlohmann::json::object();
  for (size_t i = 0; i < before.size() && i < d.after.size(); ++i)
    m[before[i].method] = {{"psnr_before_db", before[i].eval.psnr_db},
                           {"psnr_after_db", d.after[i].eval.psnr_db},
                           {"ssim_before", before[i].eval.ssim},
                           {"ssim_after", d.after[i].eval.ssim}};
  return {{"samples", d.summary.samples},
          {"pairs", d.summary.pairs},
          {"seconds", d.seconds},
          {"rms_log", d.summary.rms_log},
          {"initial_rms_log", d.summary.initial_rms_log},
          {"gain_error_max", d.gain_error_max},
          {"falloff_error_max", d.falloff_error_max},
          {"methods", m}};
}

std::string photometric_text(const PhotometricDemo& d, const std::vector<MethodRow>& before) {
  std::string t = fmt::format(
      "photometric calibration from the overlaps ({:.1f} s): gains within {:.2f} %, falloff "
      "within {:.2f} % of the truth; PSNR before -> after:",
      d.seconds, 100 * d.gain_error_max, 100 * d.falloff_error_max);
  for (size_t i = 0; i < before.size() && i < d.after.size(); ++i)
    t += fmt::format(" {} {:.2f} -> {:.2f}", before[i].method, before[i].eval.psnr_db,
                     d.after[i].eval.psnr_db);
  return t + "\n";
}

void run_demo(const DemoOptions& o) {
  set_json_mode(o.json);
  const auto t_start = std::chrono::steady_clock::now();
  const fs::path dir(o.out);
  const Rig rig = design::thesis_prototype_rig();
  const Size2 size = parse_size(o.size);
  const PanoGrid grid{parse_projection(o.projection), size.width, size.height};
  const auto scene = sim::make_scene(o.scene);  // bad input fails here, before anything is written
  fs::create_directories(dir);

  spdlog::info("demo: simulating the {}-camera dome in scene '{}'", rig.cameras.size(), o.scene);
  sim::SimulateOptions so;
  so.effects.seed = o.seed;
  so.truth_grid = grid;
  so.progress = !o.json;
  const sim::SimulateSummary simr = sim::simulate(rig, *scene, so);
  sim::write_frames_folder(dir / "frames", simr, so, *scene);
  std::vector<cv::Mat> frames;
  for (const auto& f : simr.frames) frames.push_back(f.image);
  write_image(dir / "frames_mosaic.png", frame_mosaic(rig, frames));
  io::write_panorama(dir / "truth.png", simr.truth, grid);

  // Maps that use the overlap (§4.3).
  const cv::Mat coverage = pano::coverage_map(rig, grid);
  const cv::Mat single = pano::single_camera_map(coverage);
  const cv::Mat seam = pano::seam_mask(coverage, false);
  write_image(dir / "single_camera.png", single);
  cv::Mat counts;
  coverage.convertTo(counts, CV_32S);
  write_image(dir / "coverage.png", design::render_coverage_map(counts, "cameras seeing each direction"));

  std::vector<MethodRow> rows;
  cv::Mat mrf;
  for (pano::Method m : pano::all_methods()) {
    spdlog::info("demo: stitching with {}", pano::to_string(m));
    pano::StitchOptions opt;
    opt.method = m;
    opt.grid = grid;
    opt.progress = !o.json;
    const auto t0 = std::chrono::steady_clock::now();
    const cv::Mat p = pano::stitch(rig, frames, opt);
    MethodRow row{pano::to_string(m), {}, ms_since(t0)};
    row.eval = pano::evaluate(p, simr.truth, seam);
    const cv::Mat p8 = to_u8(p);
    io::write_panorama(dir / ("pano_" + row.method + ".png"), p8, grid);
    if (m == pano::Method::kMrf) mrf = p8;
    rows.push_back(row);
  }
  const cv::Mat boundary = pano::boundary_map(rig, frames, grid);
  cv::Mat boundary8;
  boundary.convertTo(boundary8, CV_8U, 255.0 / std::max(1e-6, o.threshold * 3));
  write_image(dir / "boundary.png", boundary8);
  write_image(dir / "boundary_overlay.png", pano::boundary_overlay(mrf, boundary, o.threshold));
  spdlog::info("demo: the real-time engine on the same frames");
  const EngineRow eng = run_engine(rig, grid, frames, mrf);
  spdlog::info("demo: photometric calibration from the frames' overlaps, then every method again");
  const PhotometricDemo ph = photometric_demo(dir, rig, frames, simr, so.effects, grid, seam, !o.json);
  const double inter = pano::inter_camera_psnr(rig, frames, grid);
  const double r_vir = design::virtual_radius(rig, deg2rad(0.5));
  const DepthDemo depth = run_depth_demo(rig, grid, frames, simr.truth, simr.truth_depth, mrf, dir, !o.json);
  const double total_s = ms_since(t_start) / 1000;
  write_report(dir, o, rig, rows, eng, inter, r_vir, total_s, depth, ph);

  if (o.json) {
    nlohmann::json methods = nlohmann::json::object();
    for (const auto& r : rows)
      methods[r.method] = {{"psnr_db", r.eval.psnr_db},
                           {"ssim", r.eval.ssim},
                           {"seam_psnr_db", r.eval.seam_psnr_db},
                           {"ms", r.ms}};
    print_json({{"out", fs::absolute(dir).string()},
                {"cameras", rig.cameras.size()},
                {"scene", o.scene},
                {"width", grid.width},
                {"height", grid.height},
                {"inter_camera_psnr_db", inter},
                {"r_virtual_mm", r_vir},
                {"methods", methods},
                {"engine",
                 {{"method", "mrf"},
                  {"fps", eng.fps},
                  {"compile_s", eng.compile_s},
                  {"bytes_per_pixel", eng.bytes_per_pixel},
                  {"psnr_vs_reference_db", eng.psnr_vs_reference}}},
                {"depth", depth.json},
                {"photometric", photometric_json(ph, rows)},
                {"seconds", total_s}});
  } else {
    std::cout << fmt::format("\n{:<14} {:>9} {:>7} {:>10} {:>8}\n", "method", "PSNR dB", "SSIM", "seam dB",
                             "ms");
    for (const auto& r : rows)
      std::cout << fmt::format("{:<14} {:>9.2f} {:>7.4f} {:>10.2f} {:>8.0f}\n", r.method, r.eval.psnr_db,
                               r.eval.ssim, r.eval.seam_psnr_db, r.ms);
    std::cout << fmt::format(
        "real-time engine, mrf: {:.0f} panoramas/s ({:.0f}x the FPGA's 25 fps), {:.1f} dB "
        "against the reference stitch, map compiled in {:.2f} s\n",
        eng.fps, eng.fps / 25, eng.psnr_vs_reference, eng.compile_s);
    std::cout << depth.summary << "\n";
    std::cout << photometric_text(ph, rows);
    std::cout << fmt::format("inter-camera PSNR (eq. 4.19-4.21): {:.2f} dB; total {:.1f} s\n", inter,
                             total_s);
    std::cout << "demo written to " << fs::absolute(dir).string() << "/ (open report.html)\n";
  }
}

}  // namespace

void add_demo_command(CLI::App& root) {
  auto opts = std::make_shared<DemoOptions>();
  auto* cmd = root.add_subcommand(
      "demo",
      "The main job: the thesis's 24-camera dome in a simulated colon; frames, panoramas by all six "
      "methods against the ground truth, boundary, single-camera and coverage maps, and a report");
  cmd->add_option("--out", opts->out, "Output folder")->capture_default_str();
  cmd->add_option("--scene", opts->scene, "Scene: colon, photo:PATH, usaf[:MM], checker[:MM]")
      ->capture_default_str();
  cmd->add_option("--size", opts->size, "Panorama size WxH")->capture_default_str();
  cmd->add_option("--projection", opts->projection, "vr180 or equirect")->capture_default_str();
  cmd->add_option("--threshold", opts->threshold, "Boundary threshold th_ob on luma in [0,1] (eq. 4.16)")
      ->capture_default_str();
  cmd->add_option("--seed", opts->seed, "Simulation seed")->capture_default_str();
  cmd->add_flag("--json", opts->json, "Print one JSON summary on stdout");
  // The Giga-Eye (thesis ch. 7): its own demo (giga_demo.h).
  static std::string rig = "thesis-24";
  static GigaDemoOptions giga;
  cmd->add_option(
         "--rig", rig,
         "thesis-24 (default) or gigaeye-44: the Giga-Eye end to end (plan, coverage, a simulated raw "
         "recording, calibration, 21.6 MP panoramas; --out, --seed, --json and --size apply, --scene "
         "defaults to photo:../shared/data/lake.jpg if present, else checker:50000; --giga-mode and "
         "--frame-sets below)")
      ->capture_default_str();
  cmd->add_option("--giga-mode", giga.mode,
                  "Giga-Eye demo: sensor mode of the recording (full, skip1, skip2, skip3, skip5)")
      ->capture_default_str();
  cmd->add_option("--frame-sets", giga.frame_sets, "Giga-Eye demo: frame sets to record")
      ->capture_default_str();
  cmd->callback([opts, cmd] {
    if (rig == "thesis-24") return run_demo(*opts);
    if (rig != "gigaeye-44") throw std::invalid_argument("--rig must be thesis-24 or gigaeye-44");
    giga.json = opts->json;
    giga.seed = opts->seed;
    if (cmd->get_option("--out")->count()) giga.out = opts->out;
    if (cmd->get_option("--scene")->count()) giga.scene = opts->scene;
    if (cmd->get_option("--size")->count()) giga.size = opts->size;
    run_giga_demo(giga);
  });
}

}  // namespace omma::app
