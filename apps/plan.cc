// omma plan: the Giga-Eye recording planner (thesis Table 7.1, §7.1).
#include <cmath>
#include <iostream>
#include <memory>
#include <optional>

#include <fmt/format.h>

#include "apps/command.h"
#include "omma/core/grid.h"
#include "omma/design/recording_plan.h"

namespace omma::app {
namespace {

void print_plan(const design::RecordingPlan& p) {
  const auto& in = p.in;
  std::cout << fmt::format(
      "{} cameras, {}x{} at {:g} fps, {} bit/px, {:g} MHz clock, {} per device ({:.0f} GB, {:.0f} MB/s), "
      "{:g} min\n",
      in.cameras, in.width, in.height, in.fps, in.bits, in.clock_mhz, in.cameras_per_device,
      in.device_bytes / 1e9, in.device_rate / 1e6, in.minutes);
  std::cout << fmt::format("  per camera: {:.3f} MiB/s ({:.2f} MB/s), {:.3f} GiB\n", p.camera_mib_per_s,
                           p.camera_bytes_per_s / 1e6, p.camera_gib);
  std::cout << fmt::format("  per device: {:.3f} MiB/s ({:.2f} MB/s), {:.2f} GB; holds {:.2f} min\n",
                           p.device_bytes_per_s / (1 << 20), p.device_bytes_per_s / 1e6, p.device_bytes / 1e9,
                           p.max_minutes);
  std::cout << fmt::format("  rig: {} devices, {:.3f} GB/s, {:.2f} TiB ({:.2f} TB)\n", p.devices,
                           p.rig_bytes_per_s / 1e9, p.rig_bytes / std::pow(2.0, 40), p.rig_bytes / 1e12);
  for (const auto& c : p.checks)
    std::cout << fmt::format("  {:<18} {}  {}\n", c.name, c.ok ? "ok  " : "FAIL", c.detail);
}

void print_table71(const std::vector<design::Table71Check>& rows, const design::RecordingPlan& fives) {
  std::cout << "Table 7.1 recomputed (binary units: MB = MiB, GB = GiB; rounded half up), 2 cameras per "
               "128 GB / 150 MB/s SSD, clock < 80 MHz:\n";
  std::cout << "opt  output     bit  MHz  fps   min | BW MiB/s (printed) | memory GiB (printed) | checks\n";
  for (const auto& r : rows) {
    std::string notes;
    for (const auto& c : r.plan.checks)
      if (!c.ok) notes += (notes.empty() ? "" : ", ") + c.name;
    std::string flag = r.matches ? "matches" : "MISMATCH";
    if (r.fits_bits) flag += fmt::format(" (the printed figures fit {} bit/px)", *r.fits_bits);
    std::cout << fmt::format(
        "{:>3}  {:>4}x{:<4}  {:>3}  {:>3g}  {:>4g}  {:>3g} | {:8.3f} ({:>3}) {:>5} | {:9.3f} ({:>3}) {:>6} | "
        "{} {}\n",
        r.row.option, r.row.width, r.row.height, r.row.bits, r.row.clock_mhz, r.row.fps, r.row.minutes,
        r.plan.camera_mib_per_s, r.row.bandwidth_mb_s, r.bandwidth, r.plan.camera_gib, r.row.memory_gb,
        r.memory, notes.empty() ? "hold" : "fail: " + notes, flag);
  }
  std::cout << fmt::format(
      "\"5.2 TB for 44 cameras\" (option 1, 30 min, L6537-6539): 44 x {:.2f} GiB = {:.2f} TiB ({:.2f} TB); "
      "5.2 TiB "
      "is 30 cameras\n",
      fives.camera_gib, fives.rig_bytes / std::pow(2.0, 40), fives.rig_bytes / 1e12);
}

}  // namespace

void add_plan_command(CLI::App& root) {
  struct Opts {
    std::optional<int> row;
    std::string resolution = "2592x1944", device_size = "128GB", device_rate = "150MB/s";
    design::RecordingPlanInput in;
    bool table = false, json = false;
  };
  auto o = std::make_shared<Opts>();
  auto* cmd = root.add_subcommand(
      "plan",
      "Recording planner of the Giga-Eye (thesis Table 7.1): per camera, per storage device and for the "
      "rig,\n"
      "the bandwidth, the storage for the duration and the recording time a device holds, and whether the\n"
      "pixel clock (< 80 MHz over long cables), the device's write rate and its capacity hold. A plan that "
      "does\n"
      "not hold is an error naming the constraint. --table71 recomputes the thesis's table (binary units).");
  cmd->add_option("--row", o->row, "Start from Table 7.1 option 1..8 (other options override its values)")
      ->check(CLI::Range(1, 8));
  cmd->add_option("--resolution", o->resolution, "Output resolution per camera WxH (after skipping/window)")
      ->capture_default_str();
  cmd->add_option("--bits", o->in.bits, "Bits per pixel as stored")->capture_default_str();
  cmd->add_option("--fps", o->in.fps, "Frame rate")->capture_default_str();
  cmd->add_option("--clock", o->in.clock_mhz, "Pixel clock, MHz")->capture_default_str();
  cmd->add_option("--max-clock", o->in.max_clock_mhz, "Highest usable pixel clock (exclusive), MHz")
      ->capture_default_str();
  cmd->add_option("--cameras", o->in.cameras, "Cameras in the rig")->capture_default_str();
  cmd->add_option("--per-device", o->in.cameras_per_device, "Cameras per storage device")
      ->capture_default_str();
  cmd->add_option("--device-size", o->device_size, "Capacity of one device (B, kB, MB, GB, TB, KiB..TiB)")
      ->capture_default_str();
  cmd->add_option("--device-rate", o->device_rate, "Sustained write rate of one device, e.g. 150MB/s")
      ->capture_default_str();
  cmd->add_option("--minutes", o->in.minutes, "Planned recording duration, minutes")->capture_default_str();
  cmd->add_flag("--table71", o->table, "Recompute all 8 rows of Table 7.1 and the text's 5.2 TB");
  cmd->add_flag("--json", o->json,
                "Print one JSON object on stdout (the plan, or {rows, five_tb} with --table71)");
  cmd->callback([o, cmd] {
    set_json_mode(o->json);
    if (o->table) {
      const auto rows = design::check_table71();
      design::RecordingPlanInput in = design::plan_input(design::table71()[0]);
      const design::RecordingPlan fives = design::make_plan(in);
      if (o->json) {
        nlohmann::json jr = nlohmann::json::array();
        for (const auto& r : rows)
          jr.push_back({{"option", r.row.option},
                        {"printed_bandwidth_mb_s", r.row.bandwidth_mb_s},
                        {"printed_memory_gb", r.row.memory_gb},
                        {"bandwidth_mib_s", r.plan.camera_mib_per_s},
                        {"memory_gib", r.plan.camera_gib},
                        {"bandwidth_rounded", r.bandwidth},
                        {"memory_rounded", r.memory},
                        {"matches", r.matches},
                        {"fits_bits", r.fits_bits ? nlohmann::json(*r.fits_bits) : nlohmann::json(nullptr)},
                        {"plan", r.plan.to_json()}});
        print_json({{"rows", jr},
                    {"five_tb",
                     {{"cameras", in.cameras},
                      {"tib", fives.rig_bytes / std::pow(2.0, 40)},
                      {"tb", fives.rig_bytes / 1e12},
                      {"tib_for_30_cameras",
                       30 * fives.camera_bytes_per_s * 60 * in.minutes / std::pow(2.0, 40)}}}});
      } else {
        print_table71(rows, fives);
      }
      return;
    }
    design::RecordingPlanInput in = o->in;
    if (o->row) {
      const design::RecordingPlanInput base = design::plan_input(design::table71()[*o->row - 1]);
      auto given = [&](const char* name) { return cmd->get_option(name)->count() > 0; };
      if (!given("--resolution")) in.width = base.width, in.height = base.height;
      if (!given("--bits")) in.bits = base.bits;
      if (!given("--fps")) in.fps = base.fps;
      if (!given("--clock")) in.clock_mhz = base.clock_mhz;
      if (!given("--minutes")) in.minutes = base.minutes;
    }
    if (!o->row || cmd->get_option("--resolution")->count() > 0) {
      const Size2 s = parse_size(o->resolution);
      in.width = s.width;
      in.height = s.height;
    }
    in.device_bytes = design::parse_bytes(o->device_size);
    in.device_rate = design::parse_bytes(o->device_rate);
    const design::RecordingPlan p = design::make_plan(in);
    if (o->json)
      print_json(p.to_json());
    else
      print_plan(p);
    if (!p.feasible()) throw std::runtime_error("the plan does not hold: " + p.failed());
  });
}

}  // namespace omma::app
