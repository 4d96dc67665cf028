// Placement methods (§3.3-3.4): the thesis's numbers and the coverage of every produced rig.
#include "omma/design/placement.h"

#include <gtest/gtest.h>

#include "omma/design/coverage.h"
#include "omma/design/dome.h"

namespace omma::design {
namespace {

DesignParams params(double r_virtual, bool sphere = false) {
  DesignParams p;  // AOV 64 deg, R_phy 5 mm (Table 3.1, §3.4)
  p.r_virtual_mm = r_virtual;
  p.sphere = sphere;
  return p;
}

// The rig covers its whole field of view at `distance` on a finer sampling than the designers'.
void expect_covered(const Rig& rig, double distance) {
  const CoverageSummary st = analyze_coverage(rig, distance, deg2rad(0.25));
  EXPECT_DOUBLE_EQ(st.covered_fraction, 1.0) << rig.dome.method << " at " << distance;
  EXPECT_GE(st.min_cameras, 1);
  EXPECT_LE(st.r_virtual_mm, distance);
}

TEST(MaxVolume, ThesisLayersWithTwoMillimetreCameras) {
  // eq. 3.7-3.11 with 1 x 1 x 2 mm cameras on a 5 mm dome: r_in = 3 mm, layers 3, 9, 12.
  const MaxVolumeLayout l = max_volume_layout(5, CameraSize{1, 1, 2});
  EXPECT_NEAR(l.r_in_mm, 3.0, 1e-12);
  EXPECT_NEAR(l.d_cam_mm, std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(rad2deg(l.beta_rad), 15, 1e-9);
  EXPECT_EQ(l.per_layer, (std::vector<int>{3, 9, 12}));
  const Design d = design_max_volume(params(18));
  EXPECT_EQ(d.rig.cameras.size(), 24u);
  EXPECT_EQ(d.layers, (std::vector<int>{3, 9, 12}));
}

TEST(MaxVolume, TableLengthGivesThirteenInTheThirdLayer) {
  // Table 3.1's 1.85 mm length: r_in = 3.15 mm, third layer 13.
  EXPECT_EQ(max_volume_layout(5, CameraSize{1, 1, 1.85}).per_layer, (std::vector<int>{3, 9, 13}));
  // 3, 9, 12 holds for r_in between about 2.87 and 3.03 mm only.
  EXPECT_EQ(max_volume_layout(5, CameraSize{1, 1, 5 - 2.88}).per_layer, (std::vector<int>{3, 9, 12}));
  EXPECT_EQ(max_volume_layout(5, CameraSize{1, 1, 5 - 3.02}).per_layer, (std::vector<int>{3, 9, 12}));
  EXPECT_NE(max_volume_layout(5, CameraSize{1, 1, 5 - 2.85}).per_layer, (std::vector<int>{3, 9, 12}));
  EXPECT_NE(max_volume_layout(5, CameraSize{1, 1, 5 - 3.05}).per_layer, (std::vector<int>{3, 9, 12}));
}

TEST(Layered, PanopticFloorsAtFifteenMillimetres) {
  // §3.4.1: the earlier method needs 29 cameras for R_vir / R_phy = 15 / 5.
  const Design d = design_layered(params(15));
  EXPECT_EQ(d.rig.cameras.size(), 29u);
  EXPECT_EQ(d.layers, (std::vector<int>{1, 5, 10, 13}));
  expect_covered(d.rig, 15);
}

TEST(MinCameras, FewerThanLayeredAtFifteenMillimetres) {
  // The thesis: 22 cameras (vs 29 for the layered method) at R_vir = 15 mm.
  const Design d = design_min_cameras(params(15));
  EXPECT_GE(d.rig.cameras.size(), 22u);
  EXPECT_LE(d.rig.cameras.size(), 25u);
  EXPECT_LT(d.rig.cameras.size(), 29u);
  expect_covered(d.rig, 15);
}

TEST(MinCameras, NeverMoreThanLayeredFrom2_4To7_2) {
  // Fig. 3.7: for 7.2 > R_vir / R_phy > 2.4 the proposed method never needs more cameras.
  for (double ratio = 2.4; ratio <= 7.2 + 1e-9; ratio += 0.4) {
    const DesignParams p = params(5 * ratio);
    const int layered = cameras_needed(Method::kLayered, p);
    const Design d = design_min_cameras(p);
    EXPECT_LE(static_cast<int>(d.rig.cameras.size()), layered) << "R_vir/R_phy = " << ratio;
    expect_covered(d.rig, p.r_virtual_mm);
  }
}

TEST(Cvt, FullSphereAtEighteenMillimetres) {
  // §3.4.3: the thesis reports 48 positions on the full sphere; the ideal 64 deg cones of our
  // geometric model reach farther, so fewer are needed (40).
  const Design d = design_cvt(params(18, true));
  EXPECT_GE(d.rig.cameras.size(), 36u);
  EXPECT_LE(d.rig.cameras.size(), 48u);
  EXPECT_TRUE(d.rig.dome.sphere);
  expect_covered(d.rig, 18);
}

TEST(Designers, EveryRigCoversItsTargetDistance) {
  for (double rv : {12.0, 25.0})
    for (Method m : {Method::kLayered, Method::kMinCameras, Method::kCvt}) {
      const Design d = design_rig(m, params(rv));
      EXPECT_NO_THROW(d.rig.validate());
      EXPECT_LE(d.r_virtual_mm, rv) << to_string(m);
      expect_covered(d.rig, rv);
      int total = 0;
      for (int n : d.layers) total += n;
      EXPECT_EQ(total, static_cast<int>(d.rig.cameras.size()));
      for (const RigCamera& c : d.rig.cameras) {
        EXPECT_NEAR(c.position_mm.norm(), 5.0, 1e-9);
        EXPECT_GE(c.frame.t.z(), -1e-9);  // hemisphere
      }
    }
}

TEST(Designers, SphereDesignsCoverTheSouthToo) {
  const Design d = design_min_cameras(params(25, true));
  EXPECT_TRUE(d.rig.dome.sphere);
  expect_covered(d.rig, 25);
  const Design mv = design_max_volume(params(18, true));
  EXPECT_EQ(mv.rig.cameras.size(), 48u);  // 3 + 9 + 12 mirrored
}

TEST(Designers, MoreCamerasForCloserDistances) {
  for (Method m : {Method::kLayered, Method::kMinCameras, Method::kCvt})
    EXPECT_GT(cameras_needed(m, params(10)), cameras_needed(m, params(30))) << to_string(m);
}

TEST(Designers, RejectBadParameters) {
  EXPECT_THROW(parse_method("voronoi"), std::invalid_argument);
  EXPECT_EQ(parse_method("min-cameras"), Method::kMinCameras);
  EXPECT_THROW(parse_camera_size("1x1"), std::invalid_argument);
  EXPECT_THROW(parse_camera_size("1x-1x2"), std::invalid_argument);
  EXPECT_THROW(parse_camera_size("1x1x2mm"), std::invalid_argument);
  const CameraSize c = parse_camera_size("1x1x1.85");
  EXPECT_DOUBLE_EQ(c.length_mm, 1.85);
  EXPECT_THROW(design_min_cameras(params(4)), std::invalid_argument);  // inside the dome
  EXPECT_THROW(design_cvt(params(5.01)), std::invalid_argument);       // cones barely meet there
  DesignParams bad = params(18);
  bad.aov_rad = deg2rad(190);
  EXPECT_THROW(design_layered(bad), std::invalid_argument);
  bad = params(18);
  bad.cam = CameraSize{1, 1, 6};  // longer than the radius
  EXPECT_THROW(design_max_volume(bad), std::invalid_argument);
}

}  // namespace
}  // namespace omma::design
