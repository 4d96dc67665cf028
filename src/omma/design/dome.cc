#include "omma/design/dome.h"

#include <algorithm>
#include <cmath>

namespace omma::design {

Intrinsics ideal_intrinsics(double aov_rad, int width, int height) {
  Intrinsics in;
  in.width = width;
  in.height = height;
  in.fu = in.fv = Intrinsics::focal_for_aov(std::min(width, height), aov_rad);
  in.cu = width / 2.0;
  in.cv = height / 2.0;
  in.k = {0, 0, 0, 0, 0};
  in.aov = aov_rad;
  return in;
}

RigCamera radial_camera(int id, const Vec3& t, double r_phys_mm, const Intrinsics& in) {
  RigCamera cam;
  cam.id = id;
  cam.frame = frame_looking_at(t.normalized(), -Vec3::UnitZ());
  cam.position_mm = r_phys_mm * cam.frame.t;
  cam.in = in;
  return cam;
}

Rig radial_rig(const std::vector<Vec3>& axes, double r_phys_mm, const Intrinsics& in, bool sphere,
               const std::string& method, const std::string& name) {
  Rig rig;
  rig.name = name;
  rig.dome.radius_mm = r_phys_mm;
  rig.dome.sphere = sphere;
  rig.dome.method = method;
  for (size_t i = 0; i < axes.size(); ++i)
    rig.cameras.push_back(radial_camera(static_cast<int>(i), axes[i], r_phys_mm, in));
  rig.validate();
  return rig;
}

double reach_angle(double aov_rad, double r_phys_mm, double r_vir_mm) {
  const double h = aov_rad / 2;
  const double s = std::clamp(r_phys_mm / r_vir_mm * std::sin(h), -1.0, 1.0);
  return h - std::asin(s);  // eq. 3.2
}

double distance_for_reach(double aov_rad, double r_phys_mm, double beta_rad) {
  const double h = aov_rad / 2;
  if (beta_rad >= h) return kInfinity;
  return r_phys_mm * std::sin(h) / std::sin(h - beta_rad);  // eq. 3.1
}

}  // namespace omma::design
