#include "omma/calib/opencv_calib.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>
#include <fmt/format.h>
#include <opencv2/calib3d.hpp>

#include "omma/core/io.h"
#include "omma/core/limits.h"

namespace omma::calib {
namespace {

namespace fs = std::filesystem;

// Camera rotation (rows u, v, t: dome -> OpenCV camera coordinates x right, y down, z forward).
Mat3 camera_rotation(const Frame& f) {
  Mat3 r;
  r.row(0) = f.u.transpose();
  r.row(1) = f.v.transpose();
  r.row(2) = f.t.transpose();
  return r;
}

Frame frame_from_rotation(const Mat3& r) {
  Frame f;
  f.u = r.row(0).transpose();
  f.v = r.row(1).transpose();
  f.t = r.row(2).transpose();
  return f;
}

Mat3 to_eigen(const cv::Matx33d& m) {
  Mat3 r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = m(i, j);
  return r;
}

cv::Matx33d to_cv(const Mat3& m) {
  cv::Matx33d r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = m(i, j);
  return r;
}

// The upright view along +x: eq. 3.13 yaw 0, pitch 0, roll 180 deg.
Mat3 default_rotation() {
  Mat3 r;
  r << 0, -1, 0,  // u
      0, 0, -1,   // v
      1, 0, 0;    // t
  return r;
}

void check_rotation(const Mat3& r, const std::string& where) {
  if (!r.allFinite() || (r * r.transpose() - Mat3::Identity()).cwiseAbs().maxCoeff() > 1e-6 ||
      std::abs(r.determinant() - 1) > 1e-6)
    throw OpenCvCalibError(where + " is not a rotation matrix (orthonormal, determinant +1, to 1e-6)");
}

// The rational model's radial factor fitted by omma's polynomial (see the header).
LensConversion fit_rational(const std::vector<double>& d, const Intrinsics& in, const std::string& where) {
  const cv::Matx33d K = opencv_camera_matrix(in);
  const std::vector<double> d8(d.begin(), d.begin() + 8);
  // Sample the image (omma pixel coordinates, edges included), undistort with OpenCV, keep the points
  // that reproject to their pixel (where the rational model is invertible).
  std::vector<cv::Point2d> px;
  constexpr int nx = 41, ny = 31;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      px.emplace_back(in.width * i / double(nx - 1) - 0.5, in.height * j / double(ny - 1) - 0.5);
  std::vector<cv::Point2d> und;
  cv::undistortPoints(px, und, K, d8, cv::noArray(), cv::noArray(),
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 500, 1e-15));
  std::vector<cv::Point3d> rays;
  for (const auto& p : und) rays.emplace_back(p.x, p.y, 1.0);
  std::vector<cv::Point2d> back;
  cv::projectPoints(rays, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, d8, back);
  std::vector<Vec2> xy;
  std::vector<cv::Point2d> target;
  for (size_t i = 0; i < px.size(); ++i)
    if (std::isfinite(und[i].x) && std::isfinite(und[i].y) && cv::norm(back[i] - px[i]) < 1e-6) {
      xy.emplace_back(und[i].x, und[i].y);
      target.push_back(px[i]);
    }
  if (xy.size() < 20)
    throw OpenCvCalibError(where +
                           ": the rational distortion model (k4..k6) cannot be inverted over the image");
  const double k1 = d[0], k2 = d[1], p1 = d[2], p2 = d[3], k3 = d[4], k4 = d[5], k5 = d[6], k6 = d[7];
  Eigen::MatrixXd A(2 * xy.size(), 3);
  Eigen::VectorXd b(2 * xy.size());
  for (size_t i = 0; i < xy.size(); ++i) {
    const double x = xy[i].x(), y = xy[i].y(), s = x * x + y * y;
    const double f = (1 + s * (k1 + s * (k2 + s * k3))) / (1 + s * (k4 + s * (k5 + s * k6)));
    A.row(2 * i) << in.fu * x * s, in.fu * x * s * s, in.fu * x * s * s * s;
    A.row(2 * i + 1) << in.fv * y * s, in.fv * y * s * s, in.fv * y * s * s * s;
    b(2 * i) = in.fu * x * (f - 1);
    b(2 * i + 1) = in.fv * y * (f - 1);
  }
  const Eigen::Vector3d a = A.colPivHouseholderQr().solve(b);
  LensConversion c;
  c.k = {a(0), a(1), p2, p1, a(2)};
  c.exact = false;
  double sum2 = 0;
  for (size_t i = 0; i < xy.size(); ++i) {
    const Vec2 dd = distort(c.k, xy[i]);
    const double e =
        std::hypot(in.fu * dd.x() + K(0, 2) - target[i].x, in.fv * dd.y() + K(1, 2) - target[i].y);
    c.max_px = std::max(c.max_px, e);
    sum2 += e * e;
  }
  c.rms_px = std::sqrt(sum2 / xy.size());
  c.note = fmt::format(
      "{}: the rational radial factor (k4={}, k5={}, k6={}) has no exact counterpart in omma's model; "
      "fitted k1, k2, k5 over the image: residual {:.4f} px max, {:.4f} px rms",
      where, k4, k5, k6, c.max_px, c.rms_px);
  return c;
}

cv::FileStorage open_storage(const fs::path& path) {
  if (!fs::exists(path))
    throw OpenCvCalibError("OpenCV calibration file " + path.string() + " does not exist");
  if (!fs::is_regular_file(path))
    throw OpenCvCalibError("OpenCV calibration file " + path.string() + " is not a regular file");
  if (fs::file_size(path) > kMaxTextFileBytes)
    throw OpenCvCalibError("OpenCV calibration file " + path.string() + " is too large");
  try {
    cv::FileStorage f(path.string(), cv::FileStorage::READ);
    if (!f.isOpened()) throw OpenCvCalibError("cannot read OpenCV calibration file " + path.string());
    return f;
  } catch (const cv::Exception& e) {
    throw OpenCvCalibError("cannot parse OpenCV calibration file " + path.string() + ": " + e.err);
  }
}

bool has(const cv::FileStorage& f, const std::string& key) { return !f[key].isNone() && !f[key].empty(); }

cv::Mat read_mat(const cv::FileStorage& f, const std::string& key, const std::string& where) {
  cv::Mat m;
  try {
    f[key] >> m;
  } catch (const cv::Exception& e) {
    throw OpenCvCalibError(where + ": '" + key + "' is not a matrix: " + e.err);
  }
  if (m.empty() || m.channels() != 1) throw OpenCvCalibError(where + ": '" + key + "' is not a matrix");
  m.convertTo(m, CV_64F);
  for (auto it = m.begin<double>(); it != m.end<double>(); ++it)
    if (!std::isfinite(*it)) throw OpenCvCalibError(where + ": '" + key + "' holds a non-finite number");
  return m;
}

cv::Matx33d read_camera_matrix(const cv::FileStorage& f, const std::string& key, const std::string& where) {
  const cv::Mat m = read_mat(f, key, where);
  if (m.rows != 3 || m.cols != 3)
    throw OpenCvCalibError(
        fmt::format("{}: '{}' is {}x{}, not a 3x3 camera matrix", where, key, m.rows, m.cols));
  cv::Matx33d K(m.ptr<double>());
  if (K(2, 2) != 1 || K(1, 0) != 0 || K(2, 0) != 0 || K(2, 1) != 0)
    throw OpenCvCalibError(where + ": '" + key + "' is not of the form [fx s cx; 0 fy cy; 0 0 1]");
  if (std::abs(K(0, 1)) > 1e-12 * std::abs(K(0, 0)))
    throw OpenCvCalibError(
        fmt::format("{}: '{}' has a skew of {}; omma's camera model has none", where, key, K(0, 1)));
  if (!(K(0, 0) > 0 && K(1, 1) > 0))
    throw OpenCvCalibError(where + ": '" + key + "' must have positive focal lengths fx, fy");
  return K;
}

std::vector<double> read_vector(const cv::FileStorage& f, const std::string& key, const std::string& where) {
  const cv::Mat m = read_mat(f, key, where);
  if (m.rows != 1 && m.cols != 1)
    throw OpenCvCalibError(fmt::format("{}: '{}' is {}x{}, not a vector", where, key, m.rows, m.cols));
  return std::vector<double>(m.begin<double>(), m.end<double>());
}

int read_int(const cv::FileStorage& f, const std::string& key, const std::string& where) {
  const cv::FileNode n = f[key];
  if (!n.isInt() && !n.isReal()) throw OpenCvCalibError(where + ": '" + key + "' must be a number");
  const double v = n.real();
  if (!(v >= 1 && v <= kMaxImageSide && v == std::floor(v)))
    throw OpenCvCalibError(
        fmt::format("{}: '{}' = {} is not an image side in 1..{}", where, key, v, kMaxImageSide));
  return int(v);
}

}  // namespace

