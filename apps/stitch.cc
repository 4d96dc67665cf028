// omma stitch: camera frames -> panorama with the reference stitcher (thesis §2.4.2, ch. 4), plus
// the object boundary map (eq. 4.12-4.16), the single-camera and coverage maps and the
// inter-camera PSNR (eq. 4.19-4.21).
#include "omma/pano/stitch.h"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "apps/command.h"
#include "apps/depth_spec.h"
#include "apps/grid_args.h"
#include "omma/core/frames.h"
#include "omma/core/grid.h"
#include "omma/core/io.h"
#include "omma/core/log.h"
#include "omma/core/parse.h"
#include "omma/core/rig.h"
#include "omma/design/prototype.h"
#include "omma/io/depth_pano.h"
#include "omma/io/metadata.h"
#include "omma/io/point_cloud.h"
#include "omma/isp/isp.h"
#include "omma/isp/photometric.h"
#include "omma/pano/maps.h"
#include "omma/pano/plane_sweep.h"
#include "omma/pano/surface.h"

namespace omma::app {
namespace {

struct StitchArgs {
  std::string rig, frames, method = "mrf", projection = "vr180", size, out;
  std::string boundary, boundary_overlay, single_camera, coverage;
  std::string depth = "inf", depth_out;
  std::string depth_pitch;  // --depth-pitch: DEG or "camera"; empty = the sweep's default (1.33 deg)
  // 3D export (io/point_cloud.h, io/depth_pano.h): the coloured point cloud X = q + D w as PLY, every
  // ply_step-th pixel, without those below ply_min_confidence (--depth estimate); the 16-bit depth PNG.
  std::string ply, depth_pano;
  int ply_step = 1;
  double ply_min_confidence = 0;
  double threshold = 0.2;
  bool json = false;
  // --raw: develop DIR/cam_XX_raw.png with the ISP (thesis §5.1.2, appendix A) before stitching.
  bool raw = false;
  std::string demosaic = "hybrid", awb = "grayworld", flat;
  bool linear_output = false;
  bool no_photometric = false;  // ignore the rig's photometric model (compare before / after)
};

std::filesystem::path overlay_path_for(const std::filesystem::path& boundary) {
  return boundary.parent_path() / (boundary.stem().string() + "_overlay" + boundary.extension().string());
}

// The frames to stitch: raw mosaics developed (with the rig's photometric model in place of the flat
// field and the white balance when it has one), or developed frames corrected by that model.
std::vector<cv::Mat> stitch_frames(const StitchArgs& a, const Rig& rig, bool photometric) {
  std::vector<cv::Mat> frames;
  if (a.raw) {
    isp::IspOptions iso;
    iso.demosaic = isp::parse_demosaic(a.demosaic);
    iso.awb = isp::parse_awb(a.awb);
    iso.srgb = !a.linear_output;
    if (!a.flat.empty()) iso.flat_gain = isp::load_flat_field(a.flat);
    const std::vector<cv::Mat> raws = load_raw_frames(a.frames, rig);
    if (photometric && a.flat.empty()) {
      // The rig's photometric model replaces the flat field and the white balance: per camera a
      // flat-gain map 1 / (gain_c V) on the raw mosaic (isp/photometric.h).
      frames = isp::develop_with_model(raws, iso, isp::flat_gains_from_rig(rig));
    } else {
      frames = isp::develop_all(raws, iso);
    }
  } else {
    frames = load_frames(a.frames, rig);
    if (photometric) frames = isp::correct_frames(rig, frames);
  }
  return frames;
}

// --ply, --ply-step, --ply-min-confidence, --depth-pano: checked before any work.
void check_export_args(const StitchArgs& a) {
  const bool estimate = is_estimate_spec(a.depth);
  if ((!a.ply.empty() || !a.depth_pano.empty()) && a.depth == "inf")
    throw std::invalid_argument(
        "--ply and --depth-pano need a finite depth: --depth estimate, sphere:R or truth:FILE (with "
        "--depth inf every direction is at infinity)");
  if (!a.ply.empty() && lower_extension(a.ply) != ".ply")
    throw std::invalid_argument("--ply names a .ply file, got '" + a.ply + "'");
  if (a.ply_step < 1) throw std::invalid_argument(fmt::format("--ply-step must be >= 1, got {}", a.ply_step));
  if (!(a.ply_min_confidence >= 0 && a.ply_min_confidence <= 1))
    throw std::invalid_argument(
        fmt::format("--ply-min-confidence must be in [0, 1], got {}", a.ply_min_confidence));
  if (a.ply_min_confidence > 0 && !estimate)
    throw std::invalid_argument(
        "--ply-min-confidence applies to --depth estimate only (the other surfaces have no confidence), got "
        "--depth " +
        a.depth);
  if ((a.ply_step != 1 || a.ply_min_confidence > 0) && a.ply.empty())
    throw std::invalid_argument("--ply-step and --ply-min-confidence apply to --ply");
  auto same = [](const std::string& x, const std::string& y) {
    return std::filesystem::path(x).lexically_normal() == std::filesystem::path(y).lexically_normal();
  };
  if (!a.depth_pano.empty() &&
      (same(a.depth_pano, a.out) ||
       same(std::filesystem::path(a.depth_pano).replace_extension(".tiff").string(), a.out)))
    throw std::invalid_argument("--depth-pano '" + a.depth_pano +
                                "' (and its .tiff) must not be the panorama --out");
  if (!a.depth_pano.empty() && !a.depth_out.empty() && same(a.depth_pano, a.depth_out))
    throw std::invalid_argument("--depth-pano and --depth-out name the same file '" + a.depth_pano + "'");
  if (!a.depth_pano.empty() && lower_extension(a.depth_pano) != ".png")
    throw std::invalid_argument(
        "--depth-pano names a .png file (16-bit, mm; the float data go beside it as .tiff), got '" +
        a.depth_pano + "'");
}

void run_stitch(const StitchArgs& a) {
  set_json_mode(a.json);
  // Validate everything before any work or output.
  const pano::Method method = pano::parse_method(a.method);
  const PanoGrid grid = grid_from_args(a.projection, a.size);
  check_image_format(a.out, grid.width, grid.height);
  if (!(a.threshold >= 0 && a.threshold <= 1)) throw std::invalid_argument("--threshold must be in [0, 1]");
  check_export_args(a);
  const Rig rig = design::load_rig_or_builtin(a.rig);
  if (rig.cameras.empty()) throw std::invalid_argument("rig " + a.rig + " has no cameras");
  const bool photometric = has_photometric(rig) && !a.no_photometric;
  const std::vector<cv::Mat> frames = stitch_frames(a, rig, photometric);

  std::filesystem::path depth_data;
  if (!a.depth_out.empty()) {
    const std::filesystem::path p(a.depth_out);
    if (p.extension() == ".tiff" || p.extension() == ".tif")
      throw std::invalid_argument(
          "--depth-out names the picture (e.g. depth.png); the data go beside it as .tiff");
    depth_data = std::filesystem::path(p).replace_extension(".tiff");
  }
  const auto td = std::chrono::steady_clock::now();
  const DepthChoice depth = choose_depth(a.depth, a.depth_pitch, rig, frames, grid);
  const double depth_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - td).count();

