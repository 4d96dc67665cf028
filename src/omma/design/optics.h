// Optics calculator (thesis §3.2, §3.5 eq. 3.12, §5.5.2 eq. 5.28-5.29). Inputs in the units named;
// every default is the thesis's value.
#pragma once

namespace omma::design {

struct OpticsInputs {
  // §3.2, Table 3.1: pinhole camera.
  double wavelength_nm = 420;    // shortest visible wavelength lambda_min
  double focal_length_um = 660;  // f_pinhole
  double aperture_um = 110;      // d_pinhole
  double pixel_pitch_um = 3;     // sensor pitch (250 x 250 array)
  // §3.5, eq. 3.12: illumination through fibre channels.
  double source_flux_lm = 700;       // LED source luminous flux
  double source_diameter_mm = 13.5;  // diameter over which the source delivers it
  int channels_small = 108;          // fibre channels of the small diameter
  double channel_small_diameter_mm = 0.25;
  int channels_large = 4;  // channels at the top
  double channel_large_diameter_mm = 0.5;
  double target_area_mm2 = 1250;  // A_r as the thesis uses it (it writes 2 pi 625 mm^2 = 1250)
  double distance_mm = 20;        // d, from the imaging surface to the target
  // §5.5.2, eq. 5.28-5.29: size efficiency.
  double acuity_deg = 0.5;            // measured inter-ommatidial angle (USAF 1951)
  double ideal_wavelength_nm = 500;   // lambda in eq. 5.28 (gives the thesis's 3.3 mm)
  double implemented_radius_mm = 18;  // R_imp: the radius the system needs (its R_vir, 18 mm)
};

struct OpticsResult {
  // §3.2 Rayleigh criterion: x_i = 1.22 lambda f / d, theta_0 = x_i / f.
  double rayleigh_spot_um = 0;
  double delta_phi_optics_deg = 0;     // theta_0 = x_i / f (diffraction)
  double delta_phi_pixel_deg = 0;      // pixel pitch / f (sampling)
  double delta_phi_deg = 0;            // the coarser of the two: the camera's resolving angle
  bool pixel_supports_optics = false;  // pitch <= Rayleigh spot
  // eq. 3.12: F = L Ae Ar / d^2 with L Ae = (Ac / Ae) * source flux.
  double source_area_mm2 = 0;    // Ae
  double channel_area_mm2 = 0;   // Ac
  double delivered_flux_lm = 0;  // L x Ae
  double illumination_lm = 0;    // F
  // eq. 5.28-5.29.
  double r_ideal_mm = 0;       // lambda / (2 dphi^2)
  double size_efficiency = 0;  // zeta = R_ideal / R_imp as the thesis evaluates it (18 %)
};

// Throws std::invalid_argument unless every input lies in [1e-6, 1e6] of its unit (channel counts
// 0..10^6, not both 0), so that every result is finite.
OpticsResult compute_optics(const OpticsInputs& in);

}  // namespace omma::design
