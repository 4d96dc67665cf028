// OpenCV calibration files (cv::FileStorage, YAML or XML) <-> omma cameras and rigs.
//
// Layouts read (the first that matches):
//   * OpenCV's calibration sample (samples/cpp/calibration.cpp, left_intrinsics.yml):
//       camera_matrix (3x3), distortion_coefficients (1xN or Nx1), optional image_width, image_height.
//     Also accepted: cameraMatrix | K for the matrix, distCoeffs | dist_coeffs | D for the vector.
//   * The stereo layout of cv::stereoCalibrate's sample (intrinsics.yml, extrinsics.yml):
//       M1, D1, M2, D2 (+ M3, D3, ... for more cameras: omma's extension), optional R, T: camera 2
//       relative to camera 1 as cv::stereoCalibrate defines them, x2 = R x1 + T with x1, x2 a point in
//       the two cameras' coordinates (x right, y down, z forward) and T in the calibration's length
//       unit (the chessboard's square size unit). omma's export adds Ri, Ti (i >= 2, R2 = R, T2 = T),
//       image_width / image_height (or image_widthI / image_heightI when the sizes differ),
//       omma_camera_ids, and camera 1's pose in the rig frame (omma_R1: rows u, v, t; omma_C1_mm).
//
// Conventions (conventions.h):
//   * Pixel centres: OpenCV puts the centre of the top-left pixel at (0, 0), omma at (0.5, 0.5):
//       cu = cx + 0.5,  cv = cy + 0.5,   fu = fx, fv = fy.
//     The camera matrix must be [fx 0 cx; 0 fy cy; 0 0 1] (omma's model has no skew).
//   * Axes: OpenCV's camera x, y, z are omma's u, v, t (x right, y down, z forward).
//   * Distortion: OpenCV's model (k1, k2, p1, p2[, k3[, k4, k5, k6[, s1..s4[, tx, ty]]]]) is
//       x' = x (1 + k1 r^2 + k2 r^4 + k3 r^6) / (1 + k4 r^2 + k5 r^4 + k6 r^6) + 2 p1 x y + p2 (r^2 + 2 x^2)
//       y' = y (...) / (...) + p1 (r^2 + 2 y^2) + 2 p2 x y   (+ thin prism s1..s4, tilt tx, ty)
//     and omma's (eq. 5.23-5.26) x' = p x + 2 k4 x y + k3 (R2 + 2 x^2), y' = p y + 2 k3 x y + k4 (R2 + 2
//     y^2), p = 1 + k1 R2 + k2 R2^2 + k5 R2^3. They coincide EXACTLY with
//       omma (k1, k2, k3, k4, k5) = OpenCV (k1, k2, p2, p1, k3)
//     (checked against cv::projectPoints in opencv_calib_test.cc). Hence vectors of 4 and 5 coefficients
//     convert exactly; 8 exactly when k4 = k5 = k6 = 0, otherwise the rational radial factor is FITTED
//     by omma's polynomial (linear least squares of k1, k2, k5 over the image; the tangential terms stay
//     exact) and the residual in pixels is reported; 12 or 14 coefficients convert when the thin prism
//     and tilt terms are all zero and are refused otherwise (omma's model has no such terms).
//   * Units: omma writes T in mm (omma_T_unit: "mm"); a file's T is read in its own unit, scaled by
//     OpenCvRigOptions::scale_mm (mm per file unit).
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/core/rig.h"