std::vector<double> opencv_from_omma_k(const std::array<double, 5>& k) {
  return {k[0], k[1], k[3], k[2], k[4]};
}

cv::Matx33d opencv_camera_matrix(const Intrinsics& in) {
  return cv::Matx33d(in.fu, 0, in.cu - 0.5, 0, in.fv, in.cv - 0.5, 0, 0, 1);
}

LensConversion omma_k_from_opencv(const std::vector<double>& d, const Intrinsics& in,
                                  const std::string& where) {
  const size_t n = d.size();
  if (n != 0 && n != 4 && n != 5 && n != 8 && n != 12 && n != 14)
    throw OpenCvCalibError(
        fmt::format("{}: {} distortion coefficients; OpenCV's vectors hold 4, 5, 8, 12 or 14", where, n));
  for (double x : d)
    if (!std::isfinite(x)) throw OpenCvCalibError(where + ": a distortion coefficient is not finite");
  if (n >= 12)
    for (size_t i = 8; i < n; ++i)
      if (d[i] != 0)
        throw OpenCvCalibError(fmt::format(
            "{}: distortion coefficient {} ({}) = {} is not zero: the {} model has no counterpart in omma's "
            "camera model (radial k1 k2 k3 and tangential p1 p2 only); recalibrate without "
            "CALIB_THIN_PRISM_MODEL / CALIB_TILTED_MODEL",
            where, i + 1, i < 12 ? fmt::format("s{}", i - 7) : (i == 12 ? "tau_x" : "tau_y"), d[i],
            i < 12 ? "thin prism" : "tilted sensor"));
  LensConversion c;
  if (n == 0) return c;
  c.k = {d[0], d[1], d[3], d[2], n >= 5 ? d[4] : 0.0};
  if (n >= 8 && (d[5] != 0 || d[6] != 0 || d[7] != 0)) return fit_rational(d, in, where);
  return c;
}