  pano::StitchOptions opt;
  opt.method = method;
  opt.grid = grid;
  opt.depth = depth.depth;
  const auto t0 = std::chrono::steady_clock::now();
  const cv::Mat pano_img = pano::stitch(rig, frames, opt);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const double icp = pano::inter_camera_psnr(rig, frames, grid, opt.blend.search, opt.depth);

  cv::Mat boundary, overlay, single, coverage;
  if (!a.boundary.empty() || !a.boundary_overlay.empty()) {
    boundary = pano::boundary_map(rig, frames, grid, opt.blend.search, opt.depth);
    overlay = pano::boundary_overlay(to_u8(pano_img), boundary, a.threshold);
  }
  if (!a.single_camera.empty() || !a.coverage.empty())
    coverage = pano::coverage_map(rig, grid, opt.blend.search, opt.depth);
  if (!a.single_camera.empty()) single = pano::single_camera_map(coverage);

  const cv::Mat pano_u8 = to_u8(pano_img);
  const std::string out_ext = lower_extension(a.out);
  const bool embed_depth =
      !a.depth_pano.empty() && (out_ext == ".jpg" || out_ext == ".jpeg" || out_ext == ".png");
  if (embed_depth)
    io::write_panorama_with_depth(a.out, pano_u8, depth.depth, grid);  // + Google's depth map (GDepth)
  else
    io::write_panorama(a.out, pano_u8, grid);  // JPEG/PNG with the 360-degree XMP
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
  if (!a.depth_out.empty()) {
    const cv::Mat d = depth.depth.empty()
                          ? cv::Mat(grid.height, grid.width, CV_32FC1, cv::Scalar(pano::kInfiniteDepth))
                          : depth.depth;
    pano::write_depth(depth_data, d);
    write_image(a.depth_out, pano::depth_colormap(d, 0, 0, "depth (" + a.depth + ")"));
  }

