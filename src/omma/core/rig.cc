#include "omma/core/rig.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_set>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "omma/core/io.h"
#include "omma/core/limits.h"
#include "omma/core/parse.h"

namespace omma {
namespace {

using nlohmann::json;

constexpr int kRigFormatVersion = 1;  // "version" of the rig files this omma reads and writes

std::string cam_name(const json& jc, size_t index) {
  if (jc.is_object() && jc.contains("id") && jc["id"].is_number_integer())
    return fmt::format("camera {} (entry {})", jc["id"].dump(), index);
  return fmt::format("camera entry {}", index);
}

const json& field(const json& obj, const std::string& key, const std::string& where) {
  if (!obj.is_object()) throw RigError(where + ": expected a JSON object");
  auto it = obj.find(key);
  if (it == obj.end()) throw RigError(where + ": missing field '" + key + "'");
  return *it;
}

double number(const json& obj, const std::string& key, const std::string& where) {
  const json& v = field(obj, key, where);
  if (!v.is_number()) throw RigError(where + ": field '" + key + "' must be a number");
  const double d = v.get<double>();
  if (!std::isfinite(d)) throw RigError(where + ": field '" + key + "' is not finite");
  return d;
}

// The one reader of JSON integers: any integer the file holds (also beyond 64 bits, which nlohmann
// stores as a double and is_number_integer() refuses) is compared with [lo, hi] before narrowing.
int64_t integer(const json& obj, const std::string& key, const std::string& where, int64_t lo, int64_t hi) {
  const json& v = field(obj, key, where);
  if (!v.is_number_integer()) throw RigError(where + ": field '" + key + "' must be an integer");
  const std::optional<int64_t> i = json_integer(v, lo, hi);  // core/parse.h
  if (!i)
    throw RigError(fmt::format("{}: field '{}' = {} is out of range ({}..{})", where, key, v.dump(), lo, hi));
  return *i;
}

// An optional string field: absent gives `def`, any other type is an error.
std::string text(const json& obj, const std::string& key, const std::string& where,
                 const std::string& def = "") {
  if (!obj.contains(key)) return def;
  const json& v = obj[key];
  if (!v.is_string()) throw RigError(where + ": field '" + key + "' must be a string");
  return v.get<std::string>();
}

Vec3 vec3(const json& obj, const std::string& key, const std::string& where) {
  const json& v = field(obj, key, where);
  if (!v.is_array() || v.size() != 3)
    throw RigError(where + ": field '" + key + "' must be an array of 3 numbers");
  Vec3 r;
  for (int i = 0; i < 3; ++i) {
    if (!v[i].is_number()) throw RigError(where + ": field '" + key + "' must hold numbers");
    r[i] = v[i].get<double>();
    if (!std::isfinite(r[i])) throw RigError(where + ": field '" + key + "' is not finite");
  }
  return r;
}

json to_array(const Vec3& v) { return json::array({v.x(), v.y(), v.z()}); }

// A JSON array of exactly n finite numbers.
template <size_t N>
std::array<double, N> numbers(const json& obj, const std::string& key, const std::string& where) {
  const json& v = field(obj, key, where);
  if (!v.is_array() || v.size() != N)
    throw RigError(fmt::format("{}: field '{}' must be an array of {} numbers", where, key, N));
  std::array<double, N> r{};
  for (size_t i = 0; i < N; ++i) {
    if (!v[i].is_number()) throw RigError(where + ": field '" + key + "' must hold numbers");
    r[i] = v[i].get<double>();
    if (!std::isfinite(r[i])) throw RigError(where + ": field '" + key + "' is not finite");
  }
  return r;
}

// The optional "photometric" object of a camera (photometric.h); every field optional, defaults
// = no vignetting, centred, unit gains. Unknown fields are an error (a typo would silently do nothing).
Photometric photometric_from_json(const json& j, const std::string& where) {
  if (!j.is_object()) throw RigError(where + ": expected a JSON object");
  for (auto it = j.begin(); it != j.end(); ++it)
    if (it.key() != "vignetting" && it.key() != "vignetting_center_px" && it.key() != "gains_bgr")
      throw RigError(where + ": unknown field '" + it.key() +
                     "' (use vignetting, vignetting_center_px, gains_bgr)");
  Photometric p;
  if (j.contains("vignetting")) p.vignetting = numbers<3>(j, "vignetting", where);
  if (j.contains("vignetting_center_px")) {
    const auto c = numbers<2>(j, "vignetting_center_px", where);
    p.center_px = Vec2(c[0], c[1]);
  }
  if (j.contains("gains_bgr")) p.gains = numbers<3>(j, "gains_bgr", where);
  return p;
}

}  // namespace

void validate_camera(const RigCamera& c) {
  const std::string where = fmt::format("camera {}", c.id);
  auto finite3 = [](const Vec3& v) { return v.allFinite(); };
  if (!finite3(c.frame.t) || !finite3(c.frame.u) || !finite3(c.frame.v) || !finite3(c.position_mm))
    throw RigError(where + ": frame or position is not finite (NaN or infinity)");
  const FrameError e = frame_error(c.frame);
  constexpr double tol = 1e-3;
  if (e.max_norm_error > tol)
    throw RigError(
        fmt::format("{}: t, u, v must be unit vectors (length off by {:.3g})", where, e.max_norm_error));
  if (e.max_dot > tol)
    throw RigError(
        fmt::format("{}: t, u, v must be orthogonal (largest dot product {:.3g})", where, e.max_dot));
  if (e.handedness_error > 10 * tol) throw RigError(where + ": frame must be right-handed (u x v = t)");
  if (c.position_mm.cwiseAbs().maxCoeff() > kMaxPositionMm)
    throw RigError(
        fmt::format("{}: position_mm is more than {} mm from the dome centre", where, kMaxPositionMm));
  const Intrinsics& in = c.in;
  try {
    check_image_size(in.width, in.height, "image size");
  } catch (const std::invalid_argument& e) {
    throw RigError(where + ": " + e.what());
  }
  // Focal lengths and principal point relative to the image size (core/limits.h): positive, finite
  // and far from denormals (a focal length of 1e-320 px made 1/f infinite).
  const double side = std::max(in.width, in.height);
  for (const double f : {in.fu, in.fv})
    if (!(f >= kMinFocalRel * side && f <= kMaxFocalRel * side))
      throw RigError(
          fmt::format("{}: focal length (fu={}, fv={}) must be positive, between {} and {} x the larger "
                      "image side ({} px)",
                      where, in.fu, in.fv, kMinFocalRel, kMaxFocalRel, side));
  if (!(std::abs(in.cu) <= kMaxCentreRel * side && std::abs(in.cv) <= kMaxCentreRel * side))
    throw RigError(fmt::format("{}: principal point ({}, {}) is not finite or more than {} image sides away",
                               where, in.cu, in.cv, kMaxCentreRel));
  for (double k : in.k)
    if (!(std::abs(k) <= kMaxDistortion))
      throw RigError(fmt::format("{}: distortion coefficient {} is not finite or larger than {} in magnitude",
                                 where, k, kMaxDistortion));
  if (!std::isfinite(in.aov) || in.aov <= 0 || in.aov >= kPi)
    throw RigError(fmt::format("{}: angle of view {} deg must be in (0, 180)", where, rad2deg(in.aov)));
  if (const std::string lens = in.lens_problem(); !lens.empty()) throw RigError(where + ": " + lens);
  if (c.photometric) {
    try {
      validate_photometric(*c.photometric, in.width, in.height, where);
    } catch (const std::invalid_argument& e) {
      throw RigError(e.what());
    }
  }
}

bool has_photometric(const Rig& rig) {
  return std::any_of(rig.cameras.begin(), rig.cameras.end(),
                     [](const RigCamera& c) { return c.photometric.has_value(); });
}

void Rig::validate() const {
  if (cameras.empty()) throw RigError("rig has no cameras");
  if (cameras.size() > size_t(kMaxCameras))
    throw RigError(
        fmt::format("rig has {} cameras; the limit is {} (core/limits.h)", cameras.size(), kMaxCameras));
  if (!(dome.radius_mm >= 0 && dome.radius_mm <= kMaxPositionMm))
    throw RigError(fmt::format("dome radius_mm must be a number in [0, {}]", kMaxPositionMm));
  std::unordered_set<int> ids;
  ids.reserve(cameras.size());
  for (const RigCamera& c : cameras) {
    validate_camera(c);
    if (!ids.insert(c.id).second) throw RigError(fmt::format("camera id {} appears twice", c.id));
  }
}

json rig_to_json(const Rig& rig) {
  json j;
  j["format"] = "omma-rig";
  j["version"] = kRigFormatVersion;
  j["name"] = rig.name;
  j["dome"] = {{"radius_mm", rig.dome.radius_mm}, {"sphere", rig.dome.sphere}, {"method", rig.dome.method}};
  json cams = json::array();
  for (const auto& c : rig.cameras) {
    const YawPitchRoll a = ypr_from_frame(c.frame);
    json jc;
    jc["id"] = c.id;
    jc["t"] = to_array(c.frame.t);
    jc["u"] = to_array(c.frame.u);
    jc["v"] = to_array(c.frame.v);
    jc["ypr_deg"] = json::array({rad2deg(a.yaw), rad2deg(a.pitch), rad2deg(a.roll)});
    jc["position_mm"] = to_array(c.position_mm);
    jc["intrinsics"] = {
        {"width", c.in.width}, {"height", c.in.height}, {"fu", c.in.fu}, {"fv", c.in.fv},
        {"cu", c.in.cu},       {"cv", c.in.cv},         {"k", c.in.k},   {"aov_deg", rad2deg(c.in.aov)}};
    if (c.photometric) {
      const Photometric& p = *c.photometric;
      jc["photometric"] = {{"vignetting", p.vignetting},
                           {"vignetting_center_px", {p.center_px.x(), p.center_px.y()}},
                           {"gains_bgr", p.gains}};
    }
    if (c.in.field != Intrinsics::Field::kCone) jc["intrinsics"]["field"] = to_string(c.in.field);
    cams.push_back(std::move(jc));
  }
  j["cameras"] = std::move(cams);
  return j;
}

Rig rig_from_json(const json& j) {
  if (!j.is_object()) throw RigError("rig file must hold a JSON object");
  if (text(j, "format", "rig", "omma-rig") != "omma-rig")
    throw RigError("not an omma rig file (format is not 'omma-rig')");
  if (j.contains("version") && integer(j, "version", "rig", INT64_MIN, INT64_MAX) != kRigFormatVersion)
    throw RigError(fmt::format("rig file version {} is not supported (this omma reads version {})",
                               j["version"].dump(), kRigFormatVersion));
  Rig rig;
  rig.name = text(j, "name", "rig");
  const json& dome = field(j, "dome", "rig");
  rig.dome.radius_mm = number(dome, "radius_mm", "dome");
  if (dome.contains("sphere")) {
    if (!dome["sphere"].is_boolean()) throw RigError("dome: field 'sphere' must be true or false");
    rig.dome.sphere = dome["sphere"].get<bool>();
  }
  rig.dome.method = text(dome, "method", "dome");
  const json& cams = field(j, "cameras", "rig");
  if (!cams.is_array()) throw RigError("rig: field 'cameras' must be an array");
  if (cams.size() > size_t(kMaxCameras))
    throw RigError(
        fmt::format("rig has {} cameras; the limit is {} (core/limits.h)", cams.size(), kMaxCameras));
  for (size_t i = 0; i < cams.size(); ++i) {
    const json& jc = cams[i];
    const std::string where = cam_name(jc, i);
    RigCamera c;
    c.id = int(integer(jc, "id", where, 0, INT32_MAX));
    if (jc.contains("t") || jc.contains("u") || jc.contains("v")) {
      c.frame.t = vec3(jc, "t", where);
      c.frame.u = vec3(jc, "u", where);
      c.frame.v = vec3(jc, "v", where);
    } else if (jc.contains("ypr_deg")) {
      const Vec3 a = vec3(jc, "ypr_deg", where);
      c.frame = frame_from_ypr({deg2rad(a[0]), deg2rad(a[1]), deg2rad(a[2])});
    } else {
      throw RigError(where + ": missing orientation: give 't', 'u', 'v' or 'ypr_deg'");
    }
    c.position_mm = vec3(jc, "position_mm", where);
    const json& in = field(jc, "intrinsics", where);
    const std::string wi = where + " intrinsics";
    c.in.width = int(integer(in, "width", wi, 1, kMaxImageSide));
    c.in.height = int(integer(in, "height", wi, 1, kMaxImageSide));
    c.in.fu = number(in, "fu", wi);
    c.in.fv = number(in, "fv", wi);
    c.in.cu = number(in, "cu", wi);
    c.in.cv = number(in, "cv", wi);
    if (in.contains("field")) {
      if (!in["field"].is_string()) throw RigError(wi + ": field 'field' must be \"cone\" or \"image\"");
      try {
        c.in.field = parse_field(in["field"].get<std::string>());
      } catch (const std::invalid_argument& e) {
        throw RigError(wi + ": " + e.what());
      }
    }
    // kImage: the image bounds decide and aov is their bounding cone (aov_deg optional, ignored).
    if (c.in.field == Intrinsics::Field::kCone || in.contains("aov_deg"))
      c.in.aov = deg2rad(number(in, "aov_deg", wi));
    if (in.contains("k")) {
      const json& k = in["k"];
      if (!k.is_array() || k.size() > 5) throw RigError(wi + ": 'k' must be an array of up to 5 numbers");
      for (size_t n = 0; n < k.size(); ++n) {
        if (!k[n].is_number() || !std::isfinite(k[n].get<double>()))
          throw RigError(wi + ": 'k' must hold finite numbers");
        c.in.k[n] = k[n].get<double>();
      }
    }
    if (jc.contains("photometric"))
      c.photometric = photometric_from_json(jc["photometric"], where + " photometric");
    if (c.in.field == Intrinsics::Field::kImage && c.in.width > 0 && c.in.height > 0 && c.in.fu > 0 &&
        c.in.fv > 0)
      c.in.aov = c.in.bounding_aov();
    try {
      validate_camera(c);
    } catch (const RigError& e) {
      throw RigError(std::string(e.what()) + " (" + where + ")");
    }
    rig.cameras.push_back(c);
  }
  rig.validate();
  return rig;
}

Rig load_rig(const std::filesystem::path& path) {
  json j;
  try {
    j = json::parse(read_text_file(path, kMaxTextFileBytes, "rig file"));
  } catch (const json::parse_error& e) {
    throw RigError("rig file '" + path.string() + "' is not valid JSON: " + e.what());
  } catch (const IoError& e) {
    throw RigError(e.what());
  }
  try {
    return rig_from_json(j);
  } catch (const RigError& e) {
    throw RigError("rig file '" + path.string() + "': " + e.what());
  } catch (const json::exception& e) {
    throw RigError("rig file '" + path.string() + "': " + e.what());
  }
}

void save_rig(const Rig& rig, const std::filesystem::path& path) {
  rig.validate();
  write_text_atomically(path, rig_to_json(rig).dump(2) + "\n");
}

}  // namespace omma
