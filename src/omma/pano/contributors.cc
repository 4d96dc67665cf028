#include "omma/pano/contributors.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "omma/core/valid.h"

namespace omma::pano {

bool SearchOptions::IsValid(std::string* why) const {
  if (!q.allFinite()) return invalid(why, "observer point q must be finite");
  if (!(min_r_mm > 0) || !std::isfinite(min_r_mm))  // |r| divides the weights (eq. 2.5)
    return invalid(why, "min_r_mm must be a positive number of mm");
  return true;
}

double orthographic_distance(const Vec3& q, const Vec3& c, const Vec3& w) {
  const Vec3 d = q - c;
  return (d - d.dot(w) * w).norm();
}

std::vector<Contributor> find_contributors(const Rig& rig, const Vec3& w_in, const SearchOptions& opt) {
  return find_contributors(rig, w_in, std::numeric_limits<double>::infinity(), opt);
}

std::vector<Contributor> find_contributors(const Rig& rig, const Vec3& w_in, double depth_mm,
                                           const SearchOptions& opt) {
  std::string why;
  if (!opt.IsValid(&why)) throw std::invalid_argument("find_contributors: " + why);
  const Vec3 w = w_in.normalized();
  const bool at_infinity = !(depth_mm < std::numeric_limits<double>::infinity());
  std::vector<Contributor> out;
  for (size_t i = 0; i < rig.cameras.size(); ++i) {
    const CameraModel cam = rig.cameras[i].model();
    // The camera's own ray towards X = q + D w (w itself at infinity, the thesis's model).
    const Vec3 ray =
        at_infinity ? w : surface_ray(opt.q, rig.cameras[i].position_mm, w, depth_mm).normalized();
    if (!cam.sees(ray)) continue;  // eq. 2.3
    const auto px = cam.project(ray);
    if (!px || !cam.inside(*px)) continue;
    Contributor c;
    c.camera = static_cast<int>(i);
    c.px = *px;
    c.r = std::max(opt.min_r_mm, orthographic_distance(opt.q, rig.cameras[i].position_mm, w));
    out.push_back(c);
  }
  return out;
}

}  // namespace omma::pano
