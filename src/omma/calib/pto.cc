#include "omma/calib/pto.h"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <map>
#include <sstream>

#include <Eigen/Dense>
#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>

#include "omma/core/frames.h"
#include "omma/core/limits.h"
#include "omma/core/valid.h"

namespace omma::calib {
namespace fs = std::filesystem;

bool PtoExportOptions::IsValid(std::string* why) const {
  // The p-line's height is pano_width / 2.
  if (pano_width < 2) return invalid(why, fmt::format("pano_width must be at least 2, got {}", pano_width));
  if (interpolator < 0) return invalid(why, fmt::format("interpolator must be >= 0, got {}", interpolator));
  return true;
}

namespace {

// PT world axes in the dome frame (see pto.h).
const Vec3 kF(-1, 0, 0), kR(0, 1, 0), kU(0, 0, 1);

Mat3 rot(const Vec3& axis, double angle) { return Eigen::AngleAxisd(angle, axis).toRotationMatrix(); }

// Columns t, u, v of a PanoTools camera (radians).
Mat3 pt_axes(double yaw, double pitch, double roll) {
  Mat3 base;
  base.col(0) = kF;
  base.col(1) = kR;
  base.col(2) = -kU;
  return rot(-kU, yaw) * rot(kR, pitch) * rot(kF, roll) * base;
}

// Sample radii (normalised, undistorted R = tan(angle)) with area weights for a W x H image whose
// distortion centre is (cx, cy) and whose distorted radius rho_s(R) is given (monotone on range).
template <typename RhoOfR>
void radius_samples(int w, int h, double cx, double cy, RhoOfR rho_of_r, double r_guess_max,
                    std::vector<double>* rs, std::vector<double>* ws) {
  const double rho_max = std::hypot(std::max(cx, w - cx), std::max(cy, h - cy));
  // Keep the bisection on the monotone part of rho_s(R) (strong barrel distortion folds back).
  {
    const int steps = 2000;
    double prev = 0;
    for (int i = 1; i <= steps; ++i) {
      const double r = r_guess_max * i / steps, rho = rho_of_r(r);
      if (rho <= prev) {
        r_guess_max = r_guess_max * (i - 1) / steps;
        break;
      }
      if (rho > 2 * rho_max) {
        r_guess_max = r;
        break;
      }
      prev = rho;
    }
  }
  const int n = 200;
  for (int i = 1; i <= n; ++i) {
    const double rho = rho_max * (i - 0.5) / n;
    // Invert rho_of_r by bisection on [0, r_guess_max].
    double lo = 0, hi = r_guess_max;
    for (int it = 0; it < 60; ++it) {
      const double mid = 0.5 * (lo + hi);
      (rho_of_r(mid) < rho ? lo : hi) = mid;
    }
    // Fraction of the circle of radius rho inside the image (area weight ~ rho * inside fraction).
    int inside = 0;
    const int m = 64;
    for (int k = 0; k < m; ++k) {
      const double a = 2 * kPi * (k + 0.5) / m;
      const double x = cx + rho * std::cos(a), y = cy + rho * std::sin(a);
      inside += x >= 0 && x < w && y >= 0 && y < h;
    }
    if (inside == 0) continue;
    rs->push_back(0.5 * (lo + hi));
    ws->push_back(rho * inside / double(m));
  }
}

double omma_rho(double f, const std::array<double, 5>& k, double r) {
  const double r2 = r * r;
  return f * r * (1 + k[0] * r2 + k[1] * r2 * r2 + k[4] * r2 * r2 * r2);
}

double pt_rho(double fpt, double r0, double a, double b, double c, double rr) {
  const double ri = fpt * rr, r = ri / r0;
  return ri * (((a * r + b) * r + c) * r + 1 - a - b - c);
}

std::string fmt_num(double x) { return fmt::format("{:.12g}", x); }

// The one reader of numbers in PTO text: the whole token must be a finite number ("12abc", "nan",
// "inf", "" and 1e999 are errors).
double parse_number(const std::string& s, const std::string& where) {
  double v = 0;
  const char* end = s.data() + s.size();
  const auto r = std::from_chars(s.data(), end, v);
  if (s.empty() || r.ec != std::errc() || r.ptr != end || !std::isfinite(v))
    throw PtoError(fmt::format("{}: '{}' is not a finite number", where, s));
  return v;
}
// An integral number in [lo, hi] (also written as 250.0).
int parse_int(const std::string& s, const std::string& where, int lo, int hi) {
  const double v = parse_number(s, where);
  if (v != std::floor(v) || v < lo || v > hi)
    throw PtoError(fmt::format("{}: '{}' is not an integer in [{}, {}]", where, s, lo, hi));
  return static_cast<int>(v);
}

}  // namespace

PtoCamera pto_from_camera(const RigCamera& cam, LensFit* fit) {
  PtoCamera p;
  const Intrinsics& in = cam.in;
  p.width = in.width;
  p.height = in.height;
  // Orientation.
  const Vec3 t = cam.frame.t, u = cam.frame.u;
  const double yaw = std::atan2(t.dot(kR), t.dot(kF));
  const double pitch = std::asin(std::clamp(t.dot(kU), -1.0, 1.0));
  const Mat3 zero_roll = pt_axes(yaw, pitch, 0);
  const double roll = std::atan2(u.dot(zero_roll.col(2)), u.dot(zero_roll.col(1)));
  p.yaw_deg = rad2deg(yaw);
  p.pitch_deg = rad2deg(pitch);
  p.roll_deg = rad2deg(roll);
  p.d = in.cu - in.width / 2.0;
  p.e = in.cv - in.height / 2.0;
  // Lens: fit (f_pt, a, b, c) to omma's radial function over the image.
  const double f = std::sqrt(in.fu * in.fv);
  const double r0 = std::min(in.width, in.height) / 2.0;
  std::vector<double> rs, ws;
  const double r_max = 4 * std::hypot(in.width, in.height) / f;
  radius_samples(
      in.width, in.height, in.cu, in.cv, [&](double r) { return omma_rho(f, in.k, r); }, r_max, &rs, &ws);
  auto solve_abc = [&](double fpt, double* a, double* b, double* c) {
    // rho_pt = fpt R [1 + a (q^3 R^3 - 1) + b (q^2 R^2 - 1) + c (q R - 1)], q = fpt / r0: linear.
    const double q = fpt / r0;
    Eigen::MatrixXd m(rs.size(), 3);
    Eigen::VectorXd y(rs.size());
    for (size_t i = 0; i < rs.size(); ++i) {
      const double rr = rs[i], sw = std::sqrt(ws[i]);
      m(i, 0) = sw * fpt * rr * (std::pow(q * rr, 3) - 1);
      m(i, 1) = sw * fpt * rr * (std::pow(q * rr, 2) - 1);
      m(i, 2) = sw * fpt * rr * (q * rr - 1);
      y(i) = sw * (omma_rho(f, in.k, rr) - fpt * rr);
    }
    const Eigen::Vector3d x = m.colPivHouseholderQr().solve(y);
    *a = x[0], *b = x[1], *c = x[2];
    return (m * x - y).squaredNorm();
  };
  double a = 0, b = 0, c = 0;
  double lo = 0.5 * f, hi = 2.0 * f;  // golden-section search on f_pt
  const double g = (std::sqrt(5.0) - 1) / 2;
  double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
  double f1 = solve_abc(x1, &a, &b, &c), f2 = solve_abc(x2, &a, &b, &c);
  for (int it = 0; it < 200 && hi - lo > 1e-12 * f; ++it) {
    if (f1 < f2) {
      hi = x2, x2 = x1, f2 = f1, x1 = hi - g * (hi - lo), f1 = solve_abc(x1, &a, &b, &c);
    } else {
      lo = x1, x1 = x2, f1 = f2, x2 = lo + g * (hi - lo), f2 = solve_abc(x2, &a, &b, &c);
    }
  }
  const double fpt = 0.5 * (lo + hi);
  solve_abc(fpt, &a, &b, &c);
  if (!in.has_distortion()) a = b = c = 0;
  for (double* x : {&a, &b, &c})
    if (std::abs(*x) < 1e-10) *x = 0;  // least-squares round-off of exactly-zero terms
  p.a = a, p.b = b, p.c = c;
  p.hfov_deg = rad2deg(2 * std::atan(in.width / 2.0 / fpt));
  if (fit) {
    double s2 = 0, sw = 0, mx = 0;
    for (size_t i = 0; i < rs.size(); ++i) {
      const double err = std::abs(pt_rho(fpt, r0, a, b, c, rs[i]) - omma_rho(f, in.k, rs[i]));
      s2 += ws[i] * err * err, sw += ws[i], mx = std::max(mx, err);
    }
    fit->rms_px = std::sqrt(s2 / sw);
    fit->max_px = mx;
  }
  return p;
}

RigCamera camera_from_pto(const PtoCamera& p, int radial_terms, LensFit* fit) {
  RigCamera cam;
  const Mat3 axes = pt_axes(deg2rad(p.yaw_deg), deg2rad(p.pitch_deg), deg2rad(p.roll_deg));
  cam.frame.t = axes.col(0);
  cam.frame.u = axes.col(1);
  cam.frame.v = axes.col(2);
  cam.position_mm = 5.0 * cam.frame.t;
  Intrinsics& in = cam.in;
  in.width = p.width;
  in.height = p.height;
  in.cu = p.width / 2.0 + p.d;
  in.cv = p.height / 2.0 + p.e;
  const double fpt = p.width / 2.0 / std::tan(deg2rad(p.hfov_deg) / 2);
  const double r0 = std::min(p.width, p.height) / 2.0;
  in.aov = deg2rad(p.hfov_deg);
  std::vector<double> rs, ws;
  const double r_max = 4 * std::hypot(p.width, p.height) / fpt;
  radius_samples(
      p.width, p.height, in.cu, in.cv, [&](double r) { return pt_rho(fpt, r0, p.a, p.b, p.c, r); }, r_max,
      &rs, &ws);
  // rho / R = f + (f k1) R^2 + (f k2) R^4 + (f k5) R^6: linear least squares.
  const int terms = std::clamp(radial_terms, 0, 3);
  Eigen::MatrixXd m(rs.size(), 1 + terms);
  Eigen::VectorXd y(rs.size());
  for (size_t i = 0; i < rs.size(); ++i) {
    const double rr = rs[i], sw = std::sqrt(ws[i]);
    for (int j = 0; j <= terms; ++j) m(i, j) = sw * rr * std::pow(rr, 2 * j);
    y(i) = sw * pt_rho(fpt, r0, p.a, p.b, p.c, rr);
  }
  const Eigen::VectorXd x = m.colPivHouseholderQr().solve(y);
  const double f = (p.a == 0 && p.b == 0 && p.c == 0) ? fpt : x[0];
  in.fu = in.fv = f;
  in.k = {};
  if (p.a != 0 || p.b != 0 || p.c != 0) {
    const int slot[3] = {0, 1, 4};
    for (int j = 1; j <= terms; ++j) in.k[slot[j - 1]] = x[j] / f;
  }
  if (fit) {
    double s2 = 0, sw = 0, mx = 0;
    for (size_t i = 0; i < rs.size(); ++i) {
      const double err = std::abs(omma_rho(f, in.k, rs[i]) - pt_rho(fpt, r0, p.a, p.b, p.c, rs[i]));
      s2 += ws[i] * err * err, sw += ws[i], mx = std::max(mx, err);
    }
    fit->rms_px = sw > 0 ? std::sqrt(s2 / sw) : 0;
    fit->max_px = mx;
  }
  return cam;
}

PtoExportSummary export_pto(const Rig& rig, const PtoExportOptions& opt) {
  std::string why;
  if (!opt.IsValid(&why)) throw std::invalid_argument("export_pto: " + why);
  rig.validate();
  PtoExportSummary res;
  std::ostringstream os;
  const int pw = opt.pano_width, ph = opt.pano_width / 2;
  os << "# hugin project file written by omma (pto.h documents the convention mapping)\n";
  os << "#-omma rig name " << std::quoted(rig.name) << " radius_mm " << fmt_num(rig.dome.radius_mm)
     << " sphere " << (rig.dome.sphere ? 1 : 0) << " cameras " << rig.cameras.size() << "\n";
  os << "p f2 w" << pw << " h" << ph << " v360 E0 R0";
  if (opt.crop_to_dome && !rig.dome.sphere) os << " S0," << pw << ",0," << ph / 2;
  os << " n\"PNG\"\n";
  os << "m g1 i" << opt.interpolator << " f0 m2 p0.00784314\n";
  double s2 = 0;
  for (const auto& cam : rig.cameras) {
    LensFit fit;
    const PtoCamera p = pto_from_camera(cam, &fit);
    res.max_fit_px = std::max(res.max_fit_px, fit.max_px);
    s2 += fit.rms_px * fit.rms_px;
    if (std::abs(cam.in.fu - cam.in.fv) > 1e-9 * cam.in.fu)
      res.warnings.push_back(
          fmt::format("camera {}: fu != fv ({} vs {}); PTO holds one focal length (sqrt(fu fv) written)",
                      cam.id, cam.in.fu, cam.in.fv));
    if (cam.in.k[2] != 0 || cam.in.k[3] != 0)
      res.warnings.push_back(
          fmt::format("camera {}: tangential distortion k3, k4 has no PTO equivalent (dropped)", cam.id));
    std::string image = frame_filename(cam.id);
    if (!opt.frames_dir.empty()) image = (fs::path(opt.frames_dir) / image).string();
    os << "#-omma camera id " << cam.id << " position_mm " << fmt_num(cam.position_mm.x()) << " "
       << fmt_num(cam.position_mm.y()) << " " << fmt_num(cam.position_mm.z()) << " aov_deg "
       << fmt_num(rad2deg(cam.in.aov)) << " fv_over_fu " << fmt_num(cam.in.fv / cam.in.fu) << " k "
       << fmt_num(cam.in.k[0]) << " " << fmt_num(cam.in.k[1]) << " " << fmt_num(cam.in.k[2]) << " "
       << fmt_num(cam.in.k[3]) << " " << fmt_num(cam.in.k[4]) << " f "
       << fmt_num(std::sqrt(cam.in.fu * cam.in.fv)) << "\n";
    const Photometric ph = cam.photometric.value_or(Photometric{});
    os << "i w" << p.width << " h" << p.height << " f0 v" << fmt_num(p.hfov_deg)
       << (opt.linear_response ? " Rt1" : "") << " Ra0 Rb0 Rc0 Rd0 Re0 Eev"
       << fmt_num(0.0 - std::log2(ph.gains[1])) << " Er" << fmt_num(ph.gains[2] / ph.gains[1]) << " Eb"
       << fmt_num(ph.gains[0] / ph.gains[1]) << " r" << fmt_num(p.roll_deg) << " p" << fmt_num(p.pitch_deg)
       << " y" << fmt_num(p.yaw_deg) << " TrX0 TrY0 TrZ0 j0 a" << fmt_num(p.a) << " b" << fmt_num(p.b) << " c"
       << fmt_num(p.c) << " d" << fmt_num(p.d) << " e" << fmt_num(p.e) << " g0 t0 Va1 Vb"
       << fmt_num(ph.vignetting[0]) << " Vc" << fmt_num(ph.vignetting[1]) << " Vd"
       << fmt_num(ph.vignetting[2]) << " Vx" << fmt_num(ph.center_px.x()) << " Vy"
       << fmt_num(ph.center_px.y()) << " Vm5 n\"" << image << "\"\n";
  }
  res.rms_fit_px = rig.cameras.empty() ? 0 : std::sqrt(s2 / rig.cameras.size());
  res.text = os.str();
  return res;
}

namespace {

// Splits an i-line into key -> value text (n"..." handled).
std::map<std::string, std::string> parse_tokens(const std::string& line) {
  std::map<std::string, std::string> kv;
  size_t i = 1;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    if (i >= line.size()) break;
    if (line[i] == 'n' && i + 1 < line.size() && line[i + 1] == '"') {
      const size_t end = line.find('"', i + 2);
      kv["n"] = line.substr(i + 2, end == std::string::npos ? std::string::npos : end - i - 2);
      if (end == std::string::npos) kv["_unterminated"] = "1";
      i = end == std::string::npos ? line.size() : end + 1;
      continue;
    }
    size_t j = i;
    while (j < line.size() && std::isalpha(static_cast<unsigned char>(line[j]))) ++j;
    size_t k = j;
    while (k < line.size() && !std::isspace(static_cast<unsigned char>(line[k]))) ++k;
    kv[line.substr(i, j - i)] = line.substr(j, k - j);
    if (line.compare(i, j - i, "n") == 0) kv["_unterminated"] = "1";  // n without its quoted name
    i = k;
  }
  return kv;
}

}  // namespace