std::string choose_field(Intrinsics& in, const std::string& where) {
  Intrinsics img = in;
  img.field = Intrinsics::Field::kImage;
  img.aov = img.bounding_aov();
  if (img.aov > 0 && img.aov < kPi && img.lens_problem().empty()) {
    in = img;
    return "";
  }
  Intrinsics cone = in;
  cone.field = Intrinsics::Field::kCone;
  auto ok = [&](double aov) {
    cone.aov = aov;
    return cone.lens_problem().empty();
  };
  double lo = deg2rad(1), hi = std::min(std::isfinite(img.aov) ? img.aov : kPi, deg2rad(179));
  if (hi <= lo || !ok(lo))
    throw OpenCvCalibError(where + ": the lens model does not describe even a 1 deg cone around the axis");
  if (!ok(hi)) {
    for (int i = 0; i < 60; ++i) {
      const double mid = 0.5 * (lo + hi);
      (ok(mid) ? lo : hi) = mid;
    }
    hi = lo;
  }
  cone.aov = hi;
  in = cone;
  if (img.aov >= kPi)
    return fmt::format(
        "{}: the image spans 180 deg or more: the camera sees a cone of {:.2f} deg (field cone)", where,
        rad2deg(cone.aov));
  return fmt::format(
      "{}: the distortion folds back before the image corners (not a lens there): the camera sees the {:.2f} "
      "deg "
      "cone its lens model describes (field cone), not its whole image",
      where, rad2deg(cone.aov));
}

Intrinsics opencv_intrinsics(const OpenCvCamera& cam, int width, int height, const std::string& where,
                             LensConversion* conv, std::vector<std::string>* warnings) {
  Intrinsics in;
  in.width = width > 0 ? width : cam.width;
  in.height = height > 0 ? height : cam.height;
  if (in.width <= 0 || in.height <= 0)
    throw OpenCvCalibError(where +
                           ": the image size is unknown (the file has no image_width/image_height): "
                           "give it (--size WxH or --images)");
  in.fu = cam.K(0, 0);
  in.fv = cam.K(1, 1);
  in.cu = cam.K(0, 2) + 0.5;
  in.cv = cam.K(1, 2) + 0.5;
  const LensConversion c = omma_k_from_opencv(cam.D, in, where);
  in.k = c.k;
  if (!c.note.empty() && warnings) warnings->push_back(c.note);
  if (conv) *conv = c;
  const std::string w = choose_field(in, where);
  if (!w.empty() && warnings) warnings->push_back(w);
  return in;
}

