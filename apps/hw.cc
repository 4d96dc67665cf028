// omma hw simulate|sweep|throughput|memory|export|import: the bit-accurate hardware model of the
// panorama pipeline (thesis §5.3-5.5, ch. 6; src/omma/hw, docs/hw-model.md).
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <stdexcept>

#include <fmt/format.h>
#include <opencv2/core.hpp>

#include "apps/command.h"
#include "omma/core/frames.h"
#include "omma/core/io.h"
#include "omma/core/log.h"
#include "omma/core/progress.h"
#include "omma/core/rig.h"
#include "omma/design/prototype.h"
#include "omma/hw/export.h"
#include "omma/hw/memory.h"
#include "omma/hw/pipeline.h"
#include "omma/hw/tables.h"
#include "omma/hw/throughput.h"
#include "omma/hw/width_sweep.h"
#include "omma/isp/photometric.h"
#include "omma/pano/maps.h"
#include "omma/pano/quality.h"
#include "omma/pano/stitch.h"

namespace omma::app {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

// --config FILE (JSON object of HwConfig fields) then --set name=value overrides.
hw::HwConfig load_config(const std::string& path, const std::vector<std::string>& sets) {
  hw::HwConfig cfg;
  if (!path.empty()) {
    nlohmann::json j;
    try {
      j = nlohmann::json::parse(read_text_file(path));
    } catch (const nlohmann::json::exception& e) {
      throw std::invalid_argument(fmt::format("{}: not valid JSON ({})", path, e.what()));
    }
    cfg = hw::config_from_json(j.contains("hw") ? j["hw"] : j);
  }
  nlohmann::json j = hw::config_to_json(cfg);
  for (const std::string& s : sets) {
    const auto eq = s.find('=');
    if (eq == std::string::npos) throw std::invalid_argument("--set expects name=value, got '" + s + "'");
    const std::string name = s.substr(0, eq), value = s.substr(eq + 1);
    if (!j.contains(name))
      throw std::invalid_argument(fmt::format("--set: unknown hardware field '{}'", name));
    if (j[name].is_boolean()) {
      if (value != "true" && value != "false")
        throw std::invalid_argument(fmt::format("--set {}: use true or false", name));
      j[name] = value == "true";
    } else {
      try {
        size_t pos = 0;
        const int v = std::stoi(value, &pos);
        if (pos != value.size()) throw std::invalid_argument("");
        j[name] = v;
      } catch (const std::exception&) {
        throw std::invalid_argument(fmt::format("--set {}: '{}' is not an integer", name, value));
      }
    }
  }
  return hw::config_from_json(j);
}

PanoGrid make_grid(const std::string& projection, const std::string& size) {
  PanoGrid g;
  g.projection = parse_projection(projection);
  if (size.empty()) {
    g.width = g.projection == Projection::kVr180 ? 1080 : 1920;
    g.height = g.projection == Projection::kVr180 ? 1080 : g.projection == Projection::kEquirect ? 512 : 960;
  } else {
    const Size2 s = parse_size(size);
    g.width = s.width;
    g.height = s.height;
  }
  return g;
}

pano::Method hw_method(const std::string& name) {
  const pano::Method m = pano::parse_method(name);
  if (m != pano::Method::kNearest && m != pano::Method::kLinear && m != pano::Method::kMrf)
    throw std::invalid_argument("--method: the hardware implements nn, linear and mrf (got '" + name + "')");
  return m;
}

Rig rig_for(const std::string& rig_path, const std::string& frames) {
  if (!rig_path.empty()) return design::load_rig_or_builtin(rig_path);
  if (!frames.empty() && fs::exists(fs::path(frames) / "rig.json"))
    return load_rig(fs::path(frames) / "rig.json");
  throw std::invalid_argument("--rig is required (or a frames folder with rig.json)");
}

nlohmann::json histogram_json(const std::array<uint64_t, 9>& h) {
  nlohmann::json j = nlohmann::json::array();
  for (uint64_t v : h) j.push_back(v);
  return j;
}

// ------------------------------------------------------------------------------------ simulate
struct SimArgs {
  std::string rig, frames, method = "linear", projection = "vr180", size, out, config, dump_hex;
  std::vector<std::string> sets;
  bool boundary = false, json = false, no_reference = false, no_photometric = false;
  double clock_mhz = 120;
};

double memory_exponent(const std::string& encoding) {
  if (encoding == "srgb") return hw::kSrgbVignettingExponent;
  if (encoding == "linear") return 1.0;
  throw std::invalid_argument("--memory-encoding must be srgb or linear, not '" + encoding + "'");
}

void run_simulate(const SimArgs& a) {
  set_json_mode(a.json);
  const hw::HwConfig cfg = load_config(a.config, a.sets);
  const pano::Method method = hw_method(a.method);
  const PanoGrid grid = make_grid(a.projection, a.size);
  if (!(a.clock_mhz > 0)) throw std::invalid_argument("--clock-mhz must be positive");
  const Rig rig = rig_for(a.rig, a.frames);
  hw::check_rig(cfg, rig);
  hw::check_grid(cfg, grid);
  if (a.out.empty() && a.dump_hex.empty() && !a.json)
    spdlog::warn("hw simulate: no --out given, the panorama is not written");
  const std::vector<cv::Mat> frames = load_frames(a.frames, rig);
  // The rig's photometric model in the vignetting memory (sRGB frames: the power-law approximation,
  // hw/tables.h); the float reference then stitches the frames corrected exactly (isp/photometric.h).
  const bool photometric = !a.no_photometric && has_photometric(rig);
  const hw::VignettingTables vig = hw::make_vignetting_tables(
      cfg, rig,
      photometric ? hw::vignetting_from_rig(rig, hw::kSrgbVignettingExponent) : hw::VignettingModel{});
  hw::Pipeline pipe(cfg, rig, grid, &vig);
  pipe.load_frames(frames);
  auto t0 = Clock::now();
  const hw::PipelineSummary r = pipe.render(method, a.boundary, true);
  const double hw_ms = ms_since(t0);
  nlohmann::json j;
  const double pixels = double(grid.width) * grid.height;
  j["method"] = pano::to_string(method);
  j["projection"] = to_string(grid.projection);
  j["width"] = grid.width;
  j["height"] = grid.height;
  j["cameras"] = rig.cameras.size();
  j["cycles"] = r.stats.cycles;
  j["cycles_per_pixel"] = r.stats.cycles / pixels;
  j["clock_mhz"] = a.clock_mhz;
  j["fps_at_clock"] = a.clock_mhz * 1e6 / double(r.stats.cycles);
  j["contributors_histogram"] = histogram_json(r.stats.contributors);
  j["dropped_by_encoder_pixels"] = r.stats.dropped_by_encoder;
  j["mrf_fallback_pixels"] = r.stats.mrf_fallback_pixels;
  j["model_ms"] = hw_ms;
  j["photometric"] = photometric;
  j["config"] = hw::config_to_json(cfg);
  if (!a.no_reference) {
    pano::StitchOptions so;
    so.method = method;
    so.grid = grid;
    std::vector<cv::Mat> ref_frames = hw::rgb565_frames(frames);
    if (photometric) ref_frames = isp::correct_frames(rig, ref_frames);
    t0 = Clock::now();
    const cv::Mat ref = to_u8(pano::stitch(rig, ref_frames, so));
    j["float_ms"] = ms_since(t0);
    // Compare the panorama without the boundary paint (the float stitch has none).
    cv::Mat hw_pano = r.pano;
    if (a.boundary) hw_pano = pipe.render(method, false).pano;
    j["psnr_vs_float_db"] = pano::psnr_db(hw_pano, ref);
    if (a.boundary) {
      const cv::Mat fb =
          pano::boundary_binary(pano::boundary_map(rig, ref_frames, grid), cfg.boundary_threshold / 255.0);
      cv::Mat diff;
      cv::compare(r.boundary, fb, diff, cv::CMP_NE);
      j["boundary_pixels"] = r.stats.boundary_pixels;
      j["boundary_pixels_float"] = cv::countNonZero(fb);
      j["boundary_disagreeing_pixels"] = cv::countNonZero(diff);
    }
  }
  if (!a.out.empty()) write_image(a.out, r.pano);
  if (!a.dump_hex.empty()) {
    fs::create_directories(a.dump_hex);
    for (size_t i = 0; i < frames.size(); ++i) {
      std::vector<uint32_t> w;
      for (uint16_t x : hw::frame_to_rgb565(frames[i])) w.push_back(x);
      write_text_atomically(
          fs::path(a.dump_hex) / fmt::format("frame_{:02d}.hex", i),
          hw::readmemh_text(w, 4, fmt::format("camera {} RGB565, row-major (eq. 5.27)", i)));
    }
    std::vector<uint32_t> px;
    px.reserve(static_cast<size_t>(pixels));
    for (int y = 0; y < grid.height; ++y)
      for (int x = 0; x < grid.width; ++x) {
        const cv::Vec3b b = r.pano.at<cv::Vec3b>(y, x);
        px.push_back((uint32_t{b[2]} << 16) | (uint32_t{b[1]} << 8) | b[0]);
      }
    write_text_atomically(
        fs::path(a.dump_hex) / "expected_rgb888.hex",
        hw::readmemh_text(px, 6, "expected output RGB888 (R[23:16] G[15:8] B[7:0]), scan order"));
    hw::ExportOptions eo;
    eo.config = cfg;
    eo.grid = grid;
    eo.method = method;
    eo.boundary = a.boundary;
    hw::export_chip(rig, eo, a.dump_hex);
  }
  if (a.json) {
    print_json(j);
  } else {
    std::cout << fmt::format("hw {} {}x{}: {} cycles ({:.3f} per pixel) = {:.2f} fps at {} MHz",
                             j["method"].get<std::string>(), grid.width, grid.height, r.stats.cycles,
                             r.stats.cycles / pixels, j["fps_at_clock"].get<double>(), a.clock_mhz);
    if (j.contains("psnr_vs_float_db"))
      std::cout << fmt::format("; {:.2f} dB against the float stitch", j["psnr_vs_float_db"].get<double>());
    std::cout << "\n";
  }
}

// ------------------------------------------------------------------------------------ sweep
struct SweepArgs {
  std::string rig, frames, method = "linear", projection = "vr180", size = "540x540", out, config;
  std::vector<std::string> sets, params;
  double target = 45;
  bool json = false;
};

void run_sweep_cmd(const SweepArgs& a) {
  set_json_mode(a.json);
  hw::WidthSweepOptions o;
  o.base = load_config(a.config, a.sets);
  o.method = hw_method(a.method);
  o.grid = make_grid(a.projection, a.size);
  o.target_db = a.target;
  if (!(a.target > 0 && a.target < 200)) throw std::invalid_argument("--target must be in (0, 200) dB");
  if (!a.params.empty()) {
    std::vector<hw::SweepParam> keep;
    for (const auto& name : a.params) {
      bool found = false;
      for (const auto& p : hw::default_sweep_params())
        if (p.name == name) keep.push_back(p), found = true;
      if (!found) throw std::invalid_argument("--param: no sweep for '" + name + "'");
    }
    o.params = keep;
  }
  if (a.out.empty()) throw std::invalid_argument("--out DIR is required");
  const Rig rig = rig_for(a.rig, a.frames);
  hw::check_rig(o.base, rig);
  const std::vector<cv::Mat> frames = load_frames(a.frames, rig);
  size_t total = 1;
  for (const auto& p : o.params) total += p.values.size();
  Progress progress("hw sweep", total);
  o.progress = [&](const std::string& what) {
    spdlog::debug("hw sweep: {}", what);
    if (what.rfind("minimal set", 0) != 0) progress.step();  // the search for the smallest set is not counted
  };
  const hw::WidthSweepSummary r = hw::run_sweep(rig, frames, o);
  progress.finish();
  fs::create_directories(a.out);
  write_text_atomically(fs::path(a.out) / "hw_sweep.csv", hw::sweep_csv(r, a.target));
  write_text_atomically(fs::path(a.out) / "hw_sweep.svg", hw::sweep_svg(r, a.target));
  // The smallest set as a configuration usable with --config.
  write_text_atomically(fs::path(a.out) / "hw_minimal.json", hw::config_to_json(r.minimal).dump(2) + "\n");
  nlohmann::json pts = nlohmann::json::array();
  for (const auto& p : r.points)
    pts.push_back({{"param", p.param},
                   {"value", p.value},
                   {"psnr_db", p.valid ? nlohmann::json(p.psnr_db) : nlohmann::json()}});
  nlohmann::json j = {{"base_psnr_db", r.base_psnr_db},
                      {"target_db", a.target},
                      {"points", pts},
                      {"minimal", hw::config_to_json(r.minimal)},
                      {"minimal_psnr_db", r.minimal_psnr_db},
                      {"minimal_steps", r.minimal_steps},
                      {"csv", (fs::path(a.out) / "hw_sweep.csv").string()},
                      {"svg", (fs::path(a.out) / "hw_sweep.svg").string()},
                      {"minimal_config", (fs::path(a.out) / "hw_minimal.json").string()}};
  if (a.json) {
    print_json(j);
    return;
  }
  std::cout << fmt::format("base configuration: {:.2f} dB\n", r.base_psnr_db);
  for (const auto& s : r.minimal_steps) std::cout << "  " << s << "\n";
  std::cout << fmt::format("smallest set: {:.2f} dB: {}\n", r.minimal_psnr_db,
                           hw::config_to_json(r.minimal).dump());
}

// ------------------------------------------------------------------------------------ throughput
struct ThArgs {
  hw::ThroughputOptions o;
  std::string size = "1080x1080", rig, projection = "vr180", config;
  bool search_per_camera = false, json = false;
};

void run_throughput(ThArgs a) {
  set_json_mode(a.json);
  const Size2 s = parse_size(a.size);
  a.o.width = s.width;
  a.o.height = s.height;
  a.o.unrolled = !a.search_per_camera;
  std::string err;
  if (!a.o.IsValid(&err)) throw std::invalid_argument(err);
  const hw::ThroughputSummary t = hw::throughput(a.o);
  nlohmann::json blocks = nlohmann::json::array();
  for (const auto& b : t.blocks) blocks.push_back({{"block", b.block}, {"th", b.th}});
  nlohmann::json j = {{"blocks", blocks},
                      {"th_sys", t.th_sys},
                      {"fmin_mhz", t.fmin_mhz},
                      {"fps_at_clock", t.fps_at_clock},
                      {"clock_mhz", a.o.clock_mhz},
                      {"fps", a.o.fps},
                      {"width", a.o.width},
                      {"height", a.o.height},
                      {"cameras", a.o.cameras},
                      {"pixels_per_frame_at_clock", t.pixels_per_frame_at_clock},
                      {"square_side_at_clock", t.square_side_at_clock}};
  if (!a.rig.empty()) {
    // Beyond the thesis: the cycles the bit-accurate pipeline counts on this rig and grid
    // (contributors per pixel decide the search and pixel value Th).
    const Rig rig = design::load_rig_or_builtin(a.rig);
    const hw::HwConfig cfg = load_config(a.config, {});
    PanoGrid g{parse_projection(a.projection), s.width, s.height};
    hw::Pipeline p(cfg, rig, g);
    std::vector<cv::Mat> blank;
    for (const auto& c : rig.cameras)
      blank.emplace_back(c.in.height, c.in.width, CV_8UC3, cv::Scalar::all(0));
    p.load_frames(blank);
    const hw::PipelineSummary r = p.render(pano::Method::kNearest, false, !a.json);
    const double pixels = double(s.width) * s.height;
    j["counted"] = {{"rig", rig.name},
                    {"projection", to_string(g.projection)},
                    {"cycles", r.stats.cycles},
                    {"cycles_per_pixel", r.stats.cycles / pixels},
                    {"fps_at_clock", a.o.clock_mhz * 1e6 / double(r.stats.cycles)},
                    {"fmin_mhz", a.o.fps * double(r.stats.cycles) * 1e-6},
                    {"contributors_histogram", histogram_json(r.stats.contributors)}};
  }
  if (a.json) {
    print_json(j);
    return;
  }
  for (const auto& b : t.blocks) std::cout << fmt::format("  {:<18} Th = {}\n", b.block, b.th);
  std::cout << fmt::format(
      "Th_sys = {}; F_min = 25 x {} x {} x {} = {:.3f} MHz at {} fps; at {} MHz: {:.2f} fps, "
      "{:.0f} pixels per frame ({}x{})\n",
      t.th_sys, a.o.width, a.o.height, t.th_sys, t.fmin_mhz, a.o.fps, a.o.clock_mhz, t.fps_at_clock,
      t.pixels_per_frame_at_clock, t.square_side_at_clock, t.square_side_at_clock);
  if (j.contains("counted"))
    std::cout << fmt::format("counted on {}: {:.3f} cycles per pixel, {:.2f} fps at {} MHz\n", a.rig,
                             j["counted"]["cycles_per_pixel"].get<double>(),
                             j["counted"]["fps_at_clock"].get<double>(), a.o.clock_mhz);
}

// ------------------------------------------------------------------------------------ memory
struct MemArgs {
  hw::MemoryOptions o;
  std::string frame = "250x250", pano = "1080x1080", rig, device = "XC7VX485T";
  int bram36 = 1030;
  bool json = false;
};

void run_memory(MemArgs a) {
  set_json_mode(a.json);
  if (!a.rig.empty()) {
    const Rig rig = design::load_rig_or_builtin(a.rig);
    a.o.cameras = static_cast<int>(rig.cameras.size());
    a.frame = fmt::format("{}x{}", rig.cameras[0].in.width, rig.cameras[0].in.height);
  }
  const Size2 f = parse_size(a.frame), p = parse_size(a.pano);
  a.o.frame_width = f.width;
  a.o.frame_height = f.height;
  a.o.pano_width = p.width;
  a.o.pano_height = p.height;
  if (a.bram36 < 1) throw std::invalid_argument("--bram36 must be positive");
  const hw::MemoryReport r = hw::memory_report(a.o);
  const hw::FpgaPlan plan = hw::plan_fpga(a.o, {a.device, a.bram36});
  nlohmann::json rows = nlohmann::json::array(), fifos = nlohmann::json::array(),
                 wr = nlohmann::json::array(), pins = nlohmann::json::array();
  for (const auto& m : r.rows)
    rows.push_back({{"block", m.block},
                    {"type", hw::to_string(m.kind)},
                    {"count", m.count},
                    {"words", m.words},
                    {"bits", m.bits},
                    {"kbytes", m.kbytes},
                    {"area_mm2", m.area_mm2},
                    {"area_estimated", m.area_estimated}});
  for (const auto& x : r.fifos)
    fifos.push_back({{"name", x.name}, {"words", x.words}, {"bits", x.bits}, {"clocking", x.clocking}});
  for (const auto& x : r.wrappers)
    wr.push_back({{"name", x.name}, {"instances", x.instances}, {"kind", x.kind}, {"kbytes", x.kbytes}});
  for (const auto& x : r.pins)
    pins.push_back({{"name", x.name}, {"initial", x.initial}, {"with_io", x.with_io}});
  nlohmann::json j = {{"table_6_4", rows},
                      {"total_kbytes", r.total_kbytes},
                      {"total_area_mm2", r.total_area_mm2},
                      {"table_6_5", fifos},
                      {"table_6_8", wr},
                      {"table_6_3", pins},
                      {"pins_initial", r.pins_initial},
                      {"pins_with_io", r.pins_with_io},
                      {"frame_memory_bits", r.frame_memory_bits},
                      {"fpga",
                       {{"device", a.device},
                        {"bram36", a.bram36},
                        {"frame_blocks_per_camera", plan.frame_blocks_per_camera},
                        {"frame_blocks", plan.frame_blocks},
                        {"table_blocks", plan.table_blocks},
                        {"total_blocks", plan.total_blocks},
                        {"utilisation", plan.utilisation},
                        {"fits", plan.fits},
                        {"clock_mhz", plan.clock_mhz}}}};
  if (a.json) {
    print_json(j);
    return;
  }
  std::cout << "Table 6.4 (ASIC memories):\n";
  for (const auto& m : r.rows)
    std::cout << fmt::format("  {:<18} {:<16} {:>4} x {:>5} x {:>2} bit = {:>10.3f} KB {:>7.3f} mm2{}\n",
                             m.block, hw::to_string(m.kind), m.count, m.words, m.bits, m.kbytes, m.area_mm2,
                             m.area_estimated ? " (estimate)" : "");
  std::cout << fmt::format("  total {:.3f} KB, {:.3f} mm2\n", r.total_kbytes, r.total_area_mm2);
  std::cout << fmt::format("frame memories {:.3f} Mbit; pins {} / {} (Table 6.3)\n",
                           r.frame_memory_bits / 1e6, r.pins_initial, r.pins_with_io);
  std::cout << fmt::format("FPGA {}: {} + {} = {} of {} 36Kb blocks ({:.1f} %, {}), clock >= {:.2f} MHz\n",
                           a.device, plan.frame_blocks, plan.table_blocks, plan.total_blocks, a.bram36,
                           100 * plan.utilisation, plan.fits ? "fits" : "does NOT fit", plan.clock_mhz);
}

// ------------------------------------------------------------------------------------ export / import
struct ExArgs {
  std::string rig, dir, method = "linear", projection = "vr180", size, config, memory_encoding = "srgb";
  std::vector<std::string> sets;
  bool boundary = false, json = false, no_photometric = false;
};

void run_export(const ExArgs& a) {
  set_json_mode(a.json);
  hw::ExportOptions o;
  o.config = load_config(a.config, a.sets);
  o.grid = make_grid(a.projection, a.size);
  o.method = hw_method(a.method);
  o.boundary = a.boundary;
  // Vignetting: the rig's photometric model when it has one (hw/tables.h), else unit tables.
  const Rig rig = design::load_rig_or_builtin(a.rig);
  const double exponent = memory_exponent(a.memory_encoding);
  const bool photometric = !a.no_photometric && has_photometric(rig);
  if (photometric) {
    o.vignetting = hw::vignetting_from_rig(rig, exponent);
    o.vignetting_exponent = exponent;
  }
  const hw::ExportSummary s = hw::export_chip(rig, o, a.dir);
  nlohmann::json j = {
      {"dir", a.dir},
      {"files", s.files},
      {"cameras", rig.cameras.size()},
      {"words",
       {{"reg", s.reg_words},
        {"pix_pos", s.pix_pos_words},
        {"cam_search", s.cam_search_words},
        {"pix_val", s.pix_val_words}}},
      {"angle_registers",
       {{"theta_min", s.chip.angles.theta_min},
        {"k_theta", s.chip.angles.k_theta},
        {"phi_min", s.chip.angles.phi_min},
        {"k_phi", s.chip.angles.k_phi}}},
      {"vignetting", photometric ? "the rig's photometric model (" + a.memory_encoding + " frame memories)"
                                 : std::string("unit tables (no photometric model)")}};
  if (a.json)
    print_json(j);
  else
    std::cout << fmt::format("{}: {} files; {} register, {} pix_pos, {} cam_search, {} pix_val words\n",
                             a.dir, s.files.size(), s.reg_words, s.pix_pos_words, s.cam_search_words,
                             s.pix_val_words);
}

struct ImArgs {
  std::string dir, rig_out, compare;
  bool json = false;
};

void run_import(const ImArgs& a) {
  set_json_mode(a.json);
  const hw::ImportSummary r = hw::import_chip(a.dir);
  save_rig(r.rig, a.rig_out);
  const hw::RigDifference b = hw::quantisation_bound(r.config);
  auto diff_json = [](const hw::RigDifference& d) {
    return nlohmann::json{{"axis_deg", d.axis_deg},
                          {"position_mm", d.position_mm},
                          {"focal_px", d.focal_px},
                          {"centre_px", d.centre_px},
                          {"k", d.k},
                          {"aov_deg", d.aov_deg}};
  };
  nlohmann::json j = {
      {"rig", a.rig_out},
      {"cameras", r.rig.cameras.size()},
      {"method", pano::to_string(r.chip.method)},
      {"grid",
       {{"projection", to_string(r.grid.projection)}, {"width", r.grid.width}, {"height", r.grid.height}}},
      {"quantisation_bound", diff_json(b)},
      {"photometric_cameras", std::count_if(r.rig.cameras.begin(), r.rig.cameras.end(),
                                            [](const RigCamera& c) { return c.photometric.has_value(); })},
      {"vignetting_fit_error", r.vignetting_error}};
  if (!a.compare.empty())
    j["difference"] = diff_json(hw::rig_difference(design::load_rig_or_builtin(a.compare), r.rig));
  if (a.json)
    print_json(j);
  else
    std::cout << fmt::format(
        "{}: {} cameras{}\n", a.rig_out, r.rig.cameras.size(),
        a.compare.empty() ? ""
                          : fmt::format("; max difference to {}: {}", a.compare, j["difference"].dump()));
}

}  // namespace

