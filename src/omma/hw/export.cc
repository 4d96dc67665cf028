#include "omma/hw/export.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "omma/core/io.h"

namespace omma::hw {

bool ExportOptions::IsValid(std::string* why) const {
  std::string sub;
  if (!config.IsValid(&sub)) {
    if (why) *why = "hardware configuration: " + sub;
    return false;
  }
  if (grid.width <= 0 || grid.height <= 0) {
    if (why) *why = "panorama size must be positive";
    return false;
  }
  return true;
}

namespace {

struct IntField {
  const char* name;
  int HwConfig::*member;
};
const std::vector<IntField>& int_fields() {
  static const std::vector<IntField> f = {
      {"angle_bits", &HwConfig::angle_bits},
      {"sincos_addr_bits", &HwConfig::sincos_addr_bits},
      {"sincos_word_bits", &HwConfig::sincos_word_bits},
      {"vec_frac_bits", &HwConfig::vec_frac_bits},
      {"pos_frac_bits", &HwConfig::pos_frac_bits},
      {"dist_frac_bits", &HwConfig::dist_frac_bits},
      {"camera_bits", &HwConfig::camera_bits},
      {"max_contributors", &HwConfig::max_contributors},
      {"proj_bits", &HwConfig::proj_bits},
      {"proj_frac_bits", &HwConfig::proj_frac_bits},
      {"k_frac_bits", &HwConfig::k_frac_bits},
      {"focal_frac_bits", &HwConfig::focal_frac_bits},
      {"centre_frac_bits", &HwConfig::centre_frac_bits},
      {"pix_frac_bits", &HwConfig::pix_frac_bits},
      {"frame_addr_bits", &HwConfig::frame_addr_bits},
      {"sample_frac_bits", &HwConfig::sample_frac_bits},
      {"weight_mant_bits", &HwConfig::weight_mant_bits},
      {"recip_bits", &HwConfig::recip_bits},
      {"vig_addr_bits", &HwConfig::vig_addr_bits},
      {"vig_frac_bits", &HwConfig::vig_frac_bits},
      {"boundary_threshold", &HwConfig::boundary_threshold},
  };
  return f;
}
struct BoolField {
  const char* name;
  bool HwConfig::*member;
};
const std::vector<BoolField>& bool_fields() {
  static const std::vector<BoolField> f = {{"bilinear", &HwConfig::bilinear},
                                           {"expand_at_output", &HwConfig::expand_at_output}};
  return f;
}

std::string upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

void write_text(const std::filesystem::path& p, const std::string& text, ExportSummary& s) {
  write_text_atomically(p, text);
  s.files.push_back(p.filename().string());
}

}  // namespace

nlohmann::json config_to_json(const HwConfig& cfg) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& f : int_fields()) j[f.name] = cfg.*(f.member);
  for (const auto& f : bool_fields()) j[f.name] = cfg.*(f.member);
  return j;
}

HwConfig config_from_json(const nlohmann::json& j) {
  if (!j.is_object()) throw std::invalid_argument("hardware configuration must be a JSON object");
  HwConfig cfg;
  for (auto it = j.begin(); it != j.end(); ++it) {
    bool found = false;
    for (const auto& f : int_fields())
      if (it.key() == f.name) {
        if (!it->is_number_integer())
          throw std::invalid_argument(fmt::format("hardware configuration: {} must be an integer", f.name));
        cfg.*(f.member) = it->get<int>();
        found = true;
      }
    for (const auto& f : bool_fields())
      if (it.key() == f.name) {
        if (!it->is_boolean()) throw std::invalid_argument(fmt::format("hardware configuration: {} must be true or false", f.name));
        cfg.*(f.member) = it->get<bool>();
        found = true;
      }
    if (!found) throw std::invalid_argument(fmt::format("hardware configuration: unknown field '{}'", it.key()));
  }
  cfg.Check();
  return cfg;
}

std::string readmemh_text(const std::vector<uint32_t>& words, int digits, const std::string& comment) {
  std::string out = "// " + comment + "\n";
  out.reserve(out.size() + words.size() * (digits + 1));
  for (uint32_t w : words) out += fmt::format("{:0{}X}\n", w, digits);
  return out;
}

std::string coe_text(const std::vector<uint32_t>& words, int digits) {
  std::string out = "memory_initialization_radix=16;\nmemory_initialization_vector=\n";
  for (size_t i = 0; i < words.size(); ++i)
    out += fmt::format("{:0{}X}{}\n", words[i], digits, i + 1 == words.size() ? ";" : ",");
  return out;
}

