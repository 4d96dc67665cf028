// omma rig check | new | export | import: inspect rig files, build one from what a user knows (image
// sizes, focal lengths or fields of view, OpenCV calibration files, rough poses), and move rigs
// between omma, COLMAP (text model), OpenCV (calibration YAML/XML) and Hugin (PTO). The conventions
// are documented in src/omma/calib/colmap.h, opencv_calib.h and pto.h (docs/guide/interop.md).
#include "omma/core/rig.h"

#include <cmath>
#include <iostream>
#include <map>

#include <fmt/format.h>

#include "apps/command.h"
#include "omma/calib/colmap.h"
#include "omma/calib/opencv_calib.h"
#include "omma/calib/pto.h"
#include "omma/core/grid.h"
#include "omma/core/io.h"
#include "omma/core/log.h"
#include "omma/core/parse.h"
#include "omma/design/prototype.h"

namespace omma::app {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// --- omma rig new ---------------------------------------------------------------------------------

// One --camera SPEC: comma-separated KEY=VALUE items; a value may itself hold commas (ypr=Y,P,R):
// an item without '=' continues the previous value.
std::map<std::string, std::string> parse_spec(const std::string& spec, const std::string& where) {
  static const std::vector<std::string> kKeys = {"size",   "fov", "focal", "center", "dist",
                                                 "opencv", "ypr", "pos",   "id"};
  std::map<std::string, std::string> items;
  std::string last;
  size_t from = 0;
  while (from <= spec.size()) {
    size_t to = spec.find(',', from);
    if (to == std::string::npos) to = spec.size();
    const std::string item = spec.substr(from, to - from);
    from = to + 1;
    const size_t eq = item.find('=');
    if (eq == std::string::npos) {
      if (last.empty() || item.empty())
        throw std::invalid_argument(
            fmt::format("{}: '{}' is not KEY=VALUE (keys: size, fov, focal, center, dist, "
                        "opencv, ypr, pos, id)",
                        where, item));
      items[last] += "," + item;
      continue;
    }
    const std::string key = item.substr(0, eq);
    if (std::find(kKeys.begin(), kKeys.end(), key) == kKeys.end())
      throw std::invalid_argument(fmt::format(
          "{}: unknown key '{}' (keys: size, fov, focal, center, dist, opencv, ypr, pos, id)", where, key));
    if (items.count(key)) throw std::invalid_argument(fmt::format("{}: '{}' given twice", where, key));
    items[key] = item.substr(eq + 1);
    last = key;
  }
  return items;
}

// "a,b,c" as exactly n finite numbers; the error names the key.
std::vector<double> numbers(const std::string& text, size_t n_min, size_t n_max, const std::string& where,
                            const std::string& key) {
  std::vector<double> v;
  size_t from = 0;
  while (from <= text.size()) {
    size_t to = text.find(',', from);
    if (to == std::string::npos) to = text.size();
    const auto d = parse_double(text.substr(from, to - from));
    if (!d || !std::isfinite(*d))
      throw std::invalid_argument(
          fmt::format("{}: {}='{}' must be numbers separated by commas", where, key, text));
    v.push_back(*d);
    from = to + 1;
  }
  if (v.size() < n_min || v.size() > n_max)
    throw std::invalid_argument(
        n_min == n_max
            ? fmt::format("{}: {}='{}' must hold {} numbers", where, key, text, n_min)
            : fmt::format("{}: {}='{}' must hold {} to {} numbers", where, key, text, n_min, n_max));
  return v;
}

Size2 spec_size(const std::string& text, const std::string& where, const std::string& key) {
  try {
    return parse_size(text);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(fmt::format("{}: {}: {}", where, key, e.what()));
  }
}

Size2 image_size(const std::string& path) {
  const cv::Mat m = read_image(path);
  return Size2{m.cols, m.rows};
}

// "FILE" or "FILE:N" (N = 1, 2, ...: the camera of a stereo file).
std::pair<std::string, int> opencv_ref(const std::string& text, const std::string& where) {
  const size_t colon = text.rfind(':');
  if (colon != std::string::npos && colon + 1 < text.size() &&
      text.find_first_not_of("0123456789", colon + 1) == std::string::npos) {
    const std::string n = text.substr(colon + 1);
    if (n.size() > 4 || std::stoi(n) < 1)
      throw std::invalid_argument(
          fmt::format("{}: opencv='{}': the camera number must be 1, 2, ...", where, text));
    return {text.substr(0, colon), std::stoi(n)};
  }
  return {text, 1};
}

struct NewOptions {
  std::vector<std::string> cameras, images;
  std::string stereo, size, out, name;
  double baseline = -1, scale = 1;
  bool json = false;
};

RigCamera camera_from_spec(const std::string& spec, size_t index, const NewOptions& o,
                           std::vector<std::string>* warnings, double* fit_px) {
  const std::string where = fmt::format("--camera #{} '{}'", index + 1, spec);
  const auto items = parse_spec(spec, where);
  RigCamera c;
  c.id = int(index);
  if (items.count("id")) {
    const auto id = numbers(items.at("id"), 1, 1, where, "id")[0];
    if (id != std::floor(id) || id < 0 || id > 1e6)
      throw std::invalid_argument(
          fmt::format("{}: id='{}' must be an integer 0..1000000", where, items.at("id")));
    c.id = int(id);
  }
  // Size: size= > --images > --size > the OpenCV file.
  Size2 size;
  if (items.count("size"))
    size = spec_size(items.at("size"), where, "size");
  else if (!o.images.empty())
    size = image_size(o.images.at(index));
  else if (!o.size.empty())
    size = spec_size(o.size, where, "--size");
  if (items.count("opencv")) {
    for (const char* k : {"fov", "focal", "center", "dist"})
      if (items.count(k))
        throw std::invalid_argument(
            fmt::format("{}: {}= conflicts with opencv= (the file gives the intrinsics)", where, k));
    const auto [file, n] = opencv_ref(items.at("opencv"), where);
    const calib::OpenCvCalibration calib = calib::read_opencv_calibration(file);
    if (n > int(calib.cameras.size()))
      throw std::invalid_argument(fmt::format("{}: opencv='{}': {} holds {} camera(s)", where,
                                              items.at("opencv"), file, calib.cameras.size()));
    calib::LensConversion conv;
    c.in = calib::opencv_intrinsics(calib.cameras[n - 1], size.width, size.height, where, &conv, warnings);
    *fit_px = std::max(*fit_px, conv.max_px);
  } else {
    if (size.width == 0)
      throw std::invalid_argument(where + ": no image size: give size=WxH, --size WxH or --images");
    c.in.width = size.width;
    c.in.height = size.height;
    if (items.count("fov") == items.count("focal"))
      throw std::invalid_argument(where + ": give exactly one of fov=DEG (horizontal) and focal=PX[,PX]");
    if (items.count("fov")) {
      const double fov = numbers(items.at("fov"), 1, 1, where, "fov")[0];
      if (!(fov > 0 && fov < 180))
        throw std::invalid_argument(fmt::format("{}: fov={} must be in (0, 180) degrees", where, fov));
      c.in.fu = c.in.fv = Intrinsics::focal_for_aov(size.width, deg2rad(fov));
    } else {
      const auto f = numbers(items.at("focal"), 1, 2, where, "focal");
      for (double x : f)
        if (!(x > 0))
          throw std::invalid_argument(
              fmt::format("{}: focal={} must be positive pixels", where, items.at("focal")));
      c.in.fu = f[0];
      c.in.fv = f.size() > 1 ? f[1] : f[0];
    }
    c.in.cu = size.width / 2.0;
    c.in.cv = size.height / 2.0;
    if (items.count("center")) {
      const auto p = numbers(items.at("center"), 2, 2, where, "center");
      c.in.cu = p[0];
      c.in.cv = p[1];
    }
    if (items.count("dist")) {
      const auto d = numbers(items.at("dist"), 4, 5, where, "dist");
      c.in.k = calib::omma_k_from_opencv(d, c.in, where).k;
    }
    const std::string w = calib::choose_field(c.in, where);
    if (!w.empty()) warnings->push_back(w);
  }
  YawPitchRoll ypr{0, 0, kPi};  // upright, looking along +x
  if (items.count("ypr")) {
    const auto a = numbers(items.at("ypr"), 3, 3, where, "ypr");
    ypr = {deg2rad(a[0]), deg2rad(a[1]), deg2rad(a[2])};
  }
  c.frame = frame_from_ypr(ypr);
  if (items.count("pos")) {
    const auto p = numbers(items.at("pos"), 3, 3, where, "pos");
    c.position_mm = Vec3(p[0], p[1], p[2]);
  }
  try {
    validate_camera(c);
  } catch (const RigError& e) {
    throw std::invalid_argument(where + ": " + e.what());
  }
  return c;
}

json rig_summary(const Rig& rig) {
  json cams = json::array();
  for (const auto& c : rig.cameras)
    cams.push_back({{"id", c.id},
                    {"size", fmt::format("{}x{}", c.in.width, c.in.height)},
                    {"field", to_string(c.in.field)},
                    {"aov_deg", rad2deg(c.in.aov)}});
  return {{"name", rig.name},
          {"cameras", rig.cameras.size()},
          {"radius_mm", rig.dome.radius_mm},
          {"sphere", rig.dome.sphere},
          {"camera_list", cams}};
}

void run_new(const NewOptions& o) {
  set_json_mode(o.json);
  if (o.cameras.empty() == o.stereo.empty())
    throw std::invalid_argument(
        "give the cameras with --camera SPEC (one per camera) or --stereo FILE, not both");
  if (!(o.scale > 0 && std::isfinite(o.scale)))
    throw std::invalid_argument("--scale must be a positive number");
  if (o.baseline != -1 && !(o.baseline > 0 && std::isfinite(o.baseline)))
    throw std::invalid_argument("--baseline must be a positive number of mm");
  const std::string name = o.name.empty() ? fs::path(o.out).stem().string() : o.name;
  std::vector<std::string> warnings;
  double fit_px = 0;
  Rig rig;
  if (!o.stereo.empty()) {
    const calib::OpenCvCalibration calib = calib::read_opencv_calibration(o.stereo);
    if (calib.cameras.size() > 1 && calib.cameras[1].R && o.baseline > 0)
      throw std::invalid_argument("--baseline: " + o.stereo + " gives R, T between its cameras");
    calib::OpenCvRigOptions opt;
    if (!o.size.empty()) {
      const Size2 s = spec_size(o.size, "--stereo", "--size");
      opt.width = s.width, opt.height = s.height;
    }
    if (!o.images.empty()) {
      if (o.images.size() != calib.cameras.size())
        throw std::invalid_argument(fmt::format("--images: {} images for the {} cameras of {}",
                                                o.images.size(), calib.cameras.size(), o.stereo));
      for (const auto& im : o.images) {
        const Size2 s = image_size(im);
        opt.sizes.emplace_back(s.width, s.height);
      }
    }
    opt.baseline_mm = o.baseline;
    opt.scale_mm = o.scale;
    opt.name = name;
    calib::OpenCvRigSummary s = calib::rig_from_opencv(calib, opt);
    rig = std::move(s.rig);
    warnings.insert(warnings.end(), s.warnings.begin(), s.warnings.end());
    fit_px = s.max_fit_px;
    if (calib.cameras.size() > 1 && !calib.cameras[1].R && o.baseline > 0)
      warnings.push_back(
          fmt::format("{} holds no R, T: the cameras sit {} mm apart along camera 1's image x axis", o.stereo,
                      o.baseline));
  } else {
    if (!o.images.empty() && o.images.size() != o.cameras.size())
      throw std::invalid_argument(
          fmt::format("--images: {} images for {} --camera specs", o.images.size(), o.cameras.size()));
    if (o.baseline != -1)
      throw std::invalid_argument("--baseline goes with --stereo (use pos=X,Y,Z in --camera)");
    rig.name = name;
    for (size_t i = 0; i < o.cameras.size(); ++i)
      rig.cameras.push_back(camera_from_spec(o.cameras[i], i, o, &warnings, &fit_px));
    rig.dome = calib::dome_around(rig, "rig new");
  }
  rig.validate();
  save_rig(rig, o.out);
  for (const auto& w : warnings) spdlog::warn("rig new: {}", w);
  if (o.json) {
    json j = rig_summary(rig);
    j["out"] = o.out;
    j["lens_fit_max_px"] = fit_px;
    j["warnings"] = warnings;
    print_json(j);
  } else {
    std::cout << fmt::format("{}: rig '{}' of {} camera(s), dome radius {:.4g} mm ({})\n", o.out, rig.name,
                             rig.cameras.size(), rig.dome.radius_mm,
                             rig.dome.sphere ? "sphere" : "hemisphere");
  }
}

// --- omma rig export ------------------------------------------------------------------------------

struct ExportOptions {
  std::string rig, colmap, pto, frames, opencv;
  bool json = false;
};

void run_export(const ExportOptions& o) {
  set_json_mode(o.json);
  if (o.colmap.empty() && o.pto.empty() && o.opencv.empty())
    throw std::invalid_argument("nothing to export: give --colmap DIR, --pto FILE and/or --opencv FILE");
  const Rig rig = design::load_rig_or_builtin(o.rig);
  json j = {{"rig", o.rig}, {"cameras", rig.cameras.size()}};
  std::vector<std::string> warnings;
  if (!o.colmap.empty()) {
    const calib::ColmapExportSummary s = calib::export_colmap(rig, o.colmap);
    j["colmap"] = o.colmap;
    j["colmap_models"] = s.models;
    if (!o.json) {
      std::string models;
      for (const auto& [m, n] : s.models) models += fmt::format("{}{} {}", models.empty() ? "" : ", ", n, m);
      std::cout << fmt::format("{}: COLMAP text model of {} cameras ({}), lengths in mm, exact\n", o.colmap,
                               rig.cameras.size(), models);
    }
  }
  if (!o.pto.empty()) {
    calib::PtoExportOptions opt;
    if (!o.frames.empty()) {  // Hugin resolves image names relative to the project file's folder
      opt.frames_dir = fs::relative(fs::absolute(o.frames), fs::absolute(o.pto).parent_path()).string();
      if (opt.frames_dir.empty()) opt.frames_dir = fs::absolute(o.frames).string();
    }
    const calib::PtoExportSummary s = calib::export_pto(rig, opt);
    write_text_atomically(o.pto, s.text);
    for (const auto& w : s.warnings) warnings.push_back("pto: " + w);
    j["pto"] = o.pto;
    j["pto_lens_fit_max_px"] = s.max_fit_px;
    if (!o.json)
      std::cout << fmt::format("{}: Hugin project, distortion conversion residual {:.4f} px max\n", o.pto,
                               s.max_fit_px);
  } else if (!o.frames.empty()) {
    throw std::invalid_argument("--frames goes with --pto");
  }
  if (!o.opencv.empty()) {
    calib::write_opencv_calibration(rig, o.opencv);
    j["opencv"] = o.opencv;
    j["opencv_layout"] = rig.cameras.size() == 1 ? "calibration" : "stereo";
    for (const auto& c : rig.cameras)
      if (c.photometric) {
        warnings.push_back("opencv: the photometric models are not written (OpenCV's files hold none)");
        break;
      }
    if (!o.json)
      std::cout << fmt::format("{}: OpenCV calibration file ({} layout), exact\n", o.opencv,
                               rig.cameras.size() == 1 ? "calibration" : "stereo");
  }
  for (const auto& w : warnings) spdlog::warn("rig export: {}", w);
  j["warnings"] = warnings;
  if (o.json) print_json(j);
}

// --- omma rig import ------------------------------------------------------------------------------

struct ImportOptions {
  std::string path, out, size, name;
  std::vector<std::string> images;
  double scale = 1, baseline = -1;
  bool keep_origin = false, json = false;
};

void run_import(const ImportOptions& o) {
  set_json_mode(o.json);
  if (!(o.scale > 0 && std::isfinite(o.scale)))
    throw std::invalid_argument("--scale must be a positive number");
  const fs::path p(o.path);
  const std::string ext = lower_extension(p);
  json j = {{"in", o.path}, {"out", o.out}};
  std::vector<std::string> warnings;
  Rig rig;
  double fit_px = 0;
  const bool colmap = fs::is_directory(p) || p.filename() == "cameras.txt" || p.filename() == "images.txt";
  auto only = [&](const std::string& format, bool size_ok, bool scale_ok, bool baseline_ok, bool origin_ok) {
    if (!size_ok && (!o.size.empty() || !o.images.empty()))
      throw std::invalid_argument("--size / --images do not apply to a " + format +
                                  " (it holds the image sizes)");
    if (!scale_ok && o.scale != 1) throw std::invalid_argument("--scale does not apply to a " + format);
    if (!baseline_ok && o.baseline != -1)
      throw std::invalid_argument("--baseline does not apply to a " + format);
    if (!origin_ok && o.keep_origin)
      throw std::invalid_argument("--keep-origin does not apply to a " + format);
  };
  if (colmap) {
    only("COLMAP model", false, true, false, true);
    calib::ColmapImportOptions opt;
    opt.scale_mm = o.scale;
    opt.keep_origin = o.keep_origin;
    opt.name = o.name;
    calib::ColmapImportSummary s = calib::import_colmap(p, opt);
    rig = std::move(s.rig);
    warnings = s.warnings;
    fit_px = s.max_fit_px;
    j["format"] = "colmap";
    j["model_dir"] = s.model_dir.string();
    j["colmap_models"] = s.models;
    json images = json::array();
    for (const auto& [name, id] : s.images) images.push_back({{"name", name}, {"id", id}});
    j["images"] = images;
    j["ids_from_names"] = s.ids_from_names;
    j["omma_metadata"] = s.omma_metadata;
  } else if (ext == ".pto") {
    only("Hugin project", false, false, false, false);
    const std::string text = read_text_file(p, kMaxTextFileBytes, "PTO file");
    calib::PtoImportSummary s = calib::import_pto(text, p.parent_path());
    rig = std::move(s.rig);
    warnings = s.warnings;
    fit_px = s.max_fit_px;
    if (!o.name.empty()) rig.name = o.name;
    j["format"] = "pto";
  } else if (ext == ".yml" || ext == ".yaml" || ext == ".xml") {
    only("OpenCV calibration file", true, true, true, false);
    const calib::OpenCvCalibration calib = calib::read_opencv_calibration(p);
    calib::OpenCvRigOptions opt;
    if (!o.size.empty()) {
      const Size2 s = spec_size(o.size, "rig import", "--size");
      opt.width = s.width, opt.height = s.height;
    }
    for (const auto& im : o.images) {
      const Size2 s = image_size(im);
      opt.sizes.emplace_back(s.width, s.height);
    }
    opt.scale_mm = o.scale;
    opt.baseline_mm = o.baseline;
    opt.name = o.name.empty() ? p.stem().string() : o.name;
    calib::OpenCvRigSummary s = calib::rig_from_opencv(calib, opt);
    rig = std::move(s.rig);
    warnings = s.warnings;
    fit_px = s.max_fit_px;
    j["format"] = "opencv";
    j["opencv_layout"] = calib.layout;
  } else {
    throw std::invalid_argument(
        o.path +
        ": not a COLMAP text model folder, a Hugin project (.pto) or an OpenCV calibration "
        "file (.yml, .yaml, .xml)");
  }
  rig.validate();
  save_rig(rig, o.out);
  for (const auto& w : warnings) spdlog::warn("rig import: {}", w);
  if (o.json) {
    j.update(rig_summary(rig));
    j["lens_fit_max_px"] = fit_px;
    j["warnings"] = warnings;
    print_json(j);
  } else {
    std::cout << fmt::format(
        "{}: rig '{}' of {} camera(s) from {} (distortion conversion residual {:.4f} px max)\n", o.out,
        rig.name, rig.cameras.size(), o.path, fit_px);
  }
}

}  // namespace

