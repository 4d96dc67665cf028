#include "omma/calib/colmap.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <regex>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "omma/calib/opencv_calib.h"
#include "omma/core/frames.h"
#include "omma/core/io.h"
#include "omma/core/limits.h"
#include "omma/core/parse.h"

namespace omma::calib {
namespace {

namespace fs = std::filesystem;

constexpr const char* kOmmaTag = "# omma-rig ";

std::string num(double v) { return fmt::format("{}", v); }  // shortest text that reads back exactly

std::vector<std::string> split_words(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> w;
  std::string s;
  while (in >> s) w.push_back(s);
  return w;
}

std::string trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t\r\n");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t\r\n") - a + 1);
}

double to_double(const std::string& s, const std::string& where) {
  const auto v = parse_double(s);
  if (!v || !std::isfinite(*v)) throw ColmapError(where + ": '" + s + "' is not a finite number");
  return *v;
}

long long to_id(const std::string& s, const std::string& where) {
  const auto v = parse_double(s);
  if (!v || *v != std::floor(*v) || *v < 0 || *v > 4294967295.0 ||
      s.find_first_not_of("0123456789") != std::string::npos)
    throw ColmapError(where + ": '" + s + "' is not an identifier (an integer 0..2^32-1)");
  return static_cast<long long>(*v);
}

int to_side(const std::string& s, const std::string& where) {
  const long long v = to_id(s, where);
  if (v < 1 || v > kMaxImageSide)
    throw ColmapError(fmt::format("{}: image side {} is not in 1..{}", where, v, kMaxImageSide));
  return int(v);
}

bool same(double a, double b) { return std::abs(a - b) <= 1e-9 * std::max(1.0, std::abs(a)); }

bool same_intrinsics(const Intrinsics& a, const Intrinsics& b) {
  if (a.width != b.width || a.height != b.height) return false;
  if (!same(a.fu, b.fu) || !same(a.fv, b.fv) || !same(a.cu, b.cu) || !same(a.cv, b.cv)) return false;
  for (int i = 0; i < 5; ++i)
    if (!same(a.k[i], b.k[i])) return false;
  return true;
}

std::string model_folder_name(fs::path dir) {
  dir = fs::absolute(dir).lexically_normal();
  if (dir.filename().empty()) dir = dir.parent_path();
  while (!dir.filename().empty()) {
    const std::string n = dir.filename().string();
    if (n != "sparse" && n.find_first_not_of("0123456789") != std::string::npos) return n;
    dir = dir.parent_path();
  }
  return "colmap";
}

}  // namespace

ColmapCamera colmap_camera(const Intrinsics& in, long long id) {
  ColmapCamera c;
  c.id = id;
  c.width = in.width;
  c.height = in.height;
  const auto& k = in.k;
  c.params = {in.fu, in.fv, in.cu, in.cv};
  if (!in.has_distortion()) {
    c.model = "PINHOLE";
  } else if (k[4] == 0) {
    c.model = "OPENCV";
    c.params.insert(c.params.end(), {k[0], k[1], k[3], k[2]});
  } else {
    c.model = "FULL_OPENCV";
    c.params.insert(c.params.end(), {k[0], k[1], k[3], k[2], k[4], 0, 0, 0});
  }
  return c;
}

