// omma eval: compare a panorama with a ground truth (PSNR, SSIM, PSNR over the seam band).
#include <fmt/format.h>

#include <cmath>
#include <iostream>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>

#include "apps/command.h"
#include "omma/core/grid.h"
#include "omma/core/io.h"
#include "omma/core/rig.h"
#include "omma/pano/maps.h"
#include "omma/pano/quality.h"

namespace omma::app {
namespace {

struct EvalArgs {
  std::string pano, truth, mask, rig, projection = "vr180";
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
    const Rig rig = load_rig(a.rig);
    const PanoGrid grid{parse_projection(a.projection), pano_img.cols, pano_img.rows};
    seam = pano::seam_mask(pano::coverage_map(rig, grid), false);
  }
  const pano::EvalResult r = pano::evaluate(pano_img, truth, seam);
  if (a.json) {
    print_json({{"psnr_db", number_or_null(r.psnr_db)},
                {"ssim", r.ssim},
                {"seam_psnr_db", seam.empty() ? nlohmann::json(nullptr) : number_or_null(r.seam_psnr_db)}});
  } else {
    std::cout << fmt::format("PSNR {:.2f} dB, SSIM {:.4f}", r.psnr_db, r.ssim);
    if (!seam.empty()) std::cout << fmt::format(", seam PSNR {:.2f} dB", r.seam_psnr_db);
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
  cmd->add_flag("--json", a.json,
                "Print one JSON object {psnr_db, ssim, seam_psnr_db} on stdout (null: no seam band given)");
  cmd->callback([] { run_eval(a); });
}

}  // namespace omma::app