void add_hw_command(CLI::App& root) {
  auto* cmd =
      root.add_subcommand("hw",
                          "Bit-accurate hardware model of the panorama pipeline (thesis §5.3-5.5, ch. 6; "
                          "docs/hw-model.md)");
  cmd->require_subcommand(1);
  auto add_cfg = [](CLI::App* c, std::string& config, std::vector<std::string>& sets) {
    c->add_option("--config", config,
                  "Hardware widths: JSON object of HwConfig fields (e.g. an export's config.json)");
    c->add_option("--set", sets, "Override one width, name=value (repeatable), e.g. --set angle_bits=20");
  };
  // Options shared by simulate and sweep: the rig, its frames, the method and the output grid.
  auto add_scene = [](CLI::App* c, std::string& rig, std::string& frames, std::string& method,
                      std::string& projection, std::string& size, const char* size_help) {
    c->add_option("--rig", rig, "Rig (JSON); default FRAMES/rig.json");
    c->add_option("--frames", frames, "Frames folder (cam_XX.png)")->required();
    c->add_option("--method", method, "Pixel value unit: nn, linear (default) or mrf");
    c->add_option("--projection", projection, "vr180 (default), equirect or equirect-full");
    c->add_option("--size", size, size_help);
  };

  static SimArgs sa;
  auto* sim = cmd->add_subcommand("simulate",
                                  "Render a panorama with the bit-accurate pipeline; compare with the float "
                                  "stitch of the same RGB565 frames; count cycles");
  add_scene(sim, sa.rig, sa.frames, sa.method, sa.projection, sa.size,
            "Panorama WxH (default 1080x1080 vr180, 1920x512 equirect)");
  sim->add_flag("--boundary", sa.boundary, "Object boundary unit on (§5.4.5): boundary pixels painted green");
  sim->add_option("--out", sa.out, "Panorama image to write (PNG, atomic)");
  sim->add_option("--clock-mhz", sa.clock_mhz,
                  "Clock for the frame rate the counted cycles give (default 120)");
  sim->add_option("--dump-hex", sa.dump_hex,
                  "Also write the RTL testbench files: frame_XX.hex, expected_rgb888.hex "
                  "and the export files");
  sim->add_flag("--no-reference", sa.no_reference, "Skip the float reference (no psnr_vs_float_db)");
  sim->add_flag(
      "--no-photometric", sa.no_photometric,
      "Unit vignetting tables even when the rig has a photometric model (by default its model is loaded\n"
      "into the vignetting memory and the float reference corrects the frames exactly)");
  add_cfg(sim, sa.config, sa.sets);
  sim->add_flag("--json", sa.json, "Print one JSON object on stdout");
  sim->callback([] { run_simulate(sa); });

  static SweepArgs sw;
  auto* swp = cmd->add_subcommand("sweep",
                                  "PSNR against the float stitch as each width varies; the smallest widths "
                                  "that keep the target (CSV + SVG)");
  add_scene(swp, sw.rig, sw.frames, sw.method, sw.projection, sw.size, "Panorama WxH (default 540x540)");
  swp->add_option("--target", sw.target, "PSNR target in dB (default 45)");
  swp->add_option("--param", sw.params, "Sweep only these widths (repeatable)");
  swp->add_option("--out", sw.out, "Output folder for hw_sweep.csv and hw_sweep.svg")->required();
  add_cfg(swp, sw.config, sw.sets);
  swp->add_flag("--json", sw.json, "Print one JSON object on stdout");
  swp->callback([] { run_sweep_cmd(sw); });

  static ThArgs ta;
  auto* th = cmd->add_subcommand(
      "throughput", "Per-block initiation intervals, Th_sys, F_min = 25 N M Th_sys (§5.4.3-5.4.4)");
  th->add_option("--cameras", ta.o.cameras, "Cameras (default 24)");
  th->add_option("--contributors", ta.o.max_contributors,
                 "Contributors per direction N_cam_contr (default 4)");
  th->add_option("--size", ta.size, "Panorama WxH (default 1080x1080)");
  th->add_option("--fps", ta.o.fps, "Frame rate for F_min (default 25)");
  th->add_option("--clock-mhz", ta.o.clock_mhz, "Clock for the frame rate (default 120)");
  th->add_option("--table-sets", ta.o.table_sets,
                 "sin/cos table sets in the Cartesian unit: 1 (Th 9) or 3 (Th 3, default)");
  th->add_flag("--search-per-camera", ta.search_per_camera,
               "Camera search before unrolling: 1 cycle per camera");
  th->add_option("--rig", ta.rig, "Also count the cycles the bit-accurate pipeline takes on this rig");
  th->add_option("--projection", ta.projection, "Grid for --rig (default vr180)");
  th->add_option("--config", ta.config, "Hardware widths for --rig (JSON)");
  th->add_flag("--json", ta.json, "Print one JSON object on stdout");
  th->callback([] { run_throughput(ta); });

  static MemArgs ma;
  auto* mem = cmd->add_subcommand(
      "memory", "Memories (Tables 6.4, 6.5, 6.8), pins (Table 6.3), FPGA block-RAM plan and clock");
  mem->add_option("--cameras", ma.o.cameras, "Cameras (default 24)");
  mem->add_option("--frame", ma.frame, "Camera frame WxH (default 250x250)");
  mem->add_option("--bpp", ma.o.bits_per_pixel,
                  "Bits per stored pixel (default 16 = RGB565; 30 = 10-bit RGB)");
  mem->add_option("--pano", ma.pano, "Panorama WxH (default 1080x1080)");
  mem->add_option("--fps", ma.o.fps, "Frame rate (default 25)");
  mem->add_option("--th-sys", ma.o.th_sys, "Cycles per panorama pixel (default 4)");
  mem->add_option("--sincos-words", ma.o.sincos_words, "Words per sin/cos ROM (default 2048)");
  mem->add_option("--rig", ma.rig, "Take cameras and frame size from a rig");
  mem->add_option("--device", ma.device, "FPGA name (default XC7VX485T)");
  mem->add_option("--bram36", ma.bram36, "36 Kbit block RAMs of the FPGA (default 1030)");
  mem->add_flag("--json", ma.json, "Print one JSON object on stdout");
  mem->callback([] { run_memory(ma); });

  static ExArgs ea;
  auto* ex =
      cmd->add_subcommand("export",
                          "Write what the chip loads: register map (Table 6.7), word streams (Table 6.6), "
                          "$readmemh / .coe ROMs and tables, C header");
  ex->add_option("RIG", ea.rig, "Rig (JSON)")->required();
  ex->add_option("DIR", ea.dir, "Output folder")->required();
  ex->add_option("--method", ea.method, "nn, linear (default) or mrf");
  ex->add_option("--projection", ea.projection, "vr180 (default), equirect, equirect-full");
  ex->add_option("--size", ea.size, "Panorama WxH");
  ex->add_flag("--boundary", ea.boundary, "Enable the object boundary unit");
  ex->add_flag("--no-photometric", ea.no_photometric,
               "Unit vignetting tables even when the rig has a photometric model");
  ex->add_option(
        "--memory-encoding", ea.memory_encoding,
        "What the frame memories hold: srgb (omma's frames; the vignetting gains are (1/V)^(1/2.2)) or\n"
        "linear (the thesis's front end; 1/V)")
      ->capture_default_str();
  add_cfg(ex, ea.config, ea.sets);
  ex->add_flag("--json", ea.json, "Print one JSON object on stdout");
  ex->callback([] { run_export(ea); });

  static ImArgs ia;
  auto* im = cmd->add_subcommand("import",
                                 "Read an export folder back into a rig (within each field's quantisation)");
  im->add_option("DIR", ia.dir, "Export folder")->required();
  im->add_option("RIG", ia.rig_out, "Rig to write (JSON, atomic)")->required();
  im->add_option("--compare", ia.compare, "Report the largest differences to this rig");
  im->add_flag("--json", ia.json, "Print one JSON object on stdout");
  im->callback([] { run_import(ia); });
}

}  // namespace omma::app