Intrinsics intrinsics_from_colmap(const ColmapCamera& cam, const std::string& where, double* max_fit_px,
                                  std::vector<std::string>* warnings) {
  static const std::map<std::string, size_t> kParams = {{"SIMPLE_PINHOLE", 3}, {"PINHOLE", 4},
                                                        {"SIMPLE_RADIAL", 4},  {"RADIAL", 5},
                                                        {"OPENCV", 8},         {"FULL_OPENCV", 12}};
  const auto it = kParams.find(cam.model);
  if (it == kParams.end())
    throw ColmapError(fmt::format(
        "{}: COLMAP camera model {} has no counterpart in omma's camera model (pinhole with radial and "
        "tangential distortion: SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV, FULL_OPENCV); "
        "undistort "
        "the images with `colmap image_undistorter` and import the undistorted (PINHOLE) model",
        where, cam.model));
  const auto& p = cam.params;
  if (p.size() != it->second)
    throw ColmapError(
        fmt::format("{}: model {} takes {} parameters, not {}", where, cam.model, it->second, p.size()));
  Intrinsics in;
  in.width = cam.width;
  in.height = cam.height;
  std::vector<double> d;  // OpenCV's order
  if (cam.model == "SIMPLE_PINHOLE" || cam.model == "SIMPLE_RADIAL" || cam.model == "RADIAL") {
    in.fu = in.fv = p[0];
    in.cu = p[1];
    in.cv = p[2];
    if (cam.model == "SIMPLE_RADIAL") d = {p[3], 0, 0, 0};
    if (cam.model == "RADIAL") d = {p[3], p[4], 0, 0};
  } else {
    in.fu = p[0];
    in.fv = p[1];
    in.cu = p[2];
    in.cv = p[3];
    d.assign(p.begin() + 4, p.end());
  }
  if (!(in.fu > 0 && in.fv > 0)) throw ColmapError(where + ": focal lengths must be positive");
  const LensConversion c = omma_k_from_opencv(d, in, where);
  in.k = c.k;
  if (max_fit_px) *max_fit_px = c.max_px;
  if (!c.note.empty() && warnings) warnings->push_back(c.note);
  const std::string w = choose_field(in, where);
  if (!w.empty() && warnings) warnings->push_back(w);
  return in;
}

ColmapText colmap_text(const Rig& rig) {
  rig.validate();
  ColmapText t;
  std::ostringstream cams, imgs;
  cams << "# Camera list with one line of data per camera:\n"
       << "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
       << "# Number of cameras: " << rig.cameras.size() << "\n"
       << "# Written by omma: lengths in mm, pixel centres at +0.5 (as COLMAP), models PINHOLE / OPENCV / "
          "FULL_OPENCV exact.\n"
       << kOmmaTag << rig_to_json(rig).dump() << "\n";
  imgs << "# Image list with two lines of data per image:\n"
       << "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
       << "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
       << "# Number of images: " << rig.cameras.size() << ", mean observations per image: 0\n";
  for (size_t i = 0; i < rig.cameras.size(); ++i) {
    const RigCamera& c = rig.cameras[i];
    const long long id = static_cast<long long>(i) + 1;
    const ColmapCamera cc = colmap_camera(c.in, id);
    cams << id << " " << cc.model << " " << cc.width << " " << cc.height;
    for (double v : cc.params) cams << " " << num(v);
    cams << "\n";
    Mat3 R;  // world (dome) -> camera: rows u, v, t
    R.row(0) = c.frame.u.transpose();
    R.row(1) = c.frame.v.transpose();
    R.row(2) = c.frame.t.transpose();
    Eigen::Quaterniond q(R);
    q.normalize();
    if (q.w() < 0) q.coeffs() = -q.coeffs();
    const Vec3 T = -R * c.position_mm;
    imgs << id << " " << num(q.w()) << " " << num(q.x()) << " " << num(q.y()) << " " << num(q.z()) << " "
         << num(T.x()) << " " << num(T.y()) << " " << num(T.z()) << " " << id << " " << frame_filename(c.id)
         << "\n\n";
  }
  t.cameras = cams.str();
  t.images = imgs.str();
  t.points3D =
      "# 3D point list with one line of data per point:\n"
      "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
      "# Number of points: 0, mean track length: 0\n";
  return t;
}

ColmapExportSummary export_colmap(const Rig& rig, const fs::path& dir) {
  const ColmapText t = colmap_text(rig);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) throw ColmapError("cannot create the folder " + dir.string());
  write_text_atomically(dir / "cameras.txt", t.cameras);
  write_text_atomically(dir / "images.txt", t.images);
  write_text_atomically(dir / "points3D.txt", t.points3D);
  ColmapExportSummary s;
  for (const auto& c : rig.cameras) ++s.models[colmap_camera(c.in, 0).model];
  return s;
}

