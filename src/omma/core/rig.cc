#include "omma/core/rig.h"

#include <cmath>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "omma/core/io.h"

namespace omma {
namespace {

using nlohmann::json;

std::string cam_name(const json& jc, size_t index) {
  if (jc.is_object() && jc.contains("id") && jc["id"].is_number_integer())
    return fmt::format("camera {} (entry {})", jc["id"].get<int>(), index);
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

}  // namespace

void validate_camera(const RigCamera& c) {
  const std::string where = fmt::format("camera {}", c.id);
  auto finite3 = [](const Vec3& v) { return v.allFinite(); };
  if (!finite3(c.frame.t) || !finite3(c.frame.u) || !finite3(c.frame.v) || !finite3(c.position_mm))
    throw RigError(where + ": frame or position is not finite (NaN or infinity)");
  const FrameError e = frame_error(c.frame);
  constexpr double tol = 1e-3;
  if (e.max_norm_error > tol)
    throw RigError(fmt::format("{}: t, u, v must be unit vectors (length off by {:.3g})", where,
                               e.max_norm_error));
  if (e.max_dot > tol)
    throw RigError(fmt::format("{}: t, u, v must be orthogonal (largest dot product {:.3g})", where,
                               e.max_dot));
  if (e.handedness_error > 10 * tol)
    throw RigError(where + ": frame must be right-handed (u x v = t)");
  const Intrinsics& in = c.in;
  if (in.width <= 0 || in.height <= 0)
    throw RigError(fmt::format("{}: image size {}x{} must be positive", where, in.width, in.height));
  if (!std::isfinite(in.fu) || !std::isfinite(in.fv) || in.fu <= 0 || in.fv <= 0)
    throw RigError(fmt::format("{}: focal length (fu={}, fv={}) must be positive", where, in.fu, in.fv));
  if (!std::isfinite(in.cu) || !std::isfinite(in.cv))
    throw RigError(where + ": principal point is not finite");
  for (double k : in.k)
    if (!std::isfinite(k)) throw RigError(where + ": distortion coefficient is not finite");
  if (!std::isfinite(in.aov) || in.aov <= 0 || in.aov >= kPi)
    throw RigError(fmt::format("{}: angle of view {} deg must be in (0, 180)", where, rad2deg(in.aov)));
}

void Rig::validate() const {
  if (cameras.empty()) throw RigError("rig has no cameras");
  if (!std::isfinite(dome.radius_mm) || dome.radius_mm < 0)
    throw RigError("dome radius_mm must be a non-negative number");
  for (size_t i = 0; i < cameras.size(); ++i) {
    validate_camera(cameras[i]);
    for (size_t j = 0; j < i; ++j)
      if (cameras[j].id == cameras[i].id)
        throw RigError(fmt::format("camera id {} appears twice", cameras[i].id));
  }
}

json rig_to_json(const Rig& rig) {
  json j;
  j["format"] = "omma-rig";
  j["version"] = 1;
  j["name"] = rig.name;
  j["dome"] = {{"radius_mm", rig.dome.radius_mm}, {"sphere", rig.dome.sphere},
               {"method", rig.dome.method}};
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
    jc["intrinsics"] = {{"width", c.in.width}, {"height", c.in.height}, {"fu", c.in.fu},
                        {"fv", c.in.fv},       {"cu", c.in.cu},         {"cv", c.in.cv},
                        {"k", c.in.k},         {"aov_deg", rad2deg(c.in.aov)}};
    if (c.in.field != Intrinsics::Field::kCone) jc["intrinsics"]["field"] = to_string(c.in.field);
    cams.push_back(std::move(jc));
  }
  j["cameras"] = std::move(cams);
  return j;
}

Rig rig_from_json(const json& j) {
  if (!j.is_object()) throw RigError("rig file must hold a JSON object");
  if (j.contains("format") && j["format"] != "omma-rig")
    throw RigError("not an omma rig file (format is not 'omma-rig')");
  Rig rig;
  if (j.contains("name") && j["name"].is_string()) rig.name = j["name"].get<std::string>();
  const json& dome = field(j, "dome", "rig");
  rig.dome.radius_mm = number(dome, "radius_mm", "dome");
  if (dome.contains("sphere")) {
    if (!dome["sphere"].is_boolean()) throw RigError("dome: field 'sphere' must be true or false");
    rig.dome.sphere = dome["sphere"].get<bool>();
  }
  if (dome.contains("method") && dome["method"].is_string())
    rig.dome.method = dome["method"].get<std::string>();
  const json& cams = field(j, "cameras", "rig");
  if (!cams.is_array()) throw RigError("rig: field 'cameras' must be an array");
  for (size_t i = 0; i < cams.size(); ++i) {
    const json& jc = cams[i];
    const std::string where = cam_name(jc, i);
    RigCamera c;
    const json& id = field(jc, "id", where);
    if (!id.is_number_integer()) throw RigError(where + ": field 'id' must be an integer");
    c.id = id.get<int>();
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
    auto integer = [&](const char* key) {
      const json& v = field(in, key, wi);
      if (!v.is_number_integer()) throw RigError(wi + ": field '" + key + "' must be an integer");
      return v.get<int>();
    };
    c.in.width = integer("width");
    c.in.height = integer("height");
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
        if (!k[n].is_number()) throw RigError(wi + ": 'k' must hold numbers");
        c.in.k[n] = k[n].get<double>();
      }
    }
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
  if (!std::filesystem::exists(path)) throw RigError("rig file '" + path.string() + "' does not exist");
  json j;
  try {
    j = json::parse(read_text_file(path));
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
