// The thesis prototype rig (§3.4.2, Fig. 3.8, Table 3.1).
#include "omma/design/prototype.h"

#include <gtest/gtest.h>

#include "omma/design/coverage.h"
#include "omma/design/placement.h"

namespace omma::design {
namespace {

TEST(Prototype, TwentyFourCamerasInLayersOf3_9_12) {
  const Rig rig = thesis_prototype_rig();
  ASSERT_EQ(rig.cameras.size(), 24u);
  EXPECT_NO_THROW(rig.validate());
  EXPECT_EQ(rig.name, "thesis-24");
  const double polar_deg[] = {15, 45, 75};
  const int first[] = {0, 3, 12}, count[] = {3, 9, 12};
  for (int l = 0; l < 3; ++l)
    for (int k = first[l]; k < first[l] + count[l]; ++k) {
      const RigCamera& c = rig.cameras[k];
      EXPECT_EQ(c.id, k);
      EXPECT_NEAR(rad2deg(spherical_from_direction(c.frame.t).theta), polar_deg[l], 1e-9);
      EXPECT_NEAR(c.position_mm.norm(), 5.0, 1e-12);
      EXPECT_NEAR((c.position_mm.normalized() - c.frame.t).norm(), 0, 1e-12);
      EXPECT_EQ(c.in.width, 250);
      EXPECT_EQ(c.in.height, 250);
      EXPECT_NEAR(c.in.fu, 200.042, 0.001);  // 125 / tan(32 deg)
      EXPECT_EQ(c.in.fu, c.in.fv);
      EXPECT_EQ(c.in.cu, 125);
      EXPECT_EQ(c.in.cv, 125);
      EXPECT_NEAR(rad2deg(c.in.aov), 64, 1e-12);
      // Image "down" points away from the pole: v has a negative z component.
      EXPECT_LT(c.frame.v.z(), 0);
      EXPECT_NEAR(c.frame.u.z(), 0, 1e-12);
    }
}

TEST(Prototype, SameRigAsTheMaxVolumeDesigner) {
  DesignParams p;
  p.cam = CameraSize{1, 1, 2};
  const Design d = design_max_volume(p);
  const Rig rig = thesis_prototype_rig();
  ASSERT_EQ(d.rig.cameras.size(), rig.cameras.size());
  for (size_t i = 0; i < rig.cameras.size(); ++i)
    EXPECT_NEAR((d.rig.cameras[i].frame.t - rig.cameras[i].frame.t).norm(), 0, 1e-9) << i;
}

TEST(Prototype, VirtualRadiusOfTheGeometricModel) {
  // The thesis reports R_vir = 18 mm; the ideal 64 deg cones of this model overlap from 14 mm on.
  const double rvir = virtual_radius(thesis_prototype_rig(), deg2rad(0.25));
  EXPECT_NEAR(rvir, 14.0, 0.1);
}

}  // namespace
}  // namespace omma::design