namespace omma::calib {

class OpenCvCalibError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// An OpenCV distortion vector as omma's (k1..k5). `in` supplies the focal lengths, principal point
// and size over which a fit is made and its residual measured. Throws OpenCvCalibError naming
// `where` for a length other than 0, 4, 5, 8, 12, 14 and for non-zero thin prism / tilt terms.
struct LensConversion {
  std::array<double, 5> k{};
  bool exact = true;  // false: the radial factor was fitted
  double max_px = 0;  // fit residual over the image (0 when exact)
  double rms_px = 0;
  std::string note;  // what was done ("" when exact)
};
LensConversion omma_k_from_opencv(const std::vector<double>& d, const Intrinsics& in,
                                  const std::string& where);
// omma's k as OpenCV's 5 coefficients (k1, k2, p1, p2, k3): exact.
std::vector<double> opencv_from_omma_k(const std::array<double, 5>& k);
// [fx 0 cx; 0 fy cy; 0 0 1] of a camera (cx = cu - 0.5, cy = cv - 0.5).
cv::Matx33d opencv_camera_matrix(const Intrinsics& in);

// What the camera sees (Intrinsics::field and aov): the whole image (kImage, aov = bounding_aov())
// when the lens model maps the image one to one; otherwise (a calibration whose distortion folds
// back inside the image's corners, e.g. camera 1 of OpenCV's intrinsics.yml) a cone (kCone) of the
// widest angle of view over which it does, and a warning naming `where` is returned. "" otherwise.
// Throws OpenCvCalibError if no cone of 1 deg is valid.
std::string choose_field(Intrinsics& in, const std::string& where);

struct OpenCvCamera {
  cv::Matx33d K = cv::Matx33d::eye();
  std::vector<double> D;
  int width = 0, height = 0;     // 0: the file does not say
  std::optional<cv::Matx33d> R;  // camera i relative to camera 1: x_i = R x_1 + T (file units)
  std::optional<cv::Vec3d> T;
  int id = -1;  // omma camera id (omma_camera_ids), -1: none
};
struct OpenCvCalibration {
  std::string layout;                 // "calibration" or "stereo"
  std::vector<OpenCvCamera> cameras;  // in file order (M1 first)
  std::optional<cv::Matx33d> R1;      // omma_R1 / omma_C1_mm (omma's export only)
  std::optional<cv::Vec3d> C1_mm;
  std::string t_unit;  // omma_T_unit if present
};
// Reads a YAML or XML calibration file; throws OpenCvCalibError naming the file and key at fault.
OpenCvCalibration read_opencv_calibration(const std::filesystem::path& path);

// Camera `index` (0-based) of a file as omma Intrinsics: size from width/height (> 0) or else the
// file; throws if neither has one. Distortion via omma_k_from_opencv, field via choose_field
// (warnings appended to *warnings).
Intrinsics opencv_intrinsics(const OpenCvCamera& cam, int width, int height, const std::string& where,
                             LensConversion* conv = nullptr, std::vector<std::string>* warnings = nullptr);

// A rig from a calibration file. Camera 1 looks along +x with its image upright (t = +x, u = -y,
// v = -z, i.e. eq. 3.13 yaw 0, pitch 0, roll 180 deg) unless the file holds omma_R1 / omma_C1_mm;
// camera i >= 2 is placed by its R, T (T times scale_mm); without R, T (and more than one camera)
// camera i sits (i - 1) * baseline_mm along camera 1's u with camera 1's orientation (a rectified
// stereo pair). Without omma_C1_mm the cameras' centroid is the dome centre. Dome radius = the largest
// camera distance from the centre; sphere unless every camera's field stays above the horizon.
struct OpenCvRigOptions {
  int width = 0, height = 0;               // every camera's size when > 0 (overrides the file)
  std::vector<std::pair<int, int>> sizes;  // per camera, when not empty (overrides width/height)
  double scale_mm = 1;                     // mm per unit of the file's T
  double baseline_mm = -1;                 // < 0: none given
  std::string name = "opencv";
};
struct OpenCvRigSummary {
  Rig rig;
  double max_fit_px = 0;  // largest distortion fit residual (0 when every conversion was exact)
  std::vector<std::string> warnings;
};
OpenCvRigSummary rig_from_opencv(const OpenCvCalibration& calib, const OpenCvRigOptions& opt);

// The dome of cameras placed anywhere: radius = the largest camera distance from the origin, sphere
// unless every camera's field (its cone of aov around t) stays above the horizon (z >= 0).
DomeInfo dome_around(const Rig& rig, const std::string& method);

// Writes a rig as an OpenCV calibration file (YAML, or XML for a .xml path): one camera in the
// calibration sample's layout, two or more in the stereo layout with R, T (mm). Atomic.
void write_opencv_calibration(const Rig& rig, const std::filesystem::path& path);
// The same as text (format by `extension`: ".xml" or YAML).
std::string opencv_calibration_text(const Rig& rig, const std::string& extension = ".yml");

}  // namespace omma::calib