fs::path find_colmap_model(const fs::path& path) {
  if (!fs::exists(path)) throw ColmapError("COLMAP model " + path.string() + " does not exist");
  if (fs::is_regular_file(path)) {
    const std::string n = path.filename().string();
    if (n == "cameras.txt" || n == "images.txt" || n == "points3D.txt")
      return path.parent_path().empty() ? "." : path.parent_path();
    throw ColmapError(path.string() + " is not a COLMAP model folder (cameras.txt, images.txt)");
  }
  for (const fs::path& d : {path, path / "0", path / "sparse" / "0", path / "sparse"}) {
    if (fs::is_regular_file(d / "cameras.txt") && fs::is_regular_file(d / "images.txt")) return d;
    if (fs::is_regular_file(d / "cameras.bin"))
      throw ColmapError(fmt::format(
          "{} holds a binary COLMAP model: convert it to text first: colmap model_converter --input_path {} "
          "--output_path {} --output_type TXT",
          d.string(), d.string(), d.string()));
  }
  throw ColmapError(path.string() +
                    ": no COLMAP text model (cameras.txt and images.txt) here or in 0/ or sparse/0/");
}

ColmapImportSummary import_colmap(const fs::path& path, const ColmapImportOptions& opt) {
  const fs::path dir = find_colmap_model(path);
  const std::string cams = read_text_file(dir / "cameras.txt", kMaxTextFileBytes, "COLMAP cameras file");
  const std::string imgs = read_text_file(dir / "images.txt", kMaxTextFileBytes, "COLMAP images file");
  ColmapImportSummary s = import_colmap_text(cams, imgs, opt, model_folder_name(dir));
  s.model_dir = dir;
  return s;
}

