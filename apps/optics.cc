// omma optics: resolving angle, illumination and size efficiency (thesis §3.2, eq. 3.12, 5.28-5.29).
#include "omma/design/optics.h"

#include <iostream>
#include <memory>

#include <fmt/format.h>

#include "apps/command.h"

namespace omma::app {

void add_optics_command(CLI::App& root) {
  struct Opts {
    design::OpticsInputs in;
    bool json = false;
  };
  auto o = std::make_shared<Opts>();
  auto* cmd = root.add_subcommand(
      "optics",
      "Optics calculator with the thesis's values as defaults: Rayleigh limit and resolving angle\n"
      "of the Table 3.1 camera (§3.2), illumination of the fibre channels (eq. 3.12), the ideal\n"
      "compound-eye radius (eq. 5.28) and the size efficiency (eq. 5.29, as evaluated in §5.5.2).");
  auto& in = o->in;
  cmd->add_option("--wavelength", in.wavelength_nm, "Shortest wavelength for the Rayleigh limit, nm")
      ->capture_default_str();
  cmd->add_option("--focal", in.focal_length_um, "Pinhole focal length, um")->capture_default_str();
  cmd->add_option("--aperture", in.aperture_um, "Pinhole aperture diameter, um")->capture_default_str();
  cmd->add_option("--pixel-pitch", in.pixel_pitch_um, "Sensor pixel pitch, um")->capture_default_str();
  cmd->add_option("--source-flux", in.source_flux_lm, "LED source luminous flux, lm")->capture_default_str();
  cmd->add_option("--source-diameter", in.source_diameter_mm, "LED source output diameter, mm")
      ->capture_default_str();
  cmd->add_option("--channels", in.channels_small, "Number of small fibre channels")->capture_default_str();
  cmd->add_option("--channel-diameter", in.channel_small_diameter_mm, "Small channel diameter, mm")
      ->capture_default_str();
  cmd->add_option("--top-channels", in.channels_large, "Number of large (top) fibre channels")
      ->capture_default_str();
  cmd->add_option("--top-channel-diameter", in.channel_large_diameter_mm, "Large channel diameter, mm")
      ->capture_default_str();
  cmd->add_option("--target-area", in.target_area_mm2,
                  "Illuminated area A_r, mm^2 (the thesis uses 1250; a 25 mm hemisphere is 3927)")
      ->capture_default_str();
  cmd->add_option("--distance", in.distance_mm, "Distance d to the illuminated surface, mm")
      ->capture_default_str();
  cmd->add_option("--acuity", in.acuity_deg, "Measured inter-ommatidial angle dphi, degrees")
      ->capture_default_str();
  cmd->add_option("--ideal-wavelength", in.ideal_wavelength_nm, "Wavelength of eq. 5.28, nm")
      ->capture_default_str();
  cmd->add_option("--r-implemented", in.implemented_radius_mm,
                  "Radius the system needs, R_imp of eq. 5.29 (its R_vir), mm")
      ->capture_default_str();
  cmd->add_flag("--json", o->json, "Print one JSON object on stdout");
  cmd->callback([o] {
    set_json_mode(o->json);
    const design::OpticsResult r = design::compute_optics(o->in);
    if (o->json) {
      print_json({{"rayleigh_spot_um", r.rayleigh_spot_um},
                  {"delta_phi_optics_deg", r.delta_phi_optics_deg},
                  {"delta_phi_pixel_deg", r.delta_phi_pixel_deg},
                  {"delta_phi_deg", r.delta_phi_deg},
                  {"pixel_supports_optics", r.pixel_supports_optics},
                  {"source_area_mm2", r.source_area_mm2},
                  {"channel_area_mm2", r.channel_area_mm2},
                  {"delivered_flux_lm", r.delivered_flux_lm},
                  {"illumination_lm", r.illumination_lm},
                  {"r_ideal_mm", r.r_ideal_mm},
                  {"size_efficiency", r.size_efficiency}});
    } else {
      std::cout << fmt::format(
          "Rayleigh spot x_i = {:.2f} um, dphi = {:.3f} deg (optics) / {:.3f} deg (pixel pitch)\n"
          "Illumination (eq. 3.12): Ae = {:.1f} mm^2, Ac = {:.2f} mm^2, L x Ae = {:.1f} lm, "
          "F = {:.1f} lm\n"
          "Ideal radius (eq. 5.28) = {:.2f} mm, size efficiency (eq. 5.29) = {:.1f} %\n",
          r.rayleigh_spot_um, r.delta_phi_optics_deg, r.delta_phi_pixel_deg, r.source_area_mm2,
          r.channel_area_mm2, r.delivered_flux_lm, r.illumination_lm, r.r_ideal_mm, 100 * r.size_efficiency);
    }
  });
}

}  // namespace omma::app
