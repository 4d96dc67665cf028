// The thesis's 24-camera prototype dome (§3.4.2, Fig. 3.8, Table 3.1).
#pragma once

#include "omma/core/rig.h"

namespace omma::design {

// The prototype: max-volume placement (eq. 3.7-3.11) of 1 x 1 x 2 mm cameras on a 5 mm outer
// radius (inner radius 3 mm), layers of 3, 9 and 12 cameras at polar angles 15, 45 and 75 deg.
// Every camera: 250 x 250 px, AOV 64 deg, fu = fv = Intrinsics::focal_for_aov(250, 64 deg)
// (= 200.04 px), principal point (125, 125), no distortion; pinhole on the dome surface at 5 mm
// along its radial optical axis t; image "down" (+v) points away from the pole (projection of -z),
// image +x (u) = v x t. Camera ids 0..23 go layer by layer from the pole, and within a layer by
// increasing azimuth. The layers' azimuth offsets are fixed values chosen to minimise R_vir
// (see kPrototypeLayerOffsetsDeg in prototype.cc). Deterministic; name "thesis-24".
Rig thesis_prototype_rig();

}  // namespace omma::design
