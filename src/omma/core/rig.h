// The rig model: a dome carrying N cameras, and its JSON file format.
// Conventions (axes, angles, units, pixel centres): conventions.h. Files hold mm and degrees.
//
// Rig file (JSON):
// {
//   "format": "omma-rig", "version": 1, "name": "thesis-24",     (other versions are refused)
//   "dome": {"radius_mm": 5.0, "sphere": false, "method": "max-volume"},
//   "cameras": [
//     {"id": 0,
//      "t": [0,0,1], "u": [0,1,0], "v": [-1,0,0],      // or "ypr_deg": [yaw, pitch, roll] (eq. 3.13)
//      "position_mm": [0,0,5],
//      "intrinsics": {"width": 250, "height": 250, "fu": 200, "fv": 200, "cu": 125, "cv": 125,
//                     "k": [0,0,0,0,0], "aov_deg": 64},
//      "photometric": {"vignetting": [b, c, d], "vignetting_center_px": [x, y],   // optional,
//                      "gains_bgr": [B, G, R]}}, ...]                            // photometric.h
// }
// Intrinsics may add "field": "cone" (the default: the cone of aov_deg, eq. 2.3) or "image" (the
// camera sees what lands inside its image; aov_deg may be left out and is recomputed on loading as
// the bounding cone of the image, Intrinsics::bounding_aov).
// Loading validates everything and throws RigError naming the camera and field at fault.
#pragma once

#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "omma/core/camera.h"
#include "omma/core/photometric.h"

namespace omma {

class RigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct DomeInfo {
  double radius_mm = 5.0;  // outer radius of the dome the cameras sit on
  bool sphere = false;     // full sphere (true) or hemisphere around +z (false)
  std::string method;      // how the rig was designed (free text, e.g. "max-volume")
};

struct RigCamera {
  int id = 0;
  Frame frame;
  Vec3 position_mm = Vec3::Zero();  // camera centre in the dome frame, mm
  Intrinsics in;
  std::optional<Photometric> photometric;  // vignetting and colour gains (photometric.h); none = uncorrected
  CameraModel model() const { return CameraModel{frame, in}; }
};

struct Rig {
  std::string name;
  DomeInfo dome;
  std::vector<RigCamera> cameras;

  // Throws RigError if anything is inconsistent (see validate_camera).
  // Also: at most kMaxCameras cameras, unique ids.
  void validate() const;
};

// Validates one camera: finite numbers, unit and orthogonal right-handed frame (tolerance 1e-3),
// image size, focal lengths, principal point, distortion and position within the bounds of
// core/limits.h, aov in (0, 180) degrees, and the photometric model if any (validate_photometric:
// positive gains, a falloff that stays above 0.02 over the image).
void validate_camera(const RigCamera& cam);

nlohmann::json rig_to_json(const Rig& rig);
Rig rig_from_json(const nlohmann::json& j);       // validates
Rig load_rig(const std::filesystem::path& path);  // validates; RigError with the path on failure
// Does any camera carry a photometric model?
bool has_photometric(const Rig& rig);
void save_rig(const Rig& rig, const std::filesystem::path& path);  // atomic (temp file + rename)

}  // namespace omma
