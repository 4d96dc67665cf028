#include "omma/sim/perturb.h"

#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "omma/core/parse.h"

namespace omma::sim {

PerturbSpec parse_perturb(const std::string& text) {
  PerturbSpec p;
  if (text.empty()) return p;
  if (text.back() == ',' || text.front() == ',' || text.find(",,") != std::string::npos)
    throw std::invalid_argument(fmt::format("perturb spec '{}' has an empty item", text));
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const auto eq = item.find('=');
    if (eq == std::string::npos)
      throw std::invalid_argument(
          fmt::format("perturb item '{}' must be KEY=VALUE (keys: orient, focal, center, k1, pos)", item));
    const std::string key = item.substr(0, eq), val = item.substr(eq + 1);
    const std::optional<double> parsed = parse_double(val);  // core/parse.h
    if (!parsed)
      throw std::invalid_argument(fmt::format("perturb item '{}': '{}' is not a number", item, val));
    const double v = *parsed;
    if (!std::isfinite(v)) throw std::invalid_argument(fmt::format("perturb item '{}' is not finite", item));
    auto magnitude = [&](double max) {
      if (v < 0 || v > max)
        throw std::invalid_argument(fmt::format("perturb item '{}': {} must be in [0, {}]", item, key, max));
      return v;
    };
    if (key == "orient")
      p.orient_deg = magnitude(45);
    else if (key == "focal")
      p.focal_rel = magnitude(0.5);
    else if (key == "center")
      p.center_px = magnitude(1000);
    else if (key == "pos")
      p.position_mm = magnitude(100);
    else if (key == "k1") {
      if (std::abs(v) > 1)
        throw std::invalid_argument(fmt::format("perturb item '{}': |k1| must be <= 1", item));
      p.k1 = v;
    } else {
      throw std::invalid_argument(
          fmt::format("unknown perturb key '{}' (keys: orient, focal, center, k1, pos)", key));
    }
  }
  return p;
}

std::string to_string(const PerturbSpec& p) {
  return fmt::format("orient={},focal={},center={},k1={},pos={}", p.orient_deg, p.focal_rel, p.center_px,
                     p.k1, p.position_mm);
}

namespace {
Vec3 random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0, 1);
  Vec3 v;
  do v = Vec3(n(rng), n(rng), n(rng));
  while (v.norm() < 1e-6);
  return v.normalized();
}
}  // namespace

Rig perturb_rig(const Rig& nominal, const PerturbSpec& p, uint64_t seed) {
  Rig rig = nominal;
  if (!p.any()) return rig;
  rig.name = nominal.name + " (perturbed: " + to_string(p) + ")";
  for (auto& cam : rig.cameras) {
    std::mt19937_64 rng(seed * 0x9e3779b97f4a7c15ull + 0x70657274ull + static_cast<uint64_t>(cam.id) * 7919);
    std::uniform_real_distribution<double> uni(0, 1);
    // Draw everything in a fixed order so each error's randomness does not depend on the others.
    const Vec3 axis = random_unit(rng);
    const double focal_sign = uni(rng) < 0.5 ? -1 : 1;
    const double center_angle = 2 * kPi * uni(rng);
    const Vec3 pos_dir = random_unit(rng);
    if (p.orient_deg > 0) {
      const Mat3 R = Eigen::AngleAxisd(deg2rad(p.orient_deg), axis).toRotationMatrix();
      cam.frame.t = (R * cam.frame.t).normalized();
      cam.frame.u = (R * cam.frame.u).normalized();
      cam.frame.v = cam.frame.t.cross(cam.frame.u).normalized();
    }
    if (p.focal_rel > 0) {
      cam.in.fu *= 1 + focal_sign * p.focal_rel;
      cam.in.fv *= 1 + focal_sign * p.focal_rel;
    }
    if (p.center_px > 0) {
      cam.in.cu += p.center_px * std::cos(center_angle);
      cam.in.cv += p.center_px * std::sin(center_angle);
    }
    cam.in.k[0] += p.k1;
    if (p.position_mm > 0) cam.position_mm += p.position_mm * pos_dir;
  }
  rig.validate();
  return rig;
}

Rig perturb_rig_rms(const Rig& nominal, const PerturbSpec& p, uint64_t seed) {
  std::mt19937 rng(static_cast<std::mt19937::result_type>(seed));
  std::normal_distribution<double> g(0, 1);
  Rig rig = nominal;
  for (auto& c : rig.cameras) {
    const Vec3 aa = Vec3(g(rng), g(rng), g(rng)) * deg2rad(p.orient_deg) / std::sqrt(3.0);
    const Mat3 r = Eigen::AngleAxisd(aa.norm(), aa.normalized()).toRotationMatrix();
    // Rotate the camera in its own frame: new rows = r * old rows.
    const Mat3 m = r * c.frame.dome_to_camera();
    c.frame.t = m.row(0).transpose();
    c.frame.u = m.row(1).transpose();
    c.frame.v = m.row(2).transpose();
    const double s = 1 + p.focal_rel * g(rng);
    c.in.fu *= s;
    c.in.fv *= s;
    c.in.cu += p.center_px / std::sqrt(2.0) * g(rng);
    c.in.cv += p.center_px / std::sqrt(2.0) * g(rng);
    c.in.k[0] += p.k1 * g(rng);
  }
  return rig;
}

}  // namespace omma::sim