OpenCvCalibration read_opencv_calibration(const fs::path& path) {
  const cv::FileStorage f = open_storage(path);
  const std::string file = path.string();
  OpenCvCalibration c;
  int common_w = 0, common_h = 0;
  if (has(f, "image_width")) common_w = read_int(f, "image_width", file);
  if (has(f, "image_height")) common_h = read_int(f, "image_height", file);
  if ((common_w > 0) != (common_h > 0))
    throw OpenCvCalibError(file + ": image_width and image_height come together");
  if (has(f, "M1")) {
    c.layout = "stereo";
    for (int i = 1; has(f, fmt::format("M{}", i)); ++i) {
      if (i > kMaxCameras) throw OpenCvCalibError(fmt::format("{}: more than {} cameras", file, kMaxCameras));
      OpenCvCamera cam;
      cam.K = read_camera_matrix(f, fmt::format("M{}", i), file);
      const std::string dk = fmt::format("D{}", i);
      if (has(f, dk)) cam.D = read_vector(f, dk, file);
      cam.width = common_w, cam.height = common_h;
      const std::string wk = fmt::format("image_width{}", i), hk = fmt::format("image_height{}", i);
      if (has(f, wk)) cam.width = read_int(f, wk, file);
      if (has(f, hk)) cam.height = read_int(f, hk, file);
      if (i >= 2) {
        // R, T of cv::stereoCalibrate for camera 2; omma's Ri, Ti for every camera i >= 2.
        std::string rk = fmt::format("R{}", i), tk = fmt::format("T{}", i);
        if (i == 2 && !has(f, rk) && has(f, "R")) rk = "R";
        if (i == 2 && !has(f, tk) && has(f, "T")) tk = "T";
        if (has(f, rk) != has(f, tk))
          throw OpenCvCalibError(fmt::format("{}: '{}' and '{}' come together", file, rk, tk));
        if (has(f, rk)) {
          const cv::Mat R = read_mat(f, rk, file);
          const std::vector<double> T = read_vector(f, tk, file);
          if (R.rows != 3 || R.cols != 3) throw OpenCvCalibError(file + ": '" + rk + "' is not 3x3");
          if (T.size() != 3) throw OpenCvCalibError(file + ": '" + tk + "' is not a 3-vector");
          cam.R = cv::Matx33d(R.ptr<double>());
          cam.T = cv::Vec3d(T[0], T[1], T[2]);
          check_rotation(to_eigen(*cam.R), file + ": '" + rk + "'");
        }
      }
      c.cameras.push_back(cam);
    }
  } else {
    c.layout = "calibration";
    static const std::vector<std::string> kMatrixKeys = {"camera_matrix", "cameraMatrix", "K"};
    static const std::vector<std::string> kDistortionKeys = {"distortion_coefficients", "distCoeffs",
                                                             "dist_coeffs", "D"};
    std::string mk, dk;
    for (const std::string& k : kMatrixKeys)
      if (mk.empty() && has(f, k)) mk = k;
    for (const std::string& k : kDistortionKeys)
      if (dk.empty() && has(f, k)) dk = k;
    if (mk.empty())
      throw OpenCvCalibError(
          file +
          ": no camera matrix (expected camera_matrix [+ distortion_coefficients] as written by "
          "OpenCV's calibration sample, or M1, D1, M2, D2 as written by its stereo sample)");
    OpenCvCamera cam;
    cam.K = read_camera_matrix(f, mk, file);
    if (!dk.empty()) cam.D = read_vector(f, dk, file);
    cam.width = common_w, cam.height = common_h;
    c.cameras.push_back(cam);
  }
  if (has(f, "omma_camera_ids")) {
    std::vector<int> ids;
    f["omma_camera_ids"] >> ids;
    if (ids.size() != c.cameras.size())
      throw OpenCvCalibError(
          fmt::format("{}: omma_camera_ids holds {} ids for {} cameras", file, ids.size(), c.cameras.size()));
    for (size_t i = 0; i < ids.size(); ++i) c.cameras[i].id = ids[i];
  }
  if (has(f, "omma_R1") && has(f, "omma_C1_mm")) {
    const cv::Mat R = read_mat(f, "omma_R1", file);
    const std::vector<double> C = read_vector(f, "omma_C1_mm", file);
    if (R.rows != 3 || R.cols != 3 || C.size() != 3)
      throw OpenCvCalibError(file + ": omma_R1 / omma_C1_mm malformed");
    c.R1 = cv::Matx33d(R.ptr<double>());
    check_rotation(to_eigen(*c.R1), file + ": 'omma_R1'");
    c.C1_mm = cv::Vec3d(C[0], C[1], C[2]);
  }
  if (has(f, "omma_T_unit")) c.t_unit = std::string(f["omma_T_unit"]);
  return c;
}