std::vector<uint32_t> parse_words(const std::string& text, const std::string& name) {
  std::vector<uint32_t> words;
  std::istringstream in(text);
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    const auto c = line.find("//");
    if (c != std::string::npos) line = line.substr(0, c);
    line.erase(std::remove_if(line.begin(), line.end(), [](unsigned char ch) { return std::isspace(ch); }), line.end());
    if (line.empty()) continue;
    if (line.size() > 8 || !std::all_of(line.begin(), line.end(), [](unsigned char ch) { return std::isxdigit(ch); }))
      throw std::invalid_argument(fmt::format("{} line {}: '{}' is not a 32-bit hex word", name, n, line));
    words.push_back(static_cast<uint32_t>(std::stoul(line, nullptr, 16)));
  }
  return words;
}

ExportSummary export_chip(const Rig& rig, const ExportOptions& opt, const std::filesystem::path& dir) {
  std::string why;
  if (!opt.IsValid(&why)) throw std::invalid_argument(why);
  const HwConfig& cfg = opt.config;
  check_rig(cfg, rig);
  check_grid(cfg, opt.grid);
  for (const auto& c : rig.cameras)
    if (c.in.width != rig.cameras[0].in.width || c.in.height != rig.cameras[0].in.height)
      throw std::invalid_argument(fmt::format(
          "camera {} is {}x{}, camera {} is {}x{}: the chip has one frame size (line width of eq. 5.27)", c.id,
          c.in.width, c.in.height, rig.cameras[0].id, rig.cameras[0].in.width, rig.cameras[0].in.height));
  ExportSummary s;
  ChipConfig& chip = s.chip;
  chip.angles = angle_regs(cfg, opt.grid);
  chip.frame_width = rig.cameras[0].in.width;
  chip.frame_height = rig.cameras[0].in.height;
  chip.method = opt.method;
  chip.boundary = opt.boundary;
  chip.boundary_threshold = cfg.boundary_threshold;
  chip.cameras = camera_regs(cfg, rig);
  chip.vignetting = make_vignetting_tables(cfg, rig, opt.vignetting);
  chip.vig_shift = chip.vignetting.vig_shift;
  const WordStreams ws = encode(cfg, chip);
  s.reg_words = ws.reg.size();
  s.pix_pos_words = ws.pix_pos.size();
  s.cam_search_words = ws.cam_search.size();
  s.pix_val_words = ws.pix_val.size();

  std::filesystem::create_directories(dir);
  nlohmann::json cj = {{"format", "omma-hw-config"},
                       {"version", 1},
                       {"rig", rig.name},
                       {"cameras", rig.cameras.size()},
                       {"hw", config_to_json(cfg)},
                       {"grid", {{"projection", to_string(opt.grid.projection)}, {"width", opt.grid.width}, {"height", opt.grid.height}}},
                       {"method", pano::to_string(opt.method)},
                       {"boundary", opt.boundary}};
  write_text(dir / "config.json", cj.dump(2) + "\n", s);
  write_text(dir / "regs.hex", readmemh_text(ws.reg, 8, "omma hw: global register writes [31]=we [30:16]=address [15:0]=data"), s);
  write_text(dir / "pix_pos.hex", readmemh_text(ws.pix_pos, 8, "omma hw: pix_pos_lutconfig [24:21]=array [20:16]=camera [15:0]=data"), s);
  write_text(dir / "cam_search.hex", readmemh_text(ws.cam_search, 8, "omma hw: cam_search_lutconfig [24:21]=array [20:16]=camera [15:0]=data"), s);
  write_text(dir / "pix_val.hex", readmemh_text(ws.pix_val, 8, "omma hw: pix_val_lutconfig [31]=we [30:16]=address [15:0]=data"), s);

  // Annotated listing.
  std::string listing = "# channel word address field value\n";
  for (uint32_t w : ws.reg) {
    const uint32_t addr = (w >> 16) & 0x7FFF;
    std::string name = "?";
    for (const auto& g : global_registers())
      if (g.address == addr) name = g.name;
      else if (g.address + 1 == addr) name = std::string(g.name) + "[31:16]";
    listing += fmt::format("reg        {:08X} 0x{:04X} {} {}\n", w, addr, name, w & 0xFFFF);
  }
  auto list_array = [&](const std::vector<uint32_t>& words, int channel, const char* cname) {
    for (uint32_t w : words) {
      const int word = (w >> 21) & 0xF, cam = (w >> 16) & 0x1F;
      const ArrayField* f = nullptr;
      for (const auto& a : array_fields())
        if (a.channel == channel && a.word == word) f = &a;
      listing += fmt::format("{:<10} {:08X} 0x{:04X} {} cam {} {} {}\n", cname, w, array_address(cfg, channel, word, cam),
                             f ? f->array : "?", cam, f ? f->field : "?", static_cast<int16_t>(w & 0xFFFF));
    }
  };
  list_array(ws.pix_pos, 0, "pix_pos");
  list_array(ws.cam_search, 1, "cam_search");
  listing += fmt::format("pix_val    {} words (vignetting memory, see vig_mem.hex)\n", ws.pix_val.size());
  write_text(dir / "config_stream.txt", listing, s);

  const SinCosRom rom = make_sincos_rom(cfg);
  const int rd = (cfg.sincos_word_bits + 3) / 4;
  write_text(dir / "sin_rom.hex", readmemh_text(rom.sin_rom, rd, fmt::format("sin quarter wave, {} words uQ1.{}", rom.sin_rom.size(), cfg.sincos_word_bits - 1)), s);
  write_text(dir / "cos_rom.hex", readmemh_text(rom.cos_rom, rd, fmt::format("cos quarter wave, {} words uQ1.{}", rom.cos_rom.size(), cfg.sincos_word_bits - 1)), s);
  write_text(dir / "sin_rom.coe", coe_text(rom.sin_rom, rd), s);
  write_text(dir / "cos_rom.coe", coe_text(rom.cos_rom, rd), s);

  std::vector<uint32_t> vig(vig_memory_words(cfg), 1u << cfg.vig_frac_bits);
  for (uint32_t w : ws.pix_val) vig[(w >> 16) & 0x7FFF] = w & 0xFFFF;
  write_text(dir / "vig_mem.hex", readmemh_text(vig, 4, "vignetting memory uQ2.14: radial (camera << vig_addr_bits | index), channel gains at 2^(camera_bits+vig_addr_bits) + 4 camera + {R,G,B}"), s);
  write_text(dir / "vig_mem.coe", coe_text(vig, 4), s);

  std::vector<uint32_t> pp(16u << cfg.camera_bits, 0), cs(8u << cfg.camera_bits, 0);
  for (uint32_t w : ws.pix_pos) pp[(((w >> 21) & 0xF) << cfg.camera_bits) | ((w >> 16) & 0x1F)] = w & 0xFFFF;
  for (uint32_t w : ws.cam_search) cs[(((w >> 21) & 0xF) << cfg.camera_bits) | ((w >> 16) & 0x1F)] = w & 0xFFFF;
  write_text(dir / "pix_pos_regs.hex", readmemh_text(pp, 4, "pix_pos register arrays, entry (word << camera_bits) | camera"), s);
  write_text(dir / "cam_search_regs.hex", readmemh_text(cs, 4, "cam_search register arrays, entry (word << camera_bits) | camera"), s);

  // C header.
  std::string h = "// Generated by omma hw export: the chip configuration of rig '" + rig.name + "'.\n"
                  "// Formats: docs/hw-model.md. Do not edit.\n#pragma once\n#include <stdint.h>\n\n";
  for (const auto& f : int_fields()) h += fmt::format("#define OMMA_HW_{} {}\n", upper(f.name), cfg.*(f.member));
  for (const auto& f : bool_fields()) h += fmt::format("#define OMMA_HW_{} {}\n", upper(f.name), cfg.*(f.member) ? 1 : 0);
  h += fmt::format("#define OMMA_HW_CAMERAS {}\n#define OMMA_HW_PANO_WIDTH {}\n#define OMMA_HW_PANO_HEIGHT {}\n\n",
                   rig.cameras.size(), opt.grid.width, opt.grid.height);
  for (const auto& g : global_registers()) h += fmt::format("#define OMMA_HW_REG_{} 0x{:04X}\n", upper(g.name), g.address);
  h += fmt::format("#define OMMA_HW_PIX_POS_BASE 0x{:04X}\n#define OMMA_HW_CAM_SEARCH_BASE 0x{:04X}\n\n", kPixPosBase, kCamSearchBase);
  auto arr = [&](const char* name, const std::vector<uint32_t>& w) {
    h += fmt::format("static const uint32_t {}[{}] = {{", name, w.size());
    for (size_t i = 0; i < w.size(); ++i) h += fmt::format("{}0x{:08X}", i % 8 ? ", " : "\n  ", w[i]);
    h += "\n};\n";
  };
  arr("omma_hw_reg_words", ws.reg);
  arr("omma_hw_pix_pos_words", ws.pix_pos);
  arr("omma_hw_cam_search_words", ws.cam_search);
  write_text(dir / "omma_hw_config.h", h, s);
  return s;
}

