#include "apps/demo_depth.h"

#include <chrono>
#include <cmath>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "omma/bench/bench.h"
#include "omma/core/frames.h"
#include "omma/core/io.h"
#include "omma/core/log.h"
#include "omma/io/metadata.h"
#include "omma/pano/depth_eval.h"
#include "omma/pano/maps.h"
#include "omma/pano/plane_sweep.h"
#include "omma/pano/quality.h"
#include "omma/pano/stitch.h"
#include "omma/pano/surface.h"
#include "omma/render/depth_render.h"
#include "omma/render/render.h"

namespace omma::app {

namespace {

// Boundaries against the true occlusion boundaries, each map at its best threshold: the thesis's
// L_ob at infinity, L_ob on the estimated depth, and the estimate's own depth jumps (drawn in green on
// the panorama with depth: boundary_depth.png).
struct DepthBoundaries {
  pano::BoundaryScore at_inf, with_depth, from_depth;
  double th_inf = 0, th_depth = 0, th_jump = 0;
};
DepthBoundaries score_boundaries(const Rig& rig, const std::vector<cv::Mat>& frames, const PanoGrid& grid,
                                 const cv::Mat& truth_depth, const cv::Mat& est_depth,
                                 const cv::Mat& with_depth, const std::filesystem::path& dir) {
  DepthBoundaries b;
  const cv::Mat occl = pano::depth_discontinuities(truth_depth);
  const int tol = std::max(1, grid.width / 270);
  b.at_inf = pano::best_boundary_score(pano::boundary_map(rig, frames, grid), occl, tol, &b.th_inf);
  b.with_depth =
      pano::best_boundary_score(pano::boundary_map(rig, frames, grid, {}, est_depth), occl, tol, &b.th_depth);
  const cv::Mat jumps = pano::depth_jump_map(est_depth);
  b.from_depth = pano::best_boundary_score(jumps, occl, tol, &b.th_jump);
  cv::Mat overlay = with_depth.clone();
  cv::Mat grown;
  cv::dilate(jumps > b.th_jump, grown, cv::Mat());
  overlay.setTo(cv::Scalar(0, 255, 0), grown);
  write_image(dir / "boundary_depth.png", overlay);
  return b;
}

// The engine's depth-adaptive renderer on the same frames (depth every panorama): panoramas/s, PSNR
// against the truth and against the reference stitch on the estimate (pano_mrf_engine_depth.png).
struct EngineDepth {
  double fps = 0, psnr_db = 0, vs_reference_db = 0;
};
EngineDepth engine_depth(const Rig& rig, const PanoGrid& grid, const std::vector<cv::Mat>& frames,
                         const cv::Mat& truth, const cv::Mat& with_depth, const std::filesystem::path& dir) {
  spdlog::info("demo: the engine's depth-adaptive renderer");
  render::DepthRenderOptions dro;
  dro.map.grid = grid;
  dro.map.method = pano::Method::kMrf;
  auto dr = std::make_shared<render::DepthRenderer>(rig, dro);
  auto store = std::make_shared<render::FrameStore>(dr->layout());
  for (size_t i = 0; i < frames.size(); ++i) store->set(int(i), frames[i]);
  auto out = std::make_shared<cv::Mat>();
  const bench::Workload w{"omma-mrf-depth", 0, [&] { dr->render(*store, frames, *out); }, {}};
  EngineDepth e;
  e.fps = bench::measure_fps(w, 2.0, 10);  // 2 s: single seconds vary by +-15 % on the 2-core machine
  io::write_panorama(dir / "pano_mrf_engine_depth.png", *out, grid);  // with the 360-degree XMP
  e.psnr_db = pano::psnr_db(*out, truth);
  e.vs_reference_db = render::psnr_u8(*out, with_depth);
  return e;
}

}  // namespace

DepthDemo run_depth_demo(const Rig& rig, const PanoGrid& grid, const std::vector<cv::Mat>& frames,
                         const cv::Mat& truth, const cv::Mat& truth_depth, const cv::Mat& pano_inf,
                         const std::filesystem::path& dir, bool progress) {
  spdlog::info("demo: depth from the overlaps (sphere sweep)");
  const auto t0 = std::chrono::steady_clock::now();
  const pano::DepthEstimate est = pano::estimate_depth(rig, frames, grid);
  const double est_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  pano::write_depth(dir / "depth_estimate.tiff", est.depth);
  write_image(dir / "depth_estimate.png", pano::depth_colormap(est.depth, 12, 60, "estimated depth"));
  write_image(dir / "depth_truth.png", pano::depth_colormap(truth_depth, 12, 60, "true depth"));

  pano::StitchOptions opt;
  opt.method = pano::Method::kMrf;
  opt.grid = grid;
  opt.progress = progress;
  const cv::Mat seam = pano::seam_mask(pano::coverage_map(rig, grid), false);
  const pano::EvalSummary at_inf = pano::evaluate(pano_inf, truth, seam);
  opt.depth = pano::sphere_depth(rig, grid, 22);
  const pano::EvalSummary sphere = pano::evaluate(to_u8(pano::stitch(rig, frames, opt)), truth, seam);
  opt.depth = est.depth;
  const cv::Mat with_depth = to_u8(pano::stitch(rig, frames, opt));
  io::write_panorama(dir / "pano_mrf_depth.png", with_depth, grid);
  const pano::EvalSummary estimate = pano::evaluate(with_depth, truth, seam);
  opt.depth = truth_depth;
  const pano::EvalSummary with_truth = pano::evaluate(to_u8(pano::stitch(rig, frames, opt)), truth, seam);
  const pano::DepthError derr = pano::depth_error(est.depth, truth_depth, 300);

  const DepthBoundaries bd = score_boundaries(rig, frames, grid, truth_depth, est.depth, with_depth, dir);
  const pano::BoundaryScore &b_inf = bd.at_inf, &b_with = bd.with_depth, &b_jump = bd.from_depth;
  const double th_inf = bd.th_inf, th_depth = bd.th_depth, th_jump = bd.th_jump;

  const EngineDepth eng = engine_depth(rig, grid, frames, truth, with_depth, dir);
  const double fps = eng.fps, engine_psnr = eng.psnr_db, engine_vs_ref = eng.vs_reference_db;

  DepthDemo d;
  const double closed = 100 * (estimate.psnr_db - sphere.psnr_db) / (with_truth.psnr_db - sphere.psnr_db);
  const std::string table = fmt::format(
      "| projection surface (mrf) | PSNR (dB) | seam PSNR (dB) | SSIM |\n|---|---|---|---|\n"
      "| infinity (the thesis) | {:.2f} | {:.2f} | {:.4f} |\n| sphere 22 mm (a stitching distance) | {:.2f} "
      "| {:.2f} | {:.4f} |\n"
      "| estimated depth | **{:.2f}** | {:.2f} | {:.4f} |\n| true depth (upper bound) | {:.2f} | {:.2f} | "
      "{:.4f} |\n",
      at_inf.psnr_db, at_inf.seam_psnr_db, at_inf.ssim, sphere.psnr_db, sphere.seam_psnr_db, sphere.ssim,
      estimate.psnr_db, estimate.seam_psnr_db, estimate.ssim, with_truth.psnr_db, with_truth.seam_psnr_db,
      with_truth.ssim);
  const std::string facts = fmt::format(
      "The estimate (sphere sweep over {} candidate distances, ZNCC, semi-global smoothing; {:.1f} s) closes "
      "{:.0f} % of the gap between the fixed sphere and the true depth; median relative depth error {:.1f} % "
      "({:.0f} % of the wall within 10 %). Boundaries against the true occlusion boundaries (precision / "
      "recall "
      "/ F1, each map at its best threshold): the thesis's L_ob at infinity {:.2f} / {:.2f} / {:.2f}, L_ob "
      "on "
      "the estimated depth {:.2f} / {:.2f} / {:.2f}, the estimate's own depth jumps {:.2f} / {:.2f} / {:.2f} "
      "(green above). The engine's depth-adaptive renderer (`omma run --depth`: depth every panorama on a "
      "coarse grid, taps moved) renders {:.1f} panoramas/s here, {:.2f} dB against the truth ({:.1f} dB from "
      "the reference stitch on the estimate).",
      pano::PlaneSweepOptions{}.steps, est_s, closed, 100 * derr.median_rel, 100 * derr.within_10,
      b_inf.precision, b_inf.recall, b_inf.f1, b_with.precision, b_with.recall, b_with.f1, b_jump.precision,
      b_jump.recall, b_jump.f1, fps, engine_psnr, engine_vs_ref);
  d.markdown =
      "## Depth from the overlaps\n\n"
      "![estimated depth](depth_estimate.png) ![true depth](depth_truth.png)\n\n"
      "Without depth (infinity) and with the estimated depth:\n\n"
      "![without](pano_mrf.png) ![with](pano_mrf_depth.png)\n\n"
      "Boundaries from depth: ![boundary from depth](boundary_depth.png)\n\n" +
      table + "\n" + facts + "\n";
  d.html =
      "<h2>Depth from the overlaps</h2><div class=\"row\"><div><h3>Estimated depth</h3>"
      "<img src=\"depth_estimate.png\"></div><div><h3>True depth</h3><img "
      "src=\"depth_truth.png\"></div></div>"
      "<div class=\"row\"><div><h3>Without depth (infinity)</h3><img src=\"pano_mrf.png\"></div>"
      "<div><h3>With the estimated depth</h3><img src=\"pano_mrf_depth.png\"></div></div>"
      "<div class=\"row\"><div><h3>Boundaries from depth</h3><img src=\"boundary_depth.png\"></div>"
      "<div><h3>Engine, depth every panorama</h3><img src=\"pano_mrf_engine_depth.png\"></div></div>";
  d.html +=
      "<table><tr><th>projection surface (mrf)</th><th>PSNR (dB)</th><th>seam PSNR "
      "(dB)</th><th>SSIM</th></tr>";
  auto row = [](const char* name, const pano::EvalSummary& e) {
    return fmt::format("<tr><td>{}</td><td>{:.2f}</td><td>{:.2f}</td><td>{:.4f}</td></tr>", name, e.psnr_db,
                       e.seam_psnr_db, e.ssim);
  };
  d.html += row("infinity (the thesis)", at_inf) + row("sphere 22 mm", sphere) +
            row("estimated depth", estimate) + row("true depth (upper bound)", with_truth) + "</table><p>" +
            facts + "</p>";
  auto score = [](const pano::BoundaryScore& s, double th) {
    return nlohmann::json{{"precision", s.precision}, {"recall", s.recall}, {"f1", s.f1}, {"threshold", th}};
  };
  d.json = {{"psnr_db",
             {{"inf", at_inf.psnr_db},
              {"sphere_22", sphere.psnr_db},
              {"estimate", estimate.psnr_db},
              {"truth", with_truth.psnr_db}}},
            {"seam_psnr_db",
             {{"inf", at_inf.seam_psnr_db},
              {"sphere_22", sphere.seam_psnr_db},
              {"estimate", estimate.seam_psnr_db},
              {"truth", with_truth.seam_psnr_db}}},
            {"gap_closed", closed / 100},
            {"depth_median_rel_error", derr.median_rel},
            {"estimate_s", est_s},
            {"boundary",
             {{"thesis", score(b_inf, th_inf)},
              {"with_depth", score(b_with, th_depth)},
              {"from_depth", score(b_jump, th_jump)}}},
            {"engine", {{"fps", fps}, {"psnr_db", engine_psnr}, {"psnr_vs_reference_db", engine_vs_ref}}}};
  d.summary = fmt::format(
      "depth (mrf): inf {:.2f} dB, sphere 22 mm {:.2f} dB, estimate {:.2f} dB, truth {:.2f} dB ({:.0f} % of "
      "the gap "
      "closed), median depth error {:.1f} %; engine with depth every panorama {:.1f} panoramas/s",
      at_inf.psnr_db, sphere.psnr_db, estimate.psnr_db, with_truth.psnr_db, closed, 100 * derr.median_rel,
      fps);
  return d;
}

}  // namespace omma::app
