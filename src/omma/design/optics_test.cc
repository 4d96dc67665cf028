// Optics calculator: the thesis's numbers (§3.2, eq. 3.12, eq. 5.28-5.29).
#include "omma/design/optics.h"

#include <stdexcept>

#include <gtest/gtest.h>

namespace omma::design {
namespace {

TEST(Optics, ThesisNumbers) {
  const OpticsResult r = compute_optics(OpticsInputs{});
  EXPECT_NEAR(r.rayleigh_spot_um, 3.0, 0.1);         // x_i ~ 3 um (§3.2)
  EXPECT_NEAR(r.delta_phi_deg, 0.26, 0.01);          // dphi ~ 0.26 deg
  EXPECT_NEAR(r.delta_phi_pixel_deg, 0.2604, 1e-3);  // 3 um / 660 um
  EXPECT_TRUE(r.pixel_supports_optics);
  EXPECT_NEAR(r.source_area_mm2, 143.1, 0.1);   // Ae
  EXPECT_NEAR(r.channel_area_mm2, 6.1, 0.05);   // Ac
  EXPECT_NEAR(r.delivered_flux_lm, 29.8, 0.1);  // Ac / Ae x 700 lm
  EXPECT_NEAR(r.illumination_lm, 93.2, 0.3);    // eq. 3.12: 93.2 lm (93.0 unrounded)
  EXPECT_NEAR(r.r_ideal_mm, 3.3, 0.05);         // eq. 5.28 at dphi = 0.5 deg
  EXPECT_NEAR(r.size_efficiency, 0.18, 0.005);  // eq. 5.29: 18 %
}

TEST(Optics, ScalesAsTheEquations) {
  OpticsInputs in;
  in.distance_mm = 40;  // eq. 3.12: 1 / d^2
  EXPECT_NEAR(compute_optics(in).illumination_lm, compute_optics(OpticsInputs{}).illumination_lm / 4, 1e-9);
  in = OpticsInputs{};
  in.acuity_deg = 0.25;  // eq. 5.28: 1 / dphi^2
  EXPECT_NEAR(compute_optics(in).r_ideal_mm, 4 * compute_optics(OpticsInputs{}).r_ideal_mm, 1e-9);
}

TEST(Optics, RejectsBadInputs) {
  OpticsInputs in;
  in.aperture_um = 0;
  EXPECT_THROW(compute_optics(in), std::invalid_argument);
  in = OpticsInputs{};
  in.distance_mm = -1;
  EXPECT_THROW(compute_optics(in), std::invalid_argument);
  in = OpticsInputs{};
  in.channels_small = in.channels_large = 0;
  EXPECT_THROW(compute_optics(in), std::invalid_argument);
}

}  // namespace
}  // namespace omma::design
