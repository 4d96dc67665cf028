// omma pto export|import: Hugin / PanoTools project files (the convention mapping is documented in
// src/omma/calib/pto.h).
#include "omma/calib/pto.h"

#include <iostream>

#include <fmt/format.h>

#include "apps/command.h"
#include "omma/core/io.h"
#include "omma/core/log.h"
#include "omma/design/prototype.h"

namespace omma::app {

void add_pto_command(CLI::App& root) {
  auto* cmd = root.add_subcommand("pto",
                                  "Hugin PTO project import and export (PanoTools conventions: see "
                                  "src/omma/calib/pto.h)");
  cmd->require_subcommand(1);
  static std::string rig_path, pto_path, frames, in_path, out_rig;
  static int pano_width = 1440, interpolator = 0;
  static bool json_ex = false, json_im = false, linear_response = false;
  auto* ex = cmd->add_subcommand(
      "export",
      "Write a rig as a Hugin project: one rectilinear (f0) image per camera with yaw, pitch, roll, v, "
      "a, b, c, d, e, the photometric model (Vb Vc Vd Vx Vy Vm5, Eev Er Eb) and an equirect p-line "
      "(cropped to the dome's hemisphere)");
  ex->add_option("RIG", rig_path, "Rig (JSON)")->required();
  ex->add_option("OUT", pto_path, "Project file to write (.pto, atomic)")->required();
  ex->add_option("--frames", frames, "Frames folder: images are DIR/cam_XX.png (default: bare cam_XX.png)");
  ex->add_option("--pano-width", pano_width, "p-line panorama width, pixels (360 x 180 deg; default 1440)");
  ex->add_option("--interpolator", interpolator,
                 "m-line interpolator: 0 poly3 (default), 5 bilinear, 6 nearest");
  ex->add_flag(
      "--linear-response", linear_response,
      "Write Rt1 (the frames' pixel values are linear light) so that Hugin applies the rig's photometric "
      "model (Vb Vc Vd Vx Vy, Eev Er Eb) exactly; default: Hugin's average EMoR camera curve");
  ex->add_flag("--json", json_ex, "Print one JSON object on stdout");
  ex->callback([] {
    set_json_mode(json_ex);
    const Rig rig = design::load_rig_or_builtin(rig_path);
    calib::PtoExportOptions opt;
    // Hugin resolves image names relative to the project file's folder.
    if (!frames.empty()) {
      namespace fs = std::filesystem;
      opt.frames_dir = fs::relative(fs::absolute(frames), fs::absolute(pto_path).parent_path()).string();
      if (opt.frames_dir.empty()) opt.frames_dir = fs::absolute(frames).string();
    }
    opt.pano_width = pano_width;
    opt.interpolator = interpolator;
    opt.linear_response = linear_response;
    if (pano_width < 8) throw std::invalid_argument("--pano-width must be at least 8");
    const calib::PtoExportSummary r = calib::export_pto(rig, opt);
    for (const auto& w : r.warnings) spdlog::warn("pto export: {}", w);
    write_text_atomically(pto_path, r.text);
    if (json_ex)
      print_json({{"cameras", rig.cameras.size()},
                  {"out", pto_path},
                  {"lens_fit_max_px", r.max_fit_px},
                  {"lens_fit_rms_px", r.rms_fit_px},
                  {"warnings", r.warnings}});
    else
      std::cout << fmt::format("{}: {} images, distortion conversion residual {:.4f} px max\n", pto_path,
                               rig.cameras.size(), r.max_fit_px);
  });
  auto* im = cmd->add_subcommand("import", "Read a Hugin project (rectilinear f0 images only) into a rig");
  im->add_option("PTO", in_path, "Project file (.pto)")->required();
  im->add_option("OUT_RIG", out_rig, "Rig to write (JSON, atomic)")->required();
  im->add_flag("--json", json_im, "Print one JSON object on stdout");
  im->callback([] {
    set_json_mode(json_im);
    const std::string text = read_text_file(in_path, kMaxTextFileBytes, "PTO file");
    const calib::PtoImportSummary r = calib::import_pto(text, std::filesystem::path(in_path).parent_path());
    for (const auto& w : r.warnings) spdlog::warn("pto import: {}", w);
    save_rig(r.rig, out_rig);
    if (json_im)
      print_json({{"cameras", r.rig.cameras.size()},
                  {"out", out_rig},
                  {"lens_fit_max_px", r.max_fit_px},
                  {"warnings", r.warnings}});
    else
      std::cout << fmt::format("{}: {} cameras, distortion conversion residual {:.4f} px max\n", out_rig,
                               r.rig.cameras.size(), r.max_fit_px);
  });
}

}  // namespace omma::app