PtoImportSummary import_pto(const std::string& text, const fs::path& base_dir) {
  PtoImportSummary res;
  res.rig.name = "pto-import";
  std::istringstream is(text);
  std::string line;
  std::vector<std::map<std::string, std::string>> images;
  std::vector<std::map<std::string, std::string>> extras;  // #-omma camera lines, by position
  std::map<std::string, std::string> pending;
  int line_no = 0, expected_images = 0;
  while (std::getline(is, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::string where = fmt::format("PTO line {}", line_no);
    if (line.rfind("#-omma rig", 0) == 0) {
      std::istringstream ls(line.substr(10));
      std::string key, v;
      while (ls >> key) {
        if (key == "name")
          ls >> std::quoted(res.rig.name);
        else if (key == "radius_mm" && ls >> v)
          res.rig.dome.radius_mm = parse_number(v, where + " radius_mm");
        else if (key == "sphere" && ls >> v)
          res.rig.dome.sphere = parse_int(v, where + " sphere", 0, 1) != 0;
        else if (key == "cameras" && ls >> v)
          expected_images = parse_int(v, where + " cameras", 1, kMaxCameras);
      }
    } else if (line.rfind("#-omma camera", 0) == 0) {
      if (pending.count("_valid"))
        throw PtoError(where + ": two '#-omma camera' lines without an image line between them");
      std::istringstream ls(line.substr(13));
      std::string key, val;
      pending.clear();
      while (ls >> key) {
        std::string v, rest;
        const int count = key == "position_mm" ? 3 : key == "k" ? 5 : 1;
        for (int c = 0; c < count && ls >> v; ++c) rest += (c ? " " : "") + v;
        pending[key] = rest;
      }
      pending["_valid"] = "1";
    } else if (!line.empty() && (line[0] == 'i' || line[0] == 'o') &&
               (line.size() == 1 || std::isspace(static_cast<unsigned char>(line[1])))) {
      auto kv = parse_tokens(line);
      kv["_line"] = std::to_string(line_no);
      // Hugin writes every parameter; a line without these is cut short or not a project.
      for (const char* key : {"f", "v", "y", "p", "r", "n"})
        if (!kv.count(key))
          throw PtoError(fmt::format(
              "{}: image line without its '{}' parameter (a truncated or damaged project?)", where, key));
      if (kv.count("_unterminated"))
        throw PtoError(where + ": image name n\"... is not terminated (a truncated or damaged project?)");
      if (images.size() >= size_t(kMaxCameras))
        throw PtoError(fmt::format("PTO file has more than {} images (the rig limit)", kMaxCameras));
      images.push_back(kv);
      extras.push_back(pending);
      pending.clear();
    }
  }
  if (images.empty()) throw PtoError("PTO file has no image lines ('i ...'): nothing to import");
  if (pending.count("_valid"))
    throw PtoError("PTO file ends after an '#-omma camera' line without its image line (truncated?)");
  if (expected_images > 0 && size_t(expected_images) != images.size())
    throw PtoError(fmt::format("PTO file has {} image lines, its '#-omma rig' line says {} (truncated?)",
                               images.size(), expected_images));
  auto value = [&](size_t idx, const std::string& key, double def) -> double {
    for (int depth = 0; depth < 64; ++depth) {
      auto it = images[idx].find(key);
      if (it == images[idx].end()) return def;
      const std::string& s = it->second;
      if (s.empty())
        throw PtoError(
            fmt::format("PTO image {} (line {}): parameter {} has no value", idx, images[idx]["_line"], key));
      if (s[0] == '=') {  // linked to another image's value
        const size_t ref = size_t(
            parse_int(s.substr(1), fmt::format("PTO image {} parameter {} link", idx, key), 0, kMaxCameras));
        if (ref >= images.size())
          throw PtoError(fmt::format("PTO image {}: parameter {} links to missing image {}", idx, key, ref));
        idx = ref;
        continue;
      }
      return parse_number(s,
                          fmt::format("PTO image {} (line {}) parameter {}", idx, images[idx]["_line"], key));
    }
    throw PtoError("PTO: circular parameter links");
  };
  for (size_t i = 0; i < images.size(); ++i) {
    const double lens = value(i, "f", 0);
    if (lens != 0)
      throw PtoError(fmt::format(
          "PTO image {} (line {}): lens type f{} is not supported (only f0, rectilinear, matches omma's "
          "pinhole "
          "model; f1 panoramic, f2 circular fisheye, f3 full-frame fisheye, f4 equirectangular ... are not)",
          i, images[i]["_line"], lens));
    PtoCamera p;
    p.image = images[i].count("n") ? images[i]["n"] : "";
    const double w = value(i, "w", 0), h = value(i, "h", 0);
    if (w != 0 || h != 0) {  // 0 or absent: the image file's size
      if (w != std::floor(w) || h != std::floor(h))
        throw PtoError(fmt::format("PTO image {} (line {}): size w{} h{} is not whole pixels", i,
                                   images[i]["_line"], w, h));
      try {
        check_image_size(int64_t(std::clamp(w, -1.0, 1e9)), int64_t(std::clamp(h, -1.0, 1e9)), "image size");
      } catch (const std::invalid_argument& e) {
        throw PtoError(fmt::format("PTO image {} (line {}): {}", i, images[i]["_line"], e.what()));
      }
      p.width = int(w), p.height = int(h);
    }
    const fs::path img_path =
        p.image.empty() ? fs::path()
                        : (fs::path(p.image).is_absolute() ? fs::path(p.image) : base_dir / p.image);
    const bool exists = !p.image.empty() && fs::exists(img_path);
    if (p.width <= 0 || p.height <= 0) {
      if (!exists)
        throw PtoError(fmt::format("PTO image {} (line {}): no size (w, h) and the image '{}' is missing", i,
                                   images[i]["_line"], img_path.string()));
      const cv::Mat m = cv::imread(img_path.string(), cv::IMREAD_UNCHANGED);
      if (m.empty()) throw PtoError(fmt::format("PTO image {}: cannot read '{}'", i, img_path.string()));
      p.width = m.cols, p.height = m.rows;
    } else if (!exists) {
      res.warnings.push_back(fmt::format(
          "PTO image {}: image file '{}' is missing (geometry imported anyway)", i, img_path.string()));
    }
    p.hfov_deg = value(i, "v", 0);
    if (!(p.hfov_deg > 0 && p.hfov_deg < 180))
      throw PtoError(
          fmt::format("PTO image {} (line {}): field of view v{} must be in (0, 180) for a rectilinear lens",
                      i, images[i]["_line"], p.hfov_deg));
    p.yaw_deg = value(i, "y", 0);
    p.pitch_deg = value(i, "p", 0);
    p.roll_deg = value(i, "r", 0);
    p.a = value(i, "a", 0), p.b = value(i, "b", 0), p.c = value(i, "c", 0);
    p.d = value(i, "d", 0), p.e = value(i, "e", 0);
    LensFit fit;
    RigCamera cam = camera_from_pto(p, 3, &fit);
    res.max_fit_px = std::max(res.max_fit_px, fit.max_px);
    cam.id = static_cast<int>(i);
    cam.position_mm = res.rig.dome.radius_mm * cam.frame.t;
    const auto& ex = extras[i];
    if (ex.count("_valid")) {
      // omma's own export: restore what PTO does not hold, exactly.
      const std::string ew = fmt::format("PTO image {}: '#-omma camera' field", i);
      auto numbers = [&](const std::string& key, double* out, int n) {
        std::istringstream vs(ex.at(key));
        std::string v;
        for (int c = 0; c < n; ++c) out[c] = parse_number(vs >> v ? v : std::string(), ew + " " + key);
      };
      if (ex.count("id")) cam.id = parse_int(ex.at("id"), ew + " id", 0, INT32_MAX);
      if (ex.count("position_mm")) numbers("position_mm", cam.position_mm.data(), 3);
      if (ex.count("aov_deg")) {
        double aov = 0;
        numbers("aov_deg", &aov, 1);
        cam.in.aov = deg2rad(aov);
      }
      // The lens as written, if PTO's lens values are still the ones the export wrote (untouched
      // by Hugin): then k and f come back exactly; otherwise the fitted values stand.
      if (ex.count("k") && ex.count("f")) {
        std::array<double, 5> k{};
        numbers("k", k.data(), 5);
        RigCamera orig = cam;
        orig.in.k = k;
        numbers("f", &orig.in.fu, 1);
        orig.in.fv = orig.in.fu;
        const PtoCamera again = pto_from_camera(orig);
        if (std::abs(again.hfov_deg - p.hfov_deg) < 1e-9 && std::abs(again.a - p.a) < 1e-9 &&
            std::abs(again.b - p.b) < 1e-9 && std::abs(again.c - p.c) < 1e-9) {
          cam.in.k = k;
          cam.in.fu = cam.in.fv = orig.in.fu;
        }
      }
      if (ex.count("fv_over_fu")) {
        double ratio = 0;
        numbers("fv_over_fu", &ratio, 1);
        if (!(ratio > 0)) throw PtoError(ew + " fv_over_fu must be positive");
        const double f = cam.in.fu;
        cam.in.fu = f / std::sqrt(ratio);
        cam.in.fv = f * std::sqrt(ratio);
      }
    }
    // Photometry (see pto.h): only what differs from "no correction" makes a model.
    {
      // Vm: Hugin's vignetting mode flags (1 radial, 2 flat field, 4 and 8 options), a whole number.
      const double vm_value = value(i, "Vm", 0);
      if (!(vm_value >= 0 && vm_value <= 63 && vm_value == std::floor(vm_value)))
        throw PtoError(
            fmt::format("PTO image {} (line {}): Vm{} is not a vignetting mode (a whole number 0..63)", i,
                        images[i]["_line"], vm_value));
      const int vm = static_cast<int>(vm_value);
      const double va = value(i, "Va", 1), eev = value(i, "Eev", 0), er = value(i, "Er", 1),
                   eb = value(i, "Eb", 1);
      Photometric ph;
      if (vm & 1) {
        if (!(va > 0))
          throw PtoError(
              fmt::format("PTO image {} (line {}): Va{} must be positive", i, images[i]["_line"], va));
        ph.vignetting = {value(i, "Vb", 0) / va, value(i, "Vc", 0) / va, value(i, "Vd", 0) / va};
        ph.center_px = Vec2(value(i, "Vx", 0), value(i, "Vy", 0));
      } else if (vm & 2) {
        res.warnings.push_back(
            fmt::format("PTO image {}: flat-field vignetting (Vm{}) is not imported", i, vm));
      }
      const double scale = (vm & 1) ? va : 1.0;
      const double g = std::exp2(-eev) * scale;
      ph.gains = {g * eb, g, g * er};
      if (!ph.is_identity()) {
        try {
          validate_photometric(ph, cam.in.width, cam.in.height, fmt::format("PTO image {}", i));
        } catch (const std::invalid_argument& e) {
          throw PtoError(e.what());
        }
        cam.photometric = ph;
      }
    }
    res.rig.cameras.push_back(cam);
  }
  res.rig.validate();
  return res;
}

}  // namespace omma::calib
