// omma eval: compare a panorama with a ground truth (PSNR, SSIM, PSNR over the seam band).
#include <cmath>
#include <iostream>
#include <stdexcept>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>

#include "apps/command.h"
#include "omma/core/grid.h"
#include "omma/core/io.h"
#include "omma/core/rig.h"
#include "omma/design/prototype.h"
#include "omma/pano/depth_eval.h"
#include "omma/pano/maps.h"
#include "omma/pano/quality.h"
#include "omma/pano/surface.h"

namespace omma::app {
namespace {

struct EvalArgs {
  std::string pano, truth, mask, rig, projection = "vr180";
  std::string depth, truth_depth, boundary;
  double threshold = 0.2, max_depth = 300, jump = 1.15;
  int tolerance = 2;
  bool json = false;
};

nlohmann::json number_or_null(double x) {
  return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr);
}

void run_eval(const EvalArgs& a) {
  set_json_mode(a.json);
  if (!a.mask.empty() && !a.rig.empty()) throw std::invalid_argument("give --mask or --rig, not both");
  const cv::Mat pano_img = read_image(a.pano, cv::IMREAD_UNCHANGED);
  const cv::Mat truth = read_image(a.truth, cv::IMREAD_UNCHANGED);
  if (pano_img.size() != truth.size())
    throw std::invalid_argument(fmt::format("{} is {}x{} but {} is {}x{}", a.pano, pano_img.cols,
                                            pano_img.rows, a.truth, truth.cols, truth.rows));
  cv::Mat seam;
  if (!a.mask.empty()) {
    const cv::Mat m = read_image(a.mask, cv::IMREAD_GRAYSCALE);
    if (m.size() != pano_img.size())
      throw std::invalid_argument(fmt::format("mask {} is {}x{}, the panorama {}x{}", a.mask, m.cols, m.rows,
                                              pano_img.cols, pano_img.rows));
    seam = pano::seam_mask(m, true);
  } else if (!a.rig.empty()) {
    const Rig rig = design::load_rig_or_builtin(a.rig);
    const PanoGrid grid{parse_projection(a.projection), pano_img.cols, pano_img.rows};
    seam = pano::seam_mask(pano::coverage_map(rig, grid), false);
  }
  const pano::EvalSummary r = pano::evaluate(pano_img, truth, seam);
  // Depth (pano/depth_eval.h): the depth used against the true depth, and a boundary map (eq. 4.15, gray)
  // thresholded (eq. 4.16) against the true occlusion boundaries.
  nlohmann::json depth_json = nullptr, boundary_json = nullptr;
  if ((!a.depth.empty() || !a.boundary.empty()) && a.truth_depth.empty())
    throw std::invalid_argument("--depth and --boundary need --truth-depth");
  cv::Mat true_depth;
  const PanoGrid grid{parse_projection(a.projection), pano_img.cols, pano_img.rows};
  if (!a.truth_depth.empty()) true_depth = pano::read_depth(a.truth_depth, grid);
  auto score_json = [](const pano::BoundaryScore& s, double th) {
    return nlohmann::json{{"precision", s.precision}, {"recall", s.recall}, {"f1", s.f1},
                          {"predicted", s.predicted}, {"truth", s.truth},   {"threshold", th}};
  };
  cv::Mat occlusions;
  if (!true_depth.empty()) occlusions = pano::depth_discontinuities(true_depth, a.jump);
  if (!a.depth.empty()) {
    const cv::Mat used = pano::read_depth(a.depth, grid);
    const pano::DepthError e = pano::depth_error(used, true_depth, a.max_depth);
    double th = 0;
    const pano::BoundaryScore s =
        pano::best_boundary_score(pano::depth_jump_map(used), occlusions, a.tolerance, &th);
    depth_json = {{"median_rel", e.median_rel},
                  {"mean_rel", e.mean_rel},
                  {"within_10", e.within_10},
                  {"pixels", e.pixels},
                  {"boundary_from_depth", score_json(s, th)}};
  }
  if (!a.boundary.empty()) {
    cv::Mat b = read_image(a.boundary, cv::IMREAD_GRAYSCALE), bf;
    if (b.size() != pano_img.size())
      throw std::invalid_argument("--boundary: size differs from the panorama");
    b.convertTo(bf, CV_32F, 1 / 255.0);
    const pano::BoundaryScore s =
        pano::boundary_score(pano::boundary_binary(bf, a.threshold), occlusions, a.tolerance);
    double th = 0;
    const pano::BoundaryScore best = pano::best_boundary_score(bf, occlusions, a.tolerance, &th);
    boundary_json = score_json(s, a.threshold);
    boundary_json["best"] = score_json(best, th);
  }
  if (a.json) {
    print_json({{"psnr_db", number_or_null(r.psnr_db)},
                {"ssim", r.ssim},
                {"seam_psnr_db", seam.empty() ? nlohmann::json(nullptr) : number_or_null(r.seam_psnr_db)},
                {"depth", depth_json},
                {"boundary", boundary_json}});
  } else {
    std::cout << fmt::format("PSNR {:.2f} dB, SSIM {:.4f}", r.psnr_db, r.ssim);
    if (!seam.empty()) std::cout << fmt::format(", seam PSNR {:.2f} dB", r.seam_psnr_db);
    if (!depth_json.is_null())
      std::cout << fmt::format(", depth error median {:.1f} %", 100 * depth_json["median_rel"].get<double>());
    if (!boundary_json.is_null())
      std::cout << fmt::format(", boundary P {:.2f} R {:.2f} F1 {:.2f}",
                               boundary_json["precision"].get<double>(),
                               boundary_json["recall"].get<double>(), boundary_json["f1"].get<double>());
    std::cout << "\n";
  }
}

}  // namespace