ImportSummary import_chip(const std::filesystem::path& dir) {
  ImportSummary r;
  nlohmann::json cj;
  try {
    cj = nlohmann::json::parse(read_text_file(dir / "config.json"));
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument(fmt::format("{}: not valid JSON ({})", (dir / "config.json").string(), e.what()));
  }
  if (cj.value("format", "") != "omma-hw-config")
    throw std::invalid_argument((dir / "config.json").string() + ": format must be 'omma-hw-config'");
  if (!cj.contains("hw")) throw std::invalid_argument((dir / "config.json").string() + ": missing 'hw'");
  r.config = config_from_json(cj["hw"]);
  if (cj.contains("grid")) {
    const auto& g = cj["grid"];
    r.grid.projection = parse_projection(g.value("projection", "vr180"));
    r.grid.width = g.value("width", 1080);
    r.grid.height = g.value("height", 1080);
  }
  WordStreams ws;
  ws.reg = parse_words(read_text_file(dir / "regs.hex"), "regs.hex");
  ws.pix_pos = parse_words(read_text_file(dir / "pix_pos.hex"), "pix_pos.hex");
  ws.cam_search = parse_words(read_text_file(dir / "cam_search.hex"), "cam_search.hex");
  ws.pix_val = parse_words(read_text_file(dir / "pix_val.hex"), "pix_val.hex");
  r.chip = decode(r.config, ws);
  r.rig.name = cj.value("rig", std::string("imported"));
  double rmax = 0;
  for (size_t i = 0; i < r.chip.cameras.size(); ++i) {
    r.rig.cameras.push_back(camera_from_regs(r.config, r.chip.cameras[i], static_cast<int>(i)));
    rmax = std::max(rmax, r.rig.cameras.back().position_mm.norm());
  }
  r.rig.dome.radius_mm = rmax > 0 ? rmax : 5.0;
  r.rig.dome.method = "imported";
  r.rig.validate();
  return r;
}

