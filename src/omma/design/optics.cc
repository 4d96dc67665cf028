#include "omma/design/optics.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "omma/core/conventions.h"

namespace omma::design {
namespace {
// Every input in [1e-6, 1e6] of its unit: the products and quotients below stay finite.
void positive(double v, const char* name) {
  if (!(v >= 1e-6 && v <= 1e6))
    throw std::invalid_argument(std::string("optics: ") + name +
                                " must be a number in [1e-6, 1e6] of its unit");
}
}  // namespace

OpticsResult compute_optics(const OpticsInputs& in) {
  positive(in.wavelength_nm, "wavelength");
  positive(in.focal_length_um, "focal length");
  positive(in.aperture_um, "aperture");
  positive(in.pixel_pitch_um, "pixel pitch");
  positive(in.source_flux_lm, "source flux");
  positive(in.source_diameter_mm, "source diameter");
  positive(in.channel_small_diameter_mm, "small channel diameter");
  positive(in.channel_large_diameter_mm, "large channel diameter");
  positive(in.target_area_mm2, "target area");
  positive(in.distance_mm, "distance");
  positive(in.acuity_deg, "acuity");
  positive(in.ideal_wavelength_nm, "ideal wavelength");
  positive(in.implemented_radius_mm, "implemented radius");
  if (in.channels_small < 0 || in.channels_large < 0 || in.channels_small > 1000000 ||
      in.channels_large > 1000000 || in.channels_small + in.channels_large == 0)
    throw std::invalid_argument("optics: the channel counts must be 0..10^6 and not both 0");
  OpticsResult r;
  // §3.2: x_i = 1.22 lambda f / d (lambda in um), theta_0 = x_i / f.
  r.rayleigh_spot_um = 1.22 * (in.wavelength_nm * 1e-3) * in.focal_length_um / in.aperture_um;
  r.delta_phi_optics_deg = rad2deg(r.rayleigh_spot_um / in.focal_length_um);
  r.delta_phi_pixel_deg = rad2deg(in.pixel_pitch_um / in.focal_length_um);
  r.delta_phi_deg = std::max(r.delta_phi_optics_deg, r.delta_phi_pixel_deg);
  r.pixel_supports_optics = in.pixel_pitch_um <= r.rayleigh_spot_um;
  // §3.5, eq. 3.12.
  auto disc = [](double d) { return kPi * d * d / 4; };
  r.source_area_mm2 = disc(in.source_diameter_mm);
  r.channel_area_mm2 = in.channels_small * disc(in.channel_small_diameter_mm) +
                       in.channels_large * disc(in.channel_large_diameter_mm);
  r.delivered_flux_lm = r.channel_area_mm2 / r.source_area_mm2 * in.source_flux_lm;
  r.illumination_lm = r.delivered_flux_lm * in.target_area_mm2 / (in.distance_mm * in.distance_mm);
  // eq. 5.28: R = lambda / (2 dphi^2); eq. 5.29 as evaluated in §5.5.2 (3.3 mm / 18 mm = 18 %).
  const double dphi = deg2rad(in.acuity_deg);
  r.r_ideal_mm = (in.ideal_wavelength_nm * 1e-6) / (2 * dphi * dphi);
  r.size_efficiency = r.r_ideal_mm / in.implemented_radius_mm;
  return r;
}

}  // namespace omma::design
