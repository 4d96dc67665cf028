// omma refocus: synthetic-aperture refocusing of a frames folder (pano/refocus.h): the rig's
// overlapping cameras as one large lens focused on a sphere (or a depth map) around the rig.
#include "omma/pano/refocus.h"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <stdexcept>

#include <fmt/format.h>

#include "apps/command.h"
#include "apps/depth_spec.h"
#include "apps/grid_args.h"
#include "apps/sheet.h"
#include "omma/core/frames.h"
#include "omma/core/io.h"
#include "omma/core/parse.h"
#include "omma/design/prototype.h"
#include "omma/io/metadata.h"

namespace omma::app {
namespace {
namespace fs = std::filesystem;

struct RefocusArgs {
  std::string rig, frames, out = "refocus.png", projection = "vr180", size;
  std::vector<std::string> focus{"1000"};
  std::string focus_depth, stack;
  std::string aperture = "inf", shape = "gaussian", combine = "mean";
  double consensus = 0.1, feather = 0.05;
  bool json = false;
};

double parse_mm(const std::string& text, const std::string& what) {
  if (text == "inf") return std::numeric_limits<double>::infinity();
  const std::optional<double> v = parse_double(text);  // core/parse.h
  if (!v || !(*v >= 0))
    throw std::invalid_argument(what + " must be a distance in mm or 'inf', got '" + text + "'");
  return *v;
}

// OUT for one focus; OUT_<F>mm.EXT for each of several.
fs::path output_for(const fs::path& out, double focus_mm, bool several) {
  if (!several) return out;
  const std::string tag = std::isinf(focus_mm) ? "inf" : fmt::format("{:05.0f}mm", focus_mm);
  return out.parent_path() / (out.stem().string() + "_" + tag + out.extension().string());
}

void run_refocus(const RefocusArgs& a) {
  set_json_mode(a.json);
  // Everything is checked before any work.
  const PanoGrid grid = grid_from_args(a.projection, a.size);
  check_image_format(a.out, grid.width, grid.height);
  pano::RefocusOptions base;
  base.grid = grid;
  base.aperture_mm = parse_mm(a.aperture, "--aperture");
  base.shape = pano::parse_aperture_shape(a.shape);
  base.combine = pano::parse_refocus_combine(a.combine);
  base.consensus_gray = a.consensus;
  base.feather = a.feather;
  std::vector<double> focus;
  if (a.focus_depth.empty())
    for (const auto& f : a.focus) {
      focus.push_back(parse_mm(f, "--focus"));
      if (!(focus.back() > 0)) throw std::invalid_argument("--focus must be > 0 mm");
    }
  std::string why;
  if (!base.IsValid(&why)) throw std::invalid_argument(why);
  const Rig rig = design::load_rig_or_builtin(a.rig);
  const std::vector<cv::Mat> frames = load_frames(a.frames, rig);

  nlohmann::json js{{"rig", rig.name},
                    {"cameras", rig.cameras.size()},
                    {"grid", {to_string(grid.projection), grid.width, grid.height}},
                    {"aperture_mm",
                     std::isinf(base.aperture_mm) ? nlohmann::json("inf") : nlohmann::json(base.aperture_mm)},
                    {"shape", pano::to_string(base.shape)},
                    {"combine", pano::to_string(base.combine)}};
  std::vector<cv::Mat> stack;
  std::vector<std::string> labels;
  nlohmann::json outputs = nlohmann::json::array();
  auto one = [&](pano::RefocusOptions o, const fs::path& path, const std::string& label,
                 nlohmann::json facts) {
    const auto t0 = std::chrono::steady_clock::now();
    const pano::RefocusSummary r = pano::refocus(rig, frames, o);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const cv::Mat img = to_u8(r.image);
    io::write_panorama(path, img, grid);  // with the 360-degree XMP where the grid allows
    facts["file"] = path.string();
    facts["seconds"] = s;
    facts["mean_cameras"] = r.mean_cameras;
    outputs.push_back(facts);
    stack.push_back(img);
    labels.push_back(label);
    if (!a.json)
      fmt::print("{}: {} ({:.1f} s, {:.2f} cameras per direction)\n", path.string(), label, s,
                 r.mean_cameras);
  };
  if (!a.focus_depth.empty()) {
    const DepthChoice d = choose_depth(a.focus_depth, "", rig, frames, grid);
    pano::RefocusOptions o = base;
    o.focus_mm = std::numeric_limits<double>::infinity();
    o.focus_depth = d.depth;
    one(o, a.out, "focus: depth " + a.focus_depth, {{"focus", d.info}});
  } else {
    for (double f : focus) {
      pano::RefocusOptions o = base;
      o.focus_mm = f;
      one(o, output_for(a.out, f, focus.size() > 1),
          std::isinf(f) ? "focus inf" : fmt::format("focus {:.0f} mm", f),
          {{"focus_mm", std::isinf(f) ? nlohmann::json("inf") : nlohmann::json(f)}});
    }
  }
  js["outputs"] = outputs;
  if (!a.stack.empty()) {
    write_image(a.stack, labelled_sheet(stack, labels, 4, 480));  // 4 per row
    js["stack"] = a.stack;
  }
  if (a.json) print_json(js);
}

}  // namespace

void add_refocus_command(CLI::App& root) {
  static RefocusArgs a;
  auto* cmd = root.add_subcommand(
      "refocus",
      "Synthetic-aperture refocusing (the Stanford camera array's trick): every camera that sees a\n"
      "direction's point on the focal surface is sampled there and averaged with an aperture weight,\n"
      "so objects on the surface stay sharp, those off it blur in proportion to |1/Z - 1/F|, and a\n"
      "thin occluder in front of the surface fades (see through it with --combine median).");
  cmd->add_option("--rig", a.rig, "Rig file or built-in rig name")->required();
  cmd->add_option("--frames", a.frames, "Frames folder: DIR/cam_XX.png, one per camera id")->required();
  cmd->add_option("--focus", a.focus,
                  "Focal distance(s) from the rig centre, mm, or inf; several (e.g. --focus 600 1200 2400)\n"
                  "write a focal stack: OUT_<F>mm.EXT each")
      ->capture_default_str();
  cmd->add_option(
      "--focus-depth", a.focus_depth,
      std::string("A focal SURFACE instead of a distance (every direction in focus at its own depth):\n") +
          kDepthSpecHelp);
  cmd->add_option("--aperture", a.aperture,
                  "Synthetic aperture radius A, mm (a camera's weight exp(-r^2 / 2A^2), r its distance from\n"
                  "the direction's ray, eq. 2.5); inf = every camera alike, 0 = the nearest camera only")
      ->capture_default_str();
  cmd->add_option("--shape", a.shape, "Aperture shape: gaussian | box")->capture_default_str();
  cmd->add_option("--combine", a.combine,
                  "mean (the classic synthetic aperture) | median (consensus: removes occluders that\n"
                  "a minority of the cameras see)")
      ->capture_default_str();
  cmd->add_option("--consensus", a.consensus, "With --combine median: gray-level tolerance around the median")
      ->capture_default_str();
  cmd->add_option("--feather", a.feather, "Weight ramp at each image's border, fraction of its smaller side")
      ->capture_default_str();
  cmd->add_option("--projection", a.projection, "vr180 | equirect | equirect-full | equirect-100")
      ->capture_default_str();
  cmd->add_option("--size", a.size, "Output size WxH (default 1080x1080 vr180, 1920x960 equirect-full, ...)");
  cmd->add_option("--out", a.out, "Output image (PNG/JPEG)")->capture_default_str();
  cmd->add_option("--stack", a.stack, "Also write the focal stack side by side into this image");
  cmd->add_flag("--json", a.json, "Print one JSON summary on stdout");
  cmd->callback([] { run_refocus(a); });
}

}  // namespace omma::app