RigDifference rig_difference(const Rig& a, const Rig& b) {
  if (a.cameras.size() != b.cameras.size()) throw std::invalid_argument("rigs have different camera counts");
  RigDifference d;
  auto ang = [](const Vec3& x, const Vec3& y) { return rad2deg(std::acos(std::clamp(x.normalized().dot(y.normalized()), -1.0, 1.0))); };
  for (size_t i = 0; i < a.cameras.size(); ++i) {
    const auto &p = a.cameras[i], &q = b.cameras[i];
    d.axis_deg = std::max({d.axis_deg, ang(p.frame.t, q.frame.t), ang(p.frame.u, q.frame.u), ang(p.frame.v, q.frame.v)});
    d.position_mm = std::max(d.position_mm, (p.position_mm - q.position_mm).cwiseAbs().maxCoeff());
    d.focal_px = std::max({d.focal_px, std::abs(p.in.fu - q.in.fu), std::abs(p.in.fv - q.in.fv)});
    d.centre_px = std::max({d.centre_px, std::abs(p.in.cu - q.in.cu), std::abs(p.in.cv - q.in.cv)});
    for (int k = 0; k < 5; ++k) d.k = std::max(d.k, std::abs(p.in.k[k] - q.in.k[k]));
    d.aov_deg = std::max(d.aov_deg, std::abs(rad2deg(p.in.aov - q.in.aov)));
  }
  return d;
}

RigDifference quantisation_bound(const HwConfig& cfg) {
  RigDifference b;
  const double v = std::ldexp(1.0, -cfg.vec_frac_bits);
  // Each component off by <= v/2: the direction moves by <= sqrt(3) v / 2 rad; u re-orthogonalised
  // against t adds the same again.
  b.axis_deg = rad2deg(2 * std::sqrt(3.0) * v);
  b.position_mm = std::ldexp(0.5, -cfg.pos_frac_bits);
  b.focal_px = std::ldexp(0.5, -cfg.focal_frac_bits);
  b.centre_px = std::ldexp(0.5, -cfg.centre_frac_bits);
  b.k = std::ldexp(0.5, -cfg.k_frac_bits);
  // cos(aov/2) off by v/2: d(aov) = 2 * (v/2) / sin(aov/2) <= v / sin(aov/2); with aov >= 10 deg.
  b.aov_deg = rad2deg(v / std::sin(deg2rad(5.0)));
  return b;
}

}  // namespace omma::hw