  // 3D export: the point cloud and the depth panorama (16-bit PNG with its XMP, float TIFF beside it).
  nlohmann::json exported = nlohmann::json::object();
  const io::DepthRange range = io::depth_range(depth.depth);
  if (!a.ply.empty()) {
    io::PointCloudOptions po;
    po.q = opt.blend.search.q;
    po.step = a.ply_step;
    po.min_confidence = a.ply_min_confidence;
    io::PointCloud cloud = io::depth_to_points(depth.depth, pano_u8, grid, po, depth.estimate.confidence);
    cloud.comments.push_back(fmt::format(
        "omma stitch --depth {} --method {}: {}x{} {} panorama, every {} pixel(s)", a.depth,
        pano::to_string(method), grid.width, grid.height, to_string(grid.projection), a.ply_step));
    io::write_ply(a.ply, cloud, po.q);
    exported["ply"] = {{"file", a.ply},
                       {"points", cloud.size()},
                       {"step", a.ply_step},
                       {"min_confidence", a.ply_min_confidence}};
    if (!a.json) std::cout << fmt::format("{}: {} points (mm, rig frame)\n", a.ply, cloud.size());
  }
  if (!a.depth_pano.empty()) {
    const std::filesystem::path tiff = std::filesystem::path(a.depth_pano).replace_extension(".tiff");
    io::write_depth_png(a.depth_pano, depth.depth, grid);
    pano::write_depth(tiff, depth.depth);
    exported["depth_pano"] = {
        {"file", a.depth_pano}, {"data", tiff.string()}, {"gdepth_in_panorama", embed_depth}};
  }
  if (!depth.depth.empty())
    exported["depth_range"] = {
        {"near_mm", range.near_mm},
        {"far_mm", range.far_mm},
        {"finite_fraction", double(range.finite) / (double(grid.width) * grid.height)}};

