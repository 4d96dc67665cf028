// COLMAP's text model (cameras.txt, images.txt, points3D.txt) <-> omma rigs.
//
// The conventions (COLMAP's documentation, "Output Format" and "Camera Models"), checked against the
// `colmap` binary in colmap_test.cc:
//   * images.txt, two lines per image:
//       IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME
//       POINTS2D[] as (X, Y, POINT3D_ID)          (omma writes it empty)
//     (QW, QX, QY, QZ) is the Hamilton unit quaternion of the WORLD-TO-CAMERA rotation R and
//     (TX, TY, TZ) its translation: x_cam = R X + T; the camera centre is C = -R^T T.
//   * COLMAP's camera axes: x right, y down, z forward (the viewing direction) = omma's u, v, t.
//     So R's rows are (u, v, t) of the camera in the world frame, and omma's dome frame IS the world.
//   * cameras.txt: CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]. Pixel coordinates put the centre of the
//     top-left pixel at (0.5, 0.5), as omma does (conventions.h): cx = cu, cy = cv with no shift
//     (OpenCV's files differ by 0.5: opencv_calib.h).
//   * Camera models (normalised x, y, r^2 = x^2 + y^2):
//       SIMPLE_PINHOLE f cx cy;  PINHOLE fx fy cx cy;  SIMPLE_RADIAL f cx cy k;  RADIAL f cx cy k1 k2;
//       OPENCV fx fy cx cy k1 k2 p1 p2;  FULL_OPENCV fx fy cx cy k1 k2 p1 p2 k3 k4 k5 k6
//     with OpenCV's formula (opencv_calib.h): omma (k1, k2, k3, k4, k5) = (k1, k2, p2, p1, k3).
//   * Units: omma's export writes mm (1 COLMAP unit = 1 mm). A COLMAP reconstruction has an
//     arbitrary scale: the import multiplies lengths by ColmapImportOptions::scale_mm (mm per unit).
//
// Export (exact): one COLMAP camera and one image per omma camera, CAMERA_ID = IMAGE_ID = rig index
// + 1, NAME = cam_XX.png (omma's frames folder, core/frames.h); model PINHOLE without distortion,
// OPENCV when k5 = 0, FULL_OPENCV (k4 = k5 = k6 = 0) otherwise. points3D.txt is empty. What COLMAP does
// not hold (rig name, dome, each camera's id, field and aov, photometric model) rides in a comment
// line "# omma-rig {rig JSON}" at the top of cameras.txt, which COLMAP ignores (and drops when it
// rewrites the model).
//
// Import: SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL and OPENCV convert exactly; FULL_OPENCV
// exactly when k4 = k5 = k6 = 0, otherwise its rational radial factor is fitted (opencv_calib.h) and the
// residual in pixels reported; any other model (the fisheye models, FOV, THIN_PRISM_FISHEYE, ...) is
// refused naming the model and the camera. Image names cam_XX.* (any folder, any extension) give
// camera id XX; when not every name has that form, the ids are 0, 1, ... in IMAGE_ID order (reported).
// With the omma-rig comment line (an omma export), the name, dome, field, aov and photometric model of
// each camera come from it (field and aov only where the COLMAP intrinsics still equal the comment's);
// otherwise each camera sees its whole image (Intrinsics::Field::kImage, aov = bounding_aov(),
// calib::choose_field), the cameras' centroid becomes the dome centre (unless keep_origin), the
// dome radius is the largest camera distance from it, and the name is the model folder's.
#pragma once

#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "omma/core/rig.h"

namespace omma::calib {

class ColmapError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ColmapCamera {
  long long id = 0;
  std::string model;
  int width = 0, height = 0;
  std::vector<double> params;
};

// omma intrinsics as a COLMAP camera (the export's model choice, above).
ColmapCamera colmap_camera(const Intrinsics& in, long long id);
// A COLMAP camera as omma intrinsics (k, fu, fv, cu, cv, size; field and aov via choose_field).
// *max_fit_px: the distortion fit residual (0 when exact); notes appended to *warnings.
Intrinsics intrinsics_from_colmap(const ColmapCamera& cam, const std::string& where,
                                  double* max_fit_px = nullptr, std::vector<std::string>* warnings = nullptr);

struct ColmapText {
  std::string cameras, images, points3D;
};
ColmapText colmap_text(const Rig& rig);

struct ColmapExportSummary {
  std::map<std::string, int> models;  // model name -> number of cameras
};
// Writes DIR/cameras.txt, images.txt, points3D.txt (DIR is created; each file atomic).
ColmapExportSummary export_colmap(const Rig& rig, const std::filesystem::path& dir);

struct ColmapImportOptions {
  double scale_mm = 1;       // mm per COLMAP length unit
  bool keep_origin = false;  // without omma's comment: keep COLMAP's world origin as the dome centre
  std::string name;          // rig name ("" = the omma comment's, else the model folder's name)
};
struct ColmapImportSummary {
  Rig rig;
  std::filesystem::path model_dir;                  // the folder read
  std::map<std::string, int> models;                // model name -> number of cameras
  std::vector<std::pair<std::string, int>> images;  // image NAME -> omma camera id
  bool ids_from_names = true;                       // every NAME was cam_XX.*
  bool omma_metadata = false;                       // the omma-rig comment was used
  double max_fit_px = 0;                            // distortion conversion residual (0 = exact)
  std::vector<std::string> warnings;
};
// `path`: a folder with cameras.txt and images.txt, or one holding such a folder as 0/ or sparse/0/.
// A binary model (.bin only) is refused with the command that converts it. Throws ColmapError naming
// the file and line at fault.
ColmapImportSummary import_colmap(const std::filesystem::path& path, const ColmapImportOptions& opt = {});
// The same from the two files' text; `folder_name` names the rig when nothing else does.
ColmapImportSummary import_colmap_text(const std::string& cameras_txt, const std::string& images_txt,
                                       const ColmapImportOptions& opt, const std::string& folder_name);
// The folder import_colmap reads for `path` (see above); throws ColmapError if there is none.
std::filesystem::path find_colmap_model(const std::filesystem::path& path);

}  // namespace omma::calib