DomeInfo dome_around(const Rig& rig, const std::string& method) {
  DomeInfo d;
  d.radius_mm = 0;
  d.sphere = false;
  d.method = method;
  for (const RigCamera& c : rig.cameras) {
    d.radius_mm = std::max(d.radius_mm, c.position_mm.norm());
    const double polar = std::acos(std::clamp(c.frame.t.z() / c.frame.t.norm(), -1.0, 1.0));
    if (polar + c.in.aov / 2 > kPi / 2 + 1e-12) d.sphere = true;
  }
  return d;
}

OpenCvRigSummary rig_from_opencv(const OpenCvCalibration& calib, const OpenCvRigOptions& opt) {
  if (calib.cameras.empty()) throw OpenCvCalibError("the calibration holds no camera");
  if (!opt.sizes.empty() && opt.sizes.size() != calib.cameras.size())
    throw std::invalid_argument(
        fmt::format("{} image sizes given for {} cameras", opt.sizes.size(), calib.cameras.size()));
  if (!(opt.scale_mm > 0 && std::isfinite(opt.scale_mm)))
    throw std::invalid_argument("the scale (mm per unit) must be a positive number");
  OpenCvRigSummary s;
  s.rig.name = opt.name;
  const size_t n = calib.cameras.size();
  bool any_rt = false, all_rt = true;
  for (size_t i = 1; i < n; ++i) {
    any_rt |= calib.cameras[i].R.has_value();
    all_rt &= calib.cameras[i].R.has_value();
  }
  if (any_rt && !all_rt) throw OpenCvCalibError("the calibration gives R, T for some cameras but not all");
  if (n > 1 && !all_rt && !(opt.baseline_mm > 0))
    throw std::invalid_argument(
        "the calibration holds no R, T between its cameras: give the baseline (--baseline MM, camera i sits "
        "(i - 1) x baseline along camera 1's image x axis)");
  // The frame of OpenCV's R, T is camera 1's; omma's export carries camera 1's pose in the rig.
  const bool own = calib.R1.has_value() && calib.C1_mm.has_value();
  const Mat3 R1 = own ? to_eigen(*calib.R1) : default_rotation();
  const Vec3 C1 = own ? Vec3((*calib.C1_mm)[0], (*calib.C1_mm)[1], (*calib.C1_mm)[2]) : Vec3::Zero();
  // omma's export writes T in mm: the default scale_mm = 1 reads it back.
  for (size_t i = 0; i < n; ++i) {
    const OpenCvCamera& cam = calib.cameras[i];
    RigCamera rc;
    rc.id = cam.id >= 0 ? cam.id : int(i);
    const std::string where = fmt::format("camera {} ({} of the file)", rc.id, i + 1);
    const int w = opt.sizes.empty() ? opt.width : opt.sizes[i].first;
    const int h = opt.sizes.empty() ? opt.height : opt.sizes[i].second;
    LensConversion conv;
    rc.in = opencv_intrinsics(cam, w, h, where, &conv, &s.warnings);
    s.max_fit_px = std::max(s.max_fit_px, conv.max_px);
    Mat3 Ri = R1;
    Vec3 Ci = C1;
    if (i > 0) {
      if (all_rt) {
        Ri = to_eigen(*cam.R) * R1;
        const Vec3 T((*cam.T)[0], (*cam.T)[1], (*cam.T)[2]);
        Ci = C1 - Ri.transpose() * T * opt.scale_mm;
      } else {
        Ci = C1 + double(i) * opt.baseline_mm * R1.row(0).transpose();
      }
    }
    rc.frame = frame_from_rotation(Ri);
    rc.position_mm = Ci;
    s.rig.cameras.push_back(rc);
  }
  if (!own) {
    Vec3 centroid = Vec3::Zero();
    for (const auto& c : s.rig.cameras) centroid += c.position_mm;
    centroid /= double(n);
    for (auto& c : s.rig.cameras) c.position_mm -= centroid;
  }
  s.rig.dome = dome_around(s.rig, "opencv calibration");
  s.rig.validate();
  return s;
}

