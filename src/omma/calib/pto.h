// Hugin / PanoTools project files (.pto): export a rig, import a project as a rig.
//
// The mapping between omma's conventions (conventions.h, eq. 3.13, eq. 5.21-5.26) and PanoTools'
// (libpano13, as used by Hugin's nona), worked out here and checked against nona in pto_test.cc:
//
// World frame. PanoTools' (yaw, pitch) = (0, 0) looks at the centre of its equirect panorama,
// positive yaw turns right, positive pitch looks up. We map:
//     PT forward F (y = p = 0) = dome -x,   PT up U = dome +z,   PT right R = F x U = dome +y.
//   A PanoTools equirect panorama (360 x 180) then has longitude lambda = 180 deg - phi and latitude
//   90 deg - theta: its pixels ARE omma's equirect-full pixels, both the world seen the right way
//   round (conventions.h (G1): x = W (180 deg - phi) / 360 deg + W / 2 = -W phi / 360 deg mod W),
//   and the top half is omma's 360 x 90 equirect grid. nona's output and omma's stitch are compared
//   as they are, with no flip (pto_test.cc).
//
// Camera orientation. PanoTools' camera at y = p = r = 0 has optical axis F, image right R, image
// down -U, i.e. (t, u, v) = (-x, +y, -z) in the dome frame. A camera with (y, p, r) is
//     [t u v] = Rz(-y) * Ry(p) * Rot_t0(r) * [t0 u0 v0]    (columns, dome frame)
//   with Rot_t0(r) the rotation by r about the base optical axis t0 = -x that turns u towards v
//   (image right towards image down: positive roll turns the picture clockwise as seen in the
//   panorama), then pitch about R = +y, then yaw about -U (so that yaw turns F towards R).
//   Inverse: yaw = atan2(t.y, -t.x), pitch = asin(t.z), roll = atan2(u.v0', u.u0') with (u0', v0')
//   the axes of the camera with zero roll. omma's eq. 3.13 (yaw, pitch, roll) are a different
//   parametrisation of the same frame; the frame (t, u, v) is what is converted.
//
// Focal length and principal point. PanoTools rectilinear (f0) images have one focal length,
//   f_pt = (W/2) / tan(v/2), v = horizontal field of view in degrees. The optical centre is the
//   image centre plus the shifts d (x) and e (y) in pixels; PanoTools' pixel (i, j) has its centre
//   at integer coordinates relative to (W/2 - 0.5, H/2 - 0.5), so in omma's convention
//     cu = W/2 + d,   cv = H/2 + e.
//   fu != fv cannot be held (the export uses sqrt(fu fv) and warns).
//
// Distortion. PanoTools: ideal radius rho_i = f_pt tan(angle), r = rho_i / R0 with R0 = min(W, H)/2,
//   source radius rho_s = rho_i (a r^3 + b r^2 + c r + 1 - a - b - c).
//   omma: rho_s = f R (1 + k1 R^2 + k2 R^4 + k5 R^6) with R = tan(angle); tangential k3, k4 have no
//   PanoTools counterpart (dropped with a warning).
//   Both are radial functions rho_s(R); PanoTools' has only odd powers up to R^4 and a free scale
//   (f_pt), omma's has even powers of R in the bracket. k1 alone maps EXACTLY (a = c = 0,
//   b / (1 - b)^3 = k1 R0^2 / f^2, f_pt = f / (1 - b)); k2, k5 in general do not, so the export
//   fits (f_pt, a, b, c) by least squares over the image (area weighted, out to the corners) and
//   reports the residual in pixels; the import fits (f, k1, k2, k5) the same way (linear least
//   squares). A k1-only rig round-trips exactly.
//
// Photometry (core/photometric.h). omma's model is Hugin's radial vignetting and exposure / white
//   balance: Va1, Vb = b, Vc = c, Vd = d, Vx = x, Vy = y (pixels; Hugin's centre (W-1)/2 + Vx with
//   integer pixel centres is omma's W/2 + x), Vm5 (radial, correction by division), and
//   Eev = -log2(gain_G), Er = gain_R / gain_G, Eb = gain_B / gain_G (Hugin divides a pixel by
//   V * 2^-Eev and red by Er, blue by Eb: the same as omma's division by gain_c * V). A camera
//   without a model is written Vb0 Vc0 Vd0 Vx0 Vy0 Eev0 Er1 Eb1. Hugin applies the division in the
//   linear light of its camera response: with `linear_response` the export writes Rt1 (pixel values
//   are linear light; use linear frames, e.g. 16-bit), otherwise Hugin's default EMoR curve (Ra..Re
//   0), which is not sRGB, so nona's corrected brightness then differs from omma's (measured in
//   pto_test.cc). The import reads the same fields (Va != 1 is folded into the gains; a radial
//   model only when Vm has the radial bit).
//
// Not held by PTO and carried in "#-omma" comment lines that Hugin ignores: camera id, position
// (mm), angle of view of the cone (eq. 2.3), fu/fv ratio, and the rig name and dome radius.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "omma/core/rig.h"

namespace omma::calib {

class PtoError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct PtoCamera {
  int width = 0, height = 0;
  double yaw_deg = 0, pitch_deg = 0, roll_deg = 0;
  double hfov_deg = 0;  // v
  double a = 0, b = 0, c = 0;
  double d = 0, e = 0;  // shifts, pixels
  std::string image;    // n"..."
};

// PanoTools camera <-> omma camera (the conversions documented above).
struct LensFit {
  double rms_px = 0, max_px = 0;  // residual of the radial conversion over the image
};
PtoCamera pto_from_camera(const RigCamera& cam, LensFit* fit = nullptr);
// `keep` supplies what PTO does not hold (id, position, aov, fv/fu); pass nullptr for defaults
// (aov = the horizontal field of view widened to the image corners, position = 5 mm along t).
RigCamera camera_from_pto(const PtoCamera& p, int radial_terms = 3, LensFit* fit = nullptr);

struct PtoExportOptions {
  std::string frames_dir;        // image paths are frames_dir/cam_XX.png (relative to the PTO's folder
                                 // when possible); empty: bare "cam_XX.png"
  int pano_width = 1440;         // p-line: equirect 360 x 180 of pano_width x pano_width/2
  bool crop_to_dome = true;      // hemisphere rigs: crop the p-line to the top half (omma's 360 x 90)
  int interpolator = 0;          // m-line i: 0 poly3 (Hugin's default), 5 bilinear, 6 nearest
  bool linear_response = false;  // i-lines Rt1: the frames are linear light (see Photometry above)

  // False (with the reason in *why) when a value lies outside the range the code relies on.
  bool IsValid(std::string* why = nullptr) const;
};

struct PtoExportSummary {
  std::string text;
  double max_fit_px = 0;  // largest distortion-conversion residual over all cameras
  double rms_fit_px = 0;
  std::vector<std::string> warnings;
};

PtoExportSummary export_pto(const Rig& rig, const PtoExportOptions& opt = {});

struct PtoImportSummary {
  Rig rig;
  double max_fit_px = 0;
  std::vector<std::string> warnings;
};

// Parses PTO text. `base_dir` resolves image names (for images whose size the i-line lacks, and
// to warn about missing images). Throws PtoError on unsupported lens types (anything but f0
// rectilinear), missing sizes with missing images, or no images at all.
PtoImportSummary import_pto(const std::string& text, const std::filesystem::path& base_dir = {});

}  // namespace omma::calib