ColmapImportSummary import_colmap_text(const std::string& cameras_txt, const std::string& images_txt,
                                       const ColmapImportOptions& opt, const std::string& folder_name) {
  if (!(opt.scale_mm > 0 && std::isfinite(opt.scale_mm)))
    throw std::invalid_argument("the scale (mm per COLMAP unit) must be a positive number");
  ColmapImportSummary s;
  // cameras.txt
  std::map<long long, ColmapCamera> cameras;
  std::optional<Rig> meta;
  {
    std::istringstream in(cameras_txt);
    std::string line;
    int ln = 0;
    while (std::getline(in, line)) {
      ++ln;
      const std::string where = fmt::format("cameras.txt line {}", ln);
      if (line.rfind(kOmmaTag, 0) == 0) {
        try {
          meta = rig_from_json(nlohmann::json::parse(line.substr(std::string(kOmmaTag).size())));
        } catch (const std::exception& e) {
          s.warnings.push_back(where +
                               ": ignoring omma's comment, which does not hold a valid rig: " + e.what());
        }
        continue;
      }
      const std::string t = trim(line);
      if (t.empty() || t[0] == '#') continue;
      const auto w = split_words(t);
      if (w.size() < 4) throw ColmapError(where + ": expected CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]");
      ColmapCamera c;
      c.id = to_id(w[0], where);
      c.model = w[1];
      c.width = to_side(w[2], where);
      c.height = to_side(w[3], where);
      for (size_t i = 4; i < w.size(); ++i) c.params.push_back(to_double(w[i], where));
      if (!cameras.emplace(c.id, c).second)
        throw ColmapError(fmt::format("{}: camera {} appears twice", where, c.id));
    }
  }
  // images.txt: an image line, then its POINTS2D line (always present, maybe empty).
  struct Image {
    long long id;
    Mat3 R;
    Vec3 T;
    long long camera;
    std::string name;
    int line;
  };
  std::vector<Image> images;
  {
    std::istringstream in(images_txt);
    std::string line;
    int ln = 0;
    while (std::getline(in, line)) {
      ++ln;
      const std::string t = trim(line);
      if (t.empty() || t[0] == '#') continue;
      const std::string where = fmt::format("images.txt line {}", ln);
      const auto w = split_words(t);
      if (w.size() < 10) throw ColmapError(where + ": expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME");
      Image im;
      im.id = to_id(w[0], where);
      Eigen::Quaterniond q(to_double(w[1], where), to_double(w[2], where), to_double(w[3], where),
                           to_double(w[4], where));
      if (!(std::abs(q.norm() - 1) < 1e-3))
        throw ColmapError(fmt::format("{}: the quaternion's norm is {}, not 1", where, q.norm()));
      im.R = q.normalized().toRotationMatrix();
      im.T = Vec3(to_double(w[5], where), to_double(w[6], where), to_double(w[7], where));
      im.camera = to_id(w[8], where);
      // NAME: the rest of the line (names may hold spaces).
      std::istringstream rest(t);
      std::string skip;
      for (int i = 0; i < 9; ++i) rest >> skip;
      std::getline(rest, im.name);
      im.name = trim(im.name);
      im.line = ln;
      if (!cameras.count(im.camera))
        throw ColmapError(fmt::format("{}: image '{}' uses camera {}, which cameras.txt does not hold", where,
                                      im.name, im.camera));
      images.push_back(im);
      if (images.size() > size_t(kMaxCameras))
        throw ColmapError(fmt::format("images.txt: more than {} images (omma's camera limit)", kMaxCameras));
      std::getline(in, line);  // POINTS2D
      ++ln;
    }
  }
  if (images.empty()) throw ColmapError("images.txt holds no image");
  std::sort(images.begin(), images.end(), [](const Image& a, const Image& b) { return a.id < b.id; });
  for (size_t i = 1; i < images.size(); ++i)
    if (images[i].id == images[i - 1].id)
      throw ColmapError(
          fmt::format("images.txt line {}: image {} appears twice", images[i].line, images[i].id));
  // Camera ids: cam_XX.* names, else IMAGE_ID order.
  static const std::regex kName(R"(cam_(\d{1,9})\.[^./\\]+)");
  std::vector<int> ids;
  for (const Image& im : images) {
    std::smatch m;
    const std::string base = fs::path(im.name).filename().string();
    if (!std::regex_match(base, m, kName)) {
      s.ids_from_names = false;
      break;
    }
    ids.push_back(std::stoi(m[1].str()));
  }
  if (s.ids_from_names) {
    std::vector<int> sorted = ids;
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) s.ids_from_names = false;
  }
  if (!s.ids_from_names) {
    ids.clear();
    for (size_t i = 0; i < images.size(); ++i) ids.push_back(int(i));
    s.warnings.push_back(
        "the image names are not all distinct cam_XX.* (omma's frame names): camera ids 0.." +
        std::to_string(images.size() - 1) + " follow IMAGE_ID order (see the image list)");
  }
  // Cameras.
  Rig& rig = s.rig;
  for (size_t i = 0; i < images.size(); ++i) {
    const Image& im = images[i];
    const ColmapCamera& cc = cameras.at(im.camera);
    RigCamera c;
    c.id = ids[i];
    const std::string where =
        fmt::format("image {} '{}' (camera {}, omma camera {})", im.id, im.name, cc.id, c.id);
    double fit = 0;
    c.in = intrinsics_from_colmap(cc, where, &fit, &s.warnings);
    s.max_fit_px = std::max(s.max_fit_px, fit);
    ++s.models[cc.model];
    c.frame.u = im.R.row(0).transpose();
    c.frame.v = im.R.row(1).transpose();
    c.frame.t = im.R.row(2).transpose();
    c.position_mm = -im.R.transpose() * im.T * opt.scale_mm;
    rig.cameras.push_back(c);
    s.images.emplace_back(im.name, c.id);
  }
  if (meta) {
    s.omma_metadata = true;
    rig.name = meta->name;
    rig.dome = meta->dome;
    for (RigCamera& c : rig.cameras) {
      const auto it = std::find_if(meta->cameras.begin(), meta->cameras.end(),
                                   [&](const RigCamera& m) { return m.id == c.id; });
      if (it == meta->cameras.end()) continue;
      c.photometric = it->photometric;
      if (same_intrinsics(c.in, it->in)) {
        c.in.field = it->in.field;
        c.in.aov = it->in.aov;
      }
    }
  } else {
    if (!opt.keep_origin) {
      Vec3 centroid = Vec3::Zero();
      for (const auto& c : rig.cameras) centroid += c.position_mm;
      centroid /= double(rig.cameras.size());
      for (auto& c : rig.cameras) c.position_mm -= centroid;
    }
    rig.name = folder_name;
    rig.dome = dome_around(rig, "colmap import");
  }
  if (!opt.name.empty()) rig.name = opt.name;
  rig.validate();
  return s;
}

}  // namespace omma::calib
