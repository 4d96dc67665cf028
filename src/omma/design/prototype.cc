#include "omma/design/prototype.h"

#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "omma/design/coverage.h"
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
      axes.push_back(
          direction_from_spherical(l.polar_rad[i], deg2rad(kPrototypeLayerOffsetsDeg[i]) + 2 * kPi * k / n));
  }
  return radial_rig(axes, 5.0, ideal_intrinsics(deg2rad(64)), false, "max-volume", "thesis-24");
}

}  // namespace omma::design

// ---------------------------------------------------------------------------------------------
// Giga-Eye (thesis ch. 7).

namespace omma::design {
namespace {

constexpr int kGigaLayerCount[4] = {1, 6, 15, 22};               // top to bottom, thesis L6429-6433
constexpr double kGigaLayerPolarDeg[4] = {0, 39.6, 59.3, 80.8};  // thesis L6435-6437
constexpr double kGigaRadiusMm = 200;                            // thesis L6574
constexpr int kGigaWidth = 2592, kGigaHeight = 1944;             // 5 MP (L6427 "1926" is a typo)
constexpr double kGigaAovHDeg = 53, kGigaAovVDeg = 43;           // thesis L6425, Table 7.1

// The layout chosen by coverage: search_gigaeye_layout(1000 mm, 1 deg) (prototype_test checks that
// no single step of the search improves it). Portrait ring cameras (53 deg along the meridian, 43
// along the azimuth) see 6.21 sr by two or more cameras at 1 m, landscape ones at best 5.6 sr.
constexpr GigaEyeLayout kGigaEyeLayout = {{0, 6, 0, 0}, 5, true};

}  // namespace

GigaEyeLayout gigaeye_layout() { return kGigaEyeLayout; }

Rig gigaeye_rig(const GigaEyeLayout& layout) {
  Intrinsics in;
  in.width = kGigaWidth;
  in.height = kGigaHeight;
  in.fu = 0.5 * kGigaWidth / std::tan(deg2rad(kGigaAovHDeg) / 2);
  in.fv = 0.5 * kGigaHeight / std::tan(deg2rad(kGigaAovVDeg) / 2);
  in.cu = kGigaWidth / 2.0;
  in.cv = kGigaHeight / 2.0;
  in.field = Intrinsics::Field::kImage;
  in.aov = in.bounding_aov();
  Rig rig;
  rig.name = "gigaeye-44";
  rig.dome.radius_mm = kGigaRadiusMm;
  rig.dome.sphere = true;  // the field of view reaches below the horizon (polar ~102 deg)
  rig.dome.method = "gigaeye";
  int id = 0;
  for (int l = 0; l < 4; ++l)
    for (int k = 0; k < kGigaLayerCount[l]; ++k) {
      const double phi = deg2rad(layout.offset_deg[l]) + 2 * kPi * k / kGigaLayerCount[l];
      const Vec3 t = direction_from_spherical(deg2rad(kGigaLayerPolarDeg[l]), phi);
      RigCamera cam;
      if (l == 0) {
        // Looking up; image "down" along the azimuth zenith_roll_deg + 180 (rows), u = v x t.
        const double r = deg2rad(layout.zenith_roll_deg);
        cam = radial_camera(id, t, kGigaRadiusMm, in);
        cam.frame.v = Vec3(-std::cos(r), -std::sin(r), 0);
        cam.frame.u = cam.frame.v.cross(cam.frame.t);
      } else {
        cam = radial_camera(id, t, kGigaRadiusMm, in);
        if (layout.portrait) {  // roll by 90 deg about t: u = old v, v = -old u
          const Vec3 u = cam.frame.v, v = -cam.frame.u;
          cam.frame.u = u;
          cam.frame.v = v;
        }
      }
      rig.cameras.push_back(cam);
      ++id;
    }
  rig.validate();
  return rig;
}

double gigaeye_layout_score(const GigaEyeLayout& layout, double distance_mm, double step_rad) {
  const Rig rig = gigaeye_rig(layout);
  const CoverageSummary st = analyze_coverage(rig, distance_mm, step_rad, deg2rad(100));
  return st.solid_angle_at_least(2) + 1e-3 * st.solid_angle_at_least(1);
}

GigaEyeLayout search_gigaeye_layout(double distance_mm, double step_rad) {
  GigaEyeLayout best;
  double best_score = -1;
  for (bool portrait : {false, true}) {
    GigaEyeLayout cur;
    cur.portrait = portrait;
    double cur_score = gigaeye_layout_score(cur, distance_mm, step_rad);
    // Coordinate search: layer offsets 1, 2 (layer 3 is the reference at 0), then the zenith roll,
    // until no coordinate improves.
    for (bool improved = true; improved;) {
      improved = false;
      for (int c = 0; c < 3; ++c) {
        const double period = c < 2 ? 360.0 / kGigaLayerCount[c + 1] : 180.0;
        const double step = c < 2 ? 1.0 : 5.0;
        for (double x = 0; x < period - 1e-9; x += step) {
          GigaEyeLayout t = cur;
          (c < 2 ? t.offset_deg[c + 1] : t.zenith_roll_deg) = x;
          const double s = gigaeye_layout_score(t, distance_mm, step_rad);
          if (s > cur_score + 1e-12) {
            cur = t;
            cur_score = s;
            improved = true;
          }
        }
      }
    }
    if (cur_score > best_score) {
      best = cur;
      best_score = cur_score;
    }
  }
  return best;
}

std::string SensorMode::name() const {
  if (window_width > 0) return fmt::format("window{}x{}", window_width, window_height);
  if (skip == 0) return "full";
  return fmt::format("skip{}{}", skip, bin ? "-bin" : "");
}

Rig derive_sensor_mode(const Rig& full, const SensorMode& mode) {
  if (mode.skip < 0 || mode.skip > 7)
    throw std::invalid_argument(fmt::format("skip {} must be 0..7", mode.skip));
  if (mode.bin && mode.skip == 0) throw std::invalid_argument("binning needs skipping (skip >= 1)");
  const bool window = mode.window_width > 0 || mode.window_height > 0;
  if (window && mode.skip != 0) throw std::invalid_argument("a sub-window is read without skipping");
  Rig rig = full;
  for (RigCamera& cam : rig.cameras) {
    Intrinsics& in = cam.in;
    if (window) {
      if (mode.window_width <= 0 || mode.window_height <= 0 || mode.window_width > in.width ||
          mode.window_height > in.height)
        throw std::invalid_argument(fmt::format("sub-window {}x{} must fit the {}x{} sensor",
                                                mode.window_width, mode.window_height, in.width, in.height));
      // A centred window of even offset (the Bayer phase is kept): same focal length.
      const int x0 = (in.width - mode.window_width) / 2 & ~1, y0 = (in.height - mode.window_height) / 2 & ~1;
      in.cu -= x0;
      in.cv -= y0;
      in.width = mode.window_width;
      in.height = mode.window_height;
    } else if (mode.skip > 0) {
      // Sub-sampling by n = skip + 1: output pixel i covers input pixels [n i, n i + n), so the
      // continuous coordinates scale by 1/n (binning; pure skipping samples the first of them, a
      // shift of at most half an input pixel, 0.01 deg here).
      const int n = mode.skip + 1;
      if (in.width % n || in.height % n || (in.width / n) % 2 || (in.height / n) % 2)
        throw std::invalid_argument(fmt::format(
            "{}x{} sub-sampled by {} is not an even size (RGGB Bayer cells)", in.width, in.height, n));
      in.width /= n;
      in.height /= n;
      in.fu /= n;
      in.fv /= n;
      in.cu /= n;
      in.cv /= n;
    }
    if (in.field == Intrinsics::Field::kImage) in.aov = in.bounding_aov();
  }
  if (mode.skip > 0 || window) rig.name = full.name + "-" + mode.name();
  rig.validate();
  return rig;
}

std::optional<Rig> builtin_rig(const std::string& name) {
  if (name == "thesis-24") return thesis_prototype_rig();
  if (name == "gigaeye-44") return gigaeye_rig();
  if (name == "gigaeye-44-window") {
    Rig r = derive_sensor_mode(gigaeye_rig(), SensorMode{0, false, 1024, 768});
    r.name = name;
    return r;
  }
  const std::string prefix = "gigaeye-44-skip";
  if (name.size() == prefix.size() + 1 && name.compare(0, prefix.size(), prefix) == 0 && name.back() >= '1' &&
      name.back() <= '5')
    return derive_sensor_mode(gigaeye_rig(), SensorMode{name.back() - '0', false});
  return std::nullopt;
}

std::vector<std::string> builtin_rig_names() {
  return {"thesis-24",        "gigaeye-44",       "gigaeye-44-skip1", "gigaeye-44-skip2",
          "gigaeye-44-skip3", "gigaeye-44-skip5", "gigaeye-44-window"};
}

Rig load_rig_or_builtin(const std::string& spec) {
  // A path (a folder separator or a .json name) is a file: its own error if it cannot be read.
  const bool path_like =
      spec.find('/') != std::string::npos || std::filesystem::path(spec).extension() == ".json";
  if (path_like || std::filesystem::exists(spec)) return load_rig(spec);
  if (auto r = builtin_rig(spec)) return *r;
  throw RigError(fmt::format("'{}' is neither a rig file nor a built-in rig ({})", spec,
                             fmt::join(builtin_rig_names(), ", ")));
}

}  // namespace omma::design