void add_eval_command(CLI::App& root) {
  auto* cmd = root.add_subcommand(
      "eval",
      "Compare a panorama with a ground truth: PSNR (dB, MAX = full scale, all channels), mean SSIM\n"
      "(11x11 Gaussian window, sigma 1.5) and the PSNR over the seam band (directions seen by two or\n"
      "more cameras).");
  static EvalArgs a;
  cmd->add_option("--pano", a.pano, "Panorama to judge (image)")->required();
  cmd->add_option("--truth", a.truth,
                  "Ground truth panorama of the same size (e.g. DIR/truth.png of omma simulate)")
      ->required();
  cmd->add_option("--mask", a.mask,
                  "Single-camera map from `omma stitch --single-camera`: its black pixels are the seam band");
  cmd->add_option("--rig", a.rig, "Or: compute the seam band from this rig (with --projection)");
  cmd->add_option("--projection", a.projection, "Projection of the panorama for --rig: equirect or vr180")
      ->capture_default_str();
  cmd->add_option(
      "--truth-depth", a.truth_depth,
      "True depth of the panorama (the simulator's truth_depth.tiff), for --depth and --boundary");
  cmd->add_option(
      "--depth", a.depth,
      "A depth used for stitching (`omma stitch --depth-out`'s .tiff): median relative error against\n"
      "--truth-depth where the truth is at most --max-depth mm");
  cmd->add_option("--max-depth", a.max_depth, "Compare depths up to this many mm")->capture_default_str();
  cmd->add_option(
      "--boundary", a.boundary,
      "A boundary map L_ob (`omma stitch --boundary`, gray 255 = 1.0), thresholded at --threshold\n"
      "(eq. 4.16): precision, recall and F1 against the true occlusion boundaries (where the true\n"
      "depth jumps by more than --jump between neighbours), within --tolerance pixels; and at the\n"
      "map's best threshold (\"best\"). With --depth also the boundaries of the depth's own jumps");
  cmd->add_option("--threshold", a.threshold, "th_ob of eq. 4.16 for --boundary")->capture_default_str();
  cmd->add_option("--jump", a.jump, "Depth ratio that makes an occlusion boundary")->capture_default_str();
  cmd->add_option("--tolerance", a.tolerance, "Boundary match tolerance, pixels")->capture_default_str();
  cmd->add_flag("--json", a.json,
                "Print one JSON object {psnr_db, ssim, seam_psnr_db, depth, boundary} on stdout (null: not\n"
                "asked for)");
  cmd->callback([] { run_eval(a); });
}

}  // namespace omma::app