std::string opencv_calibration_text(const Rig& rig, const std::string& extension) {
  rig.validate();
  const bool xml = extension == ".xml";
  cv::FileStorage f(xml ? ".xml" : ".yml",
                    cv::FileStorage::WRITE | cv::FileStorage::MEMORY |
                        (xml ? cv::FileStorage::FORMAT_XML : cv::FileStorage::FORMAT_YAML));
  const size_t n = rig.cameras.size();
  f.writeComment(fmt::format(
      " omma rig '{}': {} camera(s). Pixel centres at integers (OpenCV): cx = cu - 0.5.", rig.name, n));
  f.writeComment(" Distortion (k1, k2, p1, p2, k3) = omma (k1, k2, k4, k3, k5), exact. Lengths in mm.");
  bool same = true;
  for (const auto& c : rig.cameras)
    same &= c.in.width == rig.cameras[0].in.width && c.in.height == rig.cameras[0].in.height;
  if (same) {
    f << "image_width" << rig.cameras[0].in.width;
    f << "image_height" << rig.cameras[0].in.height;
  }
  std::vector<int> ids;
  for (const auto& c : rig.cameras) ids.push_back(c.id);
  const Mat3 R1 = camera_rotation(rig.cameras[0].frame);
  const Vec3 C1 = rig.cameras[0].position_mm;
  if (n == 1) {
    const Intrinsics& in = rig.cameras[0].in;
    f << "camera_matrix" << cv::Mat(opencv_camera_matrix(in));
    f << "distortion_coefficients" << cv::Mat(opencv_from_omma_k(in.k)).clone();
  } else {
    for (size_t i = 0; i < n; ++i) {
      const Intrinsics& in = rig.cameras[i].in;
      if (!same) {
        f << fmt::format("image_width{}", i + 1) << in.width;
        f << fmt::format("image_height{}", i + 1) << in.height;
      }
      f << fmt::format("M{}", i + 1) << cv::Mat(opencv_camera_matrix(in));
      f << fmt::format("D{}", i + 1) << cv::Mat(opencv_from_omma_k(in.k)).reshape(1, 1).clone();
    }
    for (size_t i = 1; i < n; ++i) {
      const Mat3 Ri = camera_rotation(rig.cameras[i].frame);
      const Mat3 R = Ri * R1.transpose();  // x_i = R x_1 + T
      const Vec3 T = Ri * (C1 - rig.cameras[i].position_mm);
      const cv::Mat Rm(to_cv(R)), Tm(cv::Vec3d(T.x(), T.y(), T.z()));
      if (i == 1) {
        f.writeComment(
            " R, T: camera 2 relative to camera 1 as cv::stereoCalibrate gives them (x2 = R x1 + T)");
        f << "R" << Rm << "T" << Tm;
      }
      f << fmt::format("R{}", i + 1) << Rm << fmt::format("T{}", i + 1) << Tm;
    }
    f << "omma_T_unit"
      << "mm";
  }
  f << "omma_camera_ids" << ids;
  f.writeComment(
      " camera 1's pose in the rig frame: rows u, v, t (x right, y down, z forward); centre in mm");
  f << "omma_R1" << cv::Mat(to_cv(R1));
  f << "omma_C1_mm" << cv::Mat(cv::Vec3d(C1.x(), C1.y(), C1.z()));
  return f.releaseAndGetString();
}

void write_opencv_calibration(const Rig& rig, const fs::path& path) {
  write_text_atomically(path, opencv_calibration_text(rig, lower_extension(path)));
}

}  // namespace omma::calib