void add_rig_command(CLI::App& root) {
  auto* cmd = root.add_subcommand(
      "rig",
      "Inspect rig files, build one from what you know, move rigs between omma, COLMAP, OpenCV and Hugin");
  cmd->require_subcommand(1);
  auto* check = cmd->add_subcommand("check", "Load and validate a rig file, print a summary");
  static std::string path;
  static bool json = false;
  check->add_option("RIG", path, "Rig file (JSON)")->required();
  check->add_flag("--json", json, "Print one JSON object on stdout");
  check->callback([] {
    set_json_mode(json);
    const Rig rig = design::load_rig_or_builtin(path);
    double min_aov = 1e9, max_aov = 0;
    for (const auto& c : rig.cameras) {
      min_aov = std::min(min_aov, rad2deg(c.in.aov));
      max_aov = std::max(max_aov, rad2deg(c.in.aov));
    }
    if (json) {
      print_json({{"name", rig.name},
                  {"cameras", rig.cameras.size()},
                  {"radius_mm", rig.dome.radius_mm},
                  {"sphere", rig.dome.sphere},
                  {"aov_deg_min", min_aov},
                  {"aov_deg_max", max_aov},
                  {"valid", true}});
    } else {
      std::cout << fmt::format(
          "{}: valid rig '{}', {} cameras on a {} of radius {} mm, AOV {:.1f}-{:.1f} deg\n", path, rig.name,
          rig.cameras.size(), rig.dome.sphere ? "sphere" : "hemisphere", rig.dome.radius_mm, min_aov,
          max_aov);
    }
  });

  static NewOptions nw;
  auto* mk = cmd->add_subcommand(
      "new",
      "Build a rig from what you know of its cameras: image size, focal length or field of view, or an "
      "OpenCV "
      "calibration file, and rough poses. A camera without ypr looks along +x with its image upright "
      "(ypr=0,0,180); each camera sees its whole image (field \"image\")");
  mk->add_option("--out", nw.out, "Rig file to write (JSON, atomic)")->required();
  mk->add_option(
      "--camera", nw.cameras,
      "One camera (repeat for each): comma-separated KEY=VALUE items: size=WxH (pixels), fov=DEG "
      "(horizontal) or focal=PX[,PX] (fu, fv), center=CU,CV (pixels, centre of the top-left pixel at "
      "0.5,0.5; default the image centre), dist=K1,K2,P1,P2[,K3] (OpenCV's order and formula), or "
      "opencv=FILE[:N] (camera N of an OpenCV calibration file instead of fov/focal/center/dist); "
      "ypr=Y,P,R (yaw, pitch, roll in degrees, thesis eq. 3.13: ypr=0,0,180 looks along +x upright, yaw "
      "turns the view towards -y, pitch up towards +z), pos=X,Y,Z (mm), id=N "
      "(default: the order given). E.g. size=640x480,fov=60,ypr=-30,0,180,pos=0,10,0");
  mk->add_option(
      "--stereo", nw.stereo,
      "An OpenCV stereo calibration file (M1, D1, M2, D2 [, R, T]): the two-camera rig it describes; "
      "without R, T the cameras sit --baseline mm apart along camera 1's image x axis");
  mk->add_option("--size", nw.size, "Image size WxH of every camera that does not say (e.g. 640x480)");
  mk->add_option("--images", nw.images, "One image per camera (in order): each camera's size is its image's")
      ->expected(1, -1);
  mk->add_option("--baseline", nw.baseline, "With --stereo and no R, T in the file: the baseline in mm");
  mk->add_option("--scale", nw.scale,
                 "With --stereo: mm per unit of the file's T (its chessboard unit); default 1");
  mk->add_option("--name", nw.name, "Rig name (default: the --out file's stem)");
  mk->add_flag("--json", nw.json, "Print one JSON object on stdout");
  mk->callback([] { run_new(nw); });

  static ExportOptions ex;
  auto* exp = cmd->add_subcommand(
      "export",
      "Write a rig as a COLMAP text model, a Hugin project and/or an OpenCV calibration file (conventions: "
      "docs/guide/interop.md)");
  exp->add_option("RIG", ex.rig, "Rig (JSON file or built-in name)")->required();
  exp->add_option(
      "--colmap", ex.colmap,
      "Folder to write cameras.txt, images.txt, points3D.txt into (lengths in mm; PINHOLE, OPENCV or "
      "FULL_OPENCV: exact)");
  exp->add_option("--pto", ex.pto, "Hugin project to write (.pto; distortion beyond k1 is fitted)");
  exp->add_option("--frames", ex.frames, "With --pto: the frames folder the project's images are in");
  exp->add_option(
      "--opencv", ex.opencv,
      "OpenCV calibration file to write (.yml/.yaml or .xml): camera_matrix for one camera, M1, D1, "
      "M2, D2, R, T (mm) for two or more; exact");
  exp->add_flag("--json", ex.json, "Print one JSON object on stdout");
  exp->callback([] { run_export(ex); });

  static ImportOptions im;
  auto* imp = cmd->add_subcommand(
      "import",
      "Read a COLMAP text model (a folder with cameras.txt and images.txt, or with 0/ or sparse/0/), a Hugin "
      "project (.pto) or an OpenCV calibration file (.yml, .yaml, .xml) as a rig");
  imp->add_option("PATH", im.path, "COLMAP model folder, .pto, or OpenCV .yml/.yaml/.xml")->required();
  imp->add_option("--out", im.out, "Rig file to write (JSON, atomic)")->required();
  imp->add_option(
      "--scale", im.scale,
      "mm per length unit of the file (a COLMAP model's arbitrary unit, an OpenCV file's T); default 1");
  imp->add_option("--size", im.size,
                  "OpenCV files without image_width/image_height: every camera's size WxH");
  imp->add_option("--images", im.images, "OpenCV files: one image per camera (in order), giving its size")
      ->expected(1, -1);
  imp->add_option("--baseline", im.baseline, "OpenCV stereo files without R, T: the baseline in mm");
  imp->add_flag(
      "--keep-origin", im.keep_origin,
      "COLMAP models not written by omma: keep COLMAP's world origin as the dome centre (default: the "
      "cameras' centroid)");
  imp->add_option("--name", im.name, "Rig name (default: from the file or folder)");
  imp->add_flag("--json", im.json, "Print one JSON object on stdout");
  imp->callback([] { run_import(im); });
}

}  // namespace omma::app
