#include "omma/design/prototype.h"

#include <vector>

#include "omma/design/dome.h"
#include "omma/design/placement.h"

namespace omma::design {

// Azimuth (deg) of the first camera of each layer. These are the offsets design_max_volume's
// coordinate search finds for this dome (checked by prototype_test): they minimise the covering
// radius, giving R_vir = 14.0 mm with the geometric coverage model (coverage.h).
static constexpr double kPrototypeLayerOffsetsDeg[3] = {0.0, 11.0, 0.0};

Rig thesis_prototype_rig() {
  const MaxVolumeLayout l = max_volume_layout(5.0, CameraSize{1.0, 1.0, 2.0});  // 3, 9, 12
  std::vector<Vec3> axes;
  for (size_t i = 0; i < l.per_layer.size(); ++i) {
    const int n = l.per_layer[i];
    for (int k = 0; k < n; ++k)
      axes.push_back(direction_from_spherical(
          l.polar_rad[i], deg2rad(kPrototypeLayerOffsetsDeg[i]) + 2 * kPi * k / n));
  }
  return radial_rig(axes, 5.0, ideal_intrinsics(deg2rad(64)), false, "max-volume", "thesis-24");
}

}  // namespace omma::design