  nlohmann::json icp_json = std::isfinite(icp) ? nlohmann::json(icp) : nlohmann::json(nullptr);
  if (a.json) {
    nlohmann::json summary = {{"method", pano::to_string(method)},
                              {"width", grid.width},
                              {"height", grid.height},
                              {"ms", ms},
                              {"depth", depth.info},
                              {"depth_ms", depth_ms},
                              {"photometric", photometric},
                              {"inter_camera_psnr_db", icp_json}};
    summary.update(exported);  // ply, depth_pano, depth_range
    print_json(summary);
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
                  "equirect (360x90 deg, dome axis on the top row), vr180 (180x180 deg, dome axis at the "
                  "centre), equirect-full (360x180) or equirect-100 (360x100); never mirrored: turning right "
                  "moves right in the image (docs/guide/conventions.md)")
      ->capture_default_str();
  cmd->add_option("--size", a.size,
                  "Panorama size WxH in pixels [default: 1080x1080 vr180, 1920x512 equirect, 1920x960\n"
                  "equirect-full, 1920x533 equirect-100]. The 360-degree metadata (GPano) needs square\n"
                  "pixels (1920x480 equirect, not the thesis's 1920x512: docs/guide/stitching.md)");
  cmd->add_option("--out", a.out,
                  "Output panorama image (8-bit; format from the extension, e.g. .png; JPEG, PNG and TIFF\n"
                  "carry the 360-degree GPano XMP)")
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
  cmd->add_option(
         "--depth", a.depth,
         "Projection surface D(w), the distance at which each direction meets the scene:\n"
         "  inf                   the scene at infinity (the thesis's model, eq. 2.3-2.5)\n"
         "  sphere:R              a fixed stitching distance: a sphere of R mm around the dome centre\n"
         "  truth:FILE            a depth file of the panorama's size (the simulator's truth_depth.tiff:\n"
         "                        32-bit float mm, or 16-bit in 1/100 mm)\n"
         "  estimate[:NEAR,FAR,STEPS]  estimated from the cameras' overlaps by a sphere sweep (ZNCC,\n"
         "                        semi-global smoothing); default 8,inf,96 (mm, mm, candidates)")
      ->capture_default_str();
  cmd->add_option(
      "--depth-pitch", a.depth_pitch,
      "With --depth estimate: the pitch of the sweep's grid, DEG (degrees) or 'camera' (the finest\n"
      "camera's pixel pitch at its centre: the cameras' own resolution, where the output grid is\n"
      "that fine) [default: 1.33, about 5 pixels of the prototype's cameras]");
  cmd->add_option(
      "--depth-out", a.depth_out,
      "Write the depth used as a colour picture with a legend (this name, e.g. depth.png) and as\n"
      "data beside it (same name, .tiff: 32-bit float mm, inf = infinity)");
  cmd->add_option(
      "--ply", a.ply,
      "Write the 3D point cloud of the depth used (X = q + D w per pixel, mm, rig frame: origin the\n"
      "dome centre, +z the dome axis) coloured by the panorama, as binary PLY (docs/guide/depth.md);\n"
      "needs a finite --depth; `omma view3d FILE` shows it");
  cmd->add_option("--ply-step", a.ply_step,
                  "With --ply: keep every N-th pixel in each axis (N^2 fewer points)")
      ->capture_default_str();
  cmd->add_option(
         "--ply-min-confidence", a.ply_min_confidence,
         "With --ply and --depth estimate: leave out directions whose depth confidence is below C in "
         "[0, 1]")
      ->capture_default_str();
  cmd->add_option(
      "--depth-pano", a.depth_pano,
      "Write the depth as a 360-degree depth panorama: a 16-bit PNG of whole millimetres along each ray\n"
      "(0 = unknown or infinity, saturating at 65535 mm) with GPano and Google's depth-map XMP (GDepth),\n"
      "the float data beside it (same name, .tiff); a JPEG or PNG --out also gets the depth map embedded\n"
      "(GDepth RangeInverse, 16-bit PNG; JPEG: Extended XMP)");
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
  cmd->add_flag(
      "--no-photometric", a.no_photometric,
      "Ignore the rig's photometric model (vignetting and colour gains, applied by default when the rig\n"
      "has one: frames in linear light divided by gain x falloff; with --raw it replaces --awb)");
  cmd->add_flag(
      "--json", a.json,
      "Print one JSON object {method, width, height, ms, depth, depth_ms, inter_camera_psnr_db; with a\n"
      "finite depth depth_range {near_mm, far_mm, finite_fraction}; ply {file, points, step, "
      "min_confidence};\n"
      "depth_pano {file, data, gdepth_in_panorama}} on stdout");
  cmd->callback([] { run_stitch(a); });
}

}  // namespace omma::app
