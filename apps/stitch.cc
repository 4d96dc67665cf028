// omma stitch: camera frames -> panorama with the reference stitcher (thesis §2.4.2, ch. 4), plus
// the object boundary map (eq. 4.12-4.16), the single-camera and coverage maps and the
// inter-camera PSNR (eq. 4.19-4.21).
#include "omma/pano/stitch.h"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <stdexcept>

#include "apps/command.h"
#include "omma/core/frames.h"
#include "omma/core/grid.h"
#include "omma/core/io.h"
#include "omma/core/log.h"
#include "omma/core/metadata.h"
#include "omma/core/rig.h"
#include "omma/isp/isp.h"
#include "omma/pano/maps.h"

namespace omma::app {
namespace {

struct StitchArgs {
  std::string rig, frames, method = "mrf", projection = "vr180", size, out;
  std::string boundary, boundary_overlay, single_camera, coverage;
  double threshold = 0.2;
  bool json = false;
  // --raw: develop DIR/cam_XX_raw.png with the ISP (thesis §5.1.2, appendix A) before stitching.
  bool raw = false;
  std::string demosaic = "hybrid", awb = "grayworld", flat;
  bool linear_output = false;
};

std::filesystem::path overlay_path_for(const std::filesystem::path& boundary) {
  return boundary.parent_path() / (boundary.stem().string() + "_overlay" + boundary.extension().string());
}

void run_stitch(const StitchArgs& a) {
  set_json_mode(a.json);
  // Validate everything before any work or output.
  const pano::Method method = pano::parse_method(a.method);
  PanoGrid grid;
  grid.projection = parse_projection(a.projection);
  if (a.size.empty()) {
    grid.width = grid.projection == Projection::kVr180 ? 1080 : 1920;
    grid.height = grid.projection == Projection::kVr180      ? 1080
                  : grid.projection == Projection::kEquirect ? 512
                                                             : 960;
  } else {
    const Size2 s = parse_size(a.size);
    grid.width = s.width;
    grid.height = s.height;
  }
  if (grid.width <= 0 || grid.height <= 0 || grid.width > 16384 || grid.height > 16384)
    throw std::invalid_argument(fmt::format("--size {}x{} out of range (1..16384)", grid.width, grid.height));
  if (a.threshold < 0 || a.threshold > 1) throw std::invalid_argument("--threshold must be in [0, 1]");
  const Rig rig = load_rig(a.rig);
  if (rig.cameras.empty()) throw std::invalid_argument("rig " + a.rig + " has no cameras");
  std::vector<cv::Mat> frames;
  if (a.raw) {
    isp::IspOptions iso;
    iso.demosaic = isp::parse_demosaic(a.demosaic);
    iso.awb = isp::parse_awb(a.awb);
    iso.srgb = !a.linear_output;
    if (!a.flat.empty()) iso.flat_gain = isp::load_flat_field(a.flat);
    frames = isp::develop_all(load_raw_frames(a.frames, rig), iso);
  } else {
    frames = load_frames(a.frames, rig);
  }

  pano::StitchOptions opt;
  opt.method = method;
  opt.grid = grid;
  const auto t0 = std::chrono::steady_clock::now();
  const cv::Mat pano_img = pano::stitch(rig, frames, opt);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const double icp = pano::inter_camera_psnr(rig, frames, grid, opt.blend.search);

  cv::Mat boundary, overlay, single, coverage;
  if (!a.boundary.empty() || !a.boundary_overlay.empty()) {
    boundary = pano::boundary_map(rig, frames, grid, opt.blend.search);
    overlay = pano::boundary_overlay(to_u8(pano_img), boundary, a.threshold);
  }
  if (!a.single_camera.empty() || !a.coverage.empty())
    coverage = pano::coverage_map(rig, grid, opt.blend.search);
  if (!a.single_camera.empty()) single = pano::single_camera_map(coverage);

  write_panorama(a.out, to_u8(pano_img), grid);  // JPEG/PNG with the 360-degree XMP
  if (!a.boundary.empty()) {
    write_image(a.boundary, to_u8(boundary));
    write_image(
        a.boundary_overlay.empty() ? overlay_path_for(a.boundary) : std::filesystem::path(a.boundary_overlay),
        overlay);
  } else if (!a.boundary_overlay.empty()) {
    write_image(a.boundary_overlay, overlay);
  }
  if (!single.empty()) write_image(a.single_camera, single);
  if (!a.coverage.empty()) write_image(a.coverage, coverage);

  nlohmann::json icp_json = std::isfinite(icp) ? nlohmann::json(icp) : nlohmann::json(nullptr);
  if (a.json) {
    print_json({{"method", pano::to_string(method)},
                {"width", grid.width},
                {"height", grid.height},
                {"ms", ms},
                {"inter_camera_psnr_db", icp_json}});
  } else {
    std::cout << fmt::format("{}: {}x{} {} panorama by {} in {:.0f} ms, inter-camera PSNR {:.2f} dB\n", a.out,
                             grid.width, grid.height, to_string(grid.projection), pano::to_string(method), ms,
                             icp);
  }
}

}  // namespace

void add_stitch_command(CLI::App& root) {
  auto* cmd = root.add_subcommand(
      "stitch",
      "Stitch camera frames into a panorama with the reference renderer (thesis §2.4.2, ch. 4):\n"
      "camera search (eq. 2.3), camera model with distortion (eq. 5.21-5.26), bilinear sampling,\n"
      "and one of the six blending methods.");
  static StitchArgs a;
  cmd->add_option("--rig", a.rig, "Rig file (JSON, mm and degrees)")->required();
  cmd->add_option("--frames", a.frames, "Frames folder: DIR/cam_XX.png, one per camera id")->required();
  cmd->add_option("--method", a.method,
                  "Blending: nn (eq. 2.6-2.7), linear (eq. 2.8), gaussian (eq. 2.9), mrf (eq. 4.8-4.9),\n"
                  "mrf-spherical (eq. 4.10-4.11), sad (eq. 4.17-4.18)")
      ->capture_default_str();
  cmd->add_option("--projection", a.projection,
                  "equirect (360x90 deg, dome axis on the top row) or vr180 (180x180 deg, dome axis at the "
                  "centre)")
      ->capture_default_str();
  cmd->add_option("--size", a.size,
                  "Panorama size WxH in pixels [default: 1080x1080 vr180, 1920x512 equirect]");
  cmd->add_option("--out", a.out, "Output panorama image (8-bit; format from the extension, e.g. .png)")
      ->required();
  cmd->add_option("--boundary", a.boundary,
                  "Write the object boundary map L_ob (eq. 4.15, gray, 255 = 1.0) here, and the thresholded\n"
                  "map drawn in green over the panorama (eq. 4.16) beside it as <name>_overlay.<ext>");
  cmd->add_option("--boundary-overlay", a.boundary_overlay,
                  "Write the green boundary overlay to this path instead");
  cmd->add_option("--threshold", a.threshold, "Boundary threshold th_ob on gray levels in [0,1] (eq. 4.16)")
      ->capture_default_str();
  cmd->add_option(
      "--single-camera", a.single_camera,
      "Write the single-camera map: white = seen by one camera only, black = seen by two or more\n"
      "(the seam band, usable as `omma eval --mask`), dark gray = seen by none");
  cmd->add_option("--coverage", a.coverage,
                  "Write the coverage map: number of cameras per direction (8-bit gray)");
  cmd->add_flag("--raw", a.raw,
                "Read the raw Bayer frames DIR/cam_XX_raw.png (16-bit RGGB, 10-bit values) and develop each\n"
                "with the ISP (demosaic, white balance, optional flat field) before stitching");
  cmd->add_option("--demosaic", a.demosaic, "With --raw: bilinear, hybrid, ah or cc (appendix A)")
      ->capture_default_str();
  cmd->add_option("--awb", a.awb, "With --raw: none, grayworld or whitepatch (eq. A.23-A.38)")
      ->capture_default_str();
  cmd->add_option("--flat", a.flat, "With --raw: flat-field raw frame for vignetting correction");
  cmd->add_flag("--linear-output", a.linear_output,
                "With --raw: keep the 8 most significant linear bits (the thesis hardware) instead of sRGB");
  cmd->add_flag("--json", a.json,
                "Print one JSON object {method, width, height, ms, inter_camera_psnr_db} on stdout");
  cmd->callback([] { run_stitch(a); });
}

}  // namespace omma::app
