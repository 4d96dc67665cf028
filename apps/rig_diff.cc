// omma rig-diff A B: camera-by-camera differences between two rigs (e.g. calibrated vs true).
#include "omma/calib/rig_diff.h"

#include <iostream>

#include <fmt/format.h>

#include "apps/command.h"
#include "omma/design/prototype.h"

namespace omma::app {

void add_rig_diff_command(CLI::App& root) {
  static std::string a_path, b_path;
  static bool json = false, align = false;
  auto* cmd = root.add_subcommand(
      "rig-diff",
      "Compare two rigs camera by camera (paired by id): orientation error = angle of the relative rotation\n"
      "of the (t, u, v) frames (degrees), focal error = |f_A - f_B| / f_B (larger of fu, fv), centre error "
      "=\n"
      "|(cu, cv)_A - (cu, cv)_B| (pixels), ray error = RMS angle between the rays A and B give the same\n"
      "pixels (degrees; what a stitch sees); median and max over the cameras.");
  cmd->add_option("A", a_path, "First rig (JSON), e.g. the calibrated one")->required();
  cmd->add_option("B", b_path, "Second rig (JSON), e.g. the true one")->required();
  cmd->add_flag("--align", align,
                "First remove the global rotation between the rigs (the far-field gauge: a "
                "distant scene cannot tell a rig from a rotated copy)");
  cmd->add_flag("--json", json, "Print one JSON object on stdout");
  cmd->callback([] {
    set_json_mode(json);
    const calib::RigDiff d =
        calib::diff_rigs(design::load_rig_or_builtin(a_path), design::load_rig_or_builtin(b_path), align);
    auto stat = [](const calib::Stat& s) {
      return nlohmann::json{{"median", s.median}, {"max", s.max}, {"mean", s.mean}};
    };
    if (json) {
      const double align_deg = rad2deg(Eigen::AngleAxisd(d.alignment).angle());
      print_json({{"orientation_error_deg", stat(d.orientation_error_deg)},
                  {"focal_error_rel", stat(d.focal_error_rel)},
                  {"center_error_px", stat(d.center_error_px)},
                  {"ray_error_deg", stat(d.ray_error_deg)},
                  {"cameras", d.per_camera_orientation_deg.size()},
                  {"aligned", align},
                  {"alignment_deg", align_deg}});
    } else {
      std::cout << fmt::format(
          "orientation error {:.4f} deg median, {:.4f} max; focal error {:.3f} % median, {:.3f} % max; "
          "centre error "
          "{:.3f} px median, {:.3f} px max; ray error {:.4f} deg median, {:.4f} max\n",
          d.orientation_error_deg.median, d.orientation_error_deg.max, 100 * d.focal_error_rel.median,
          100 * d.focal_error_rel.max, d.center_error_px.median, d.center_error_px.max,
          d.ray_error_deg.median, d.ray_error_deg.max);
    }
  });
}

}  // namespace omma::app
