#include "omma/design/recording_plan.h"

#include <cctype>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "omma/core/valid.h"

namespace omma::design {

bool RecordingPlanInput::IsValid(std::string* why) const {
  if (width <= 0 || height <= 0 || width > 65536 || height > 65536)
    return invalid(why,
                   fmt::format("resolution {}x{} must be positive (at most 65536 per side)", width, height));
  if (bits < 1 || bits > 16) return invalid(why, fmt::format("bits per pixel {} must be 1..16", bits));
  if (!(fps > 0 && fps <= 10000)) return invalid(why, "frame rate must be in (0, 10000] fps");
  if (!(clock_mhz > 0 && clock_mhz < 1e5))
    return invalid(why, "pixel clock must be a positive number of MHz");
  if (!(max_clock_mhz > 0)) return invalid(why, "the clock limit must be positive");
  if (cameras < 1 || cameras > 100000) return invalid(why, "cameras must be 1..100000");
  if (cameras_per_device < 1 || cameras_per_device > cameras)
    return invalid(why, fmt::format("cameras per device must be 1..{} (the number of cameras)", cameras));
  if (!(device_bytes > 0 && std::isfinite(device_bytes))) return invalid(why, "device size must be positive");
  if (!(device_rate > 0 && std::isfinite(device_rate)))
    return invalid(why, "device write rate must be positive");
  if (!(minutes > 0 && minutes < 1e7)) return invalid(why, "duration must be a positive number of minutes");
  return true;
}

long round_half_up(double x) { return static_cast<long>(std::floor(x + 0.5)); }

nlohmann::json RecordingPlan::to_json() const {
  nlohmann::json checks_json = nlohmann::json::array();
  for (const auto& c : checks) checks_json.push_back({{"name", c.name}, {"ok", c.ok}, {"detail", c.detail}});
  return {
      {"input",
       {{"width", in.width},
        {"height", in.height},
        {"bits", in.bits},
        {"fps", in.fps},
        {"clock_mhz", in.clock_mhz},
        {"max_clock_mhz", in.max_clock_mhz},
        {"cameras", in.cameras},
        {"cameras_per_device", in.cameras_per_device},
        {"device_bytes", in.device_bytes},
        {"device_rate_bytes_per_s", in.device_rate},
        {"minutes", in.minutes}}},
      {"camera", {{"bytes_per_s", camera_bytes_per_s}, {"mib_per_s", camera_mib_per_s}, {"gib", camera_gib}}},
      {"device",
       {{"bytes_per_s", device_bytes_per_s}, {"bytes", device_bytes}, {"max_minutes", max_minutes}}},
      {"rig",
       {{"devices", devices},
        {"bytes_per_s", rig_bytes_per_s},
        {"bytes", rig_bytes},
        {"tib", rig_bytes / std::pow(2.0, 40)},
        {"tb", rig_bytes / 1e12}}},
      {"checks", checks_json},
      {"feasible", feasible()}};
}

bool RecordingPlan::feasible() const {
  for (const PlanCheck& c : checks)
    if (!c.ok) return false;
  return true;
}

std::string RecordingPlan::failed() const {
  std::string s;
  for (const PlanCheck& c : checks)
    if (!c.ok) s += (s.empty() ? "" : "; ") + c.name + ": " + c.detail;
  return s;
}

RecordingPlan make_plan(const RecordingPlanInput& in) {
  if (std::string why; !in.IsValid(&why)) throw std::invalid_argument("plan: " + why);
  RecordingPlan p;
  p.in = in;
  const double pixels_per_s = double(in.width) * in.height * in.fps;
  p.camera_bytes_per_s = pixels_per_s * in.bits / 8;
  p.camera_mib_per_s = p.camera_bytes_per_s / (1 << 20);
  const double seconds = in.minutes * 60;
  p.camera_gib = p.camera_bytes_per_s * seconds / (1 << 30);
  p.device_bytes_per_s = in.cameras_per_device * p.camera_bytes_per_s;
  p.device_bytes = p.device_bytes_per_s * seconds;
  p.devices = (in.cameras + in.cameras_per_device - 1) / in.cameras_per_device;
  p.rig_bytes_per_s = in.cameras * p.camera_bytes_per_s;
  p.rig_bytes = p.rig_bytes_per_s * seconds;
  p.max_minutes = in.device_bytes / p.device_bytes_per_s / 60;
  p.checks.push_back(
      {"pixel-clock", in.clock_mhz < in.max_clock_mhz,
       fmt::format("{:g} MHz {} the {:g} MHz limit of long camera cables", in.clock_mhz,
                   in.clock_mhz < in.max_clock_mhz ? "is below" : "is not below", in.max_clock_mhz)});
  p.checks.push_back(
      {"pixel-rate", in.clock_mhz * 1e6 >= pixels_per_s,
       fmt::format("{:.2f} Mpixel/s needed, {:g} MHz clock", pixels_per_s / 1e6, in.clock_mhz)});
  p.checks.push_back(
      {"device-write-rate", p.device_bytes_per_s <= in.device_rate,
       fmt::format("{} camera(s) per device write {:.1f} MB/s ({:.1f} MiB/s), the device sustains "
                   "{:.1f} MB/s",
                   in.cameras_per_device, p.device_bytes_per_s / 1e6, p.device_bytes_per_s / (1 << 20),
                   in.device_rate / 1e6)});
  p.checks.push_back({"device-capacity", p.device_bytes <= in.device_bytes,
                      fmt::format("{:g} min need {:.1f} GB per device, it holds {:.1f} GB ({:.2f} min)",
                                  in.minutes, p.device_bytes / 1e9, in.device_bytes / 1e9, p.max_minutes)});
  return p;
}

const std::vector<Table71Row>& table71() {
  // Thesis L6489-6503, verbatim (notes §3).
  static const std::vector<Table71Row> rows = {
      {1, 2592, 1944, "0-0", 12, 96, 53, 43, 2592, 1944, 14, 30, 177, 101},
      {2, 2592, 1944, "0-0", 12, 66, 53, 43, 2592, 1944, 9.5, 14, 56, 68},
      {3, 2592, 1944, "1-1", 12, 86, 53, 43, 1296, 972, 30, 30, 95, 54},
      {4, 2592, 1944, "1-0", 12, 66, 53, 43, 1296, 972, 30, 30, 95, 54},
      {5, 2592, 1944, "1-0", 12, 66, 53, 43, 1296, 972, 30, 17, 54, 54},
      {6, 2592, 1944, "1-0", 8, 66, 53, 43, 1296, 972, 30, 30, 63, 36},
      {7, 2592, 1944, "2-0", 8, 36, 53, 43, 864, 648, 30, 30, 28, 16},
      {8, 1024, 768, "0-0", 12, 46, 21, 16, 1024, 768, 30, 30, 40, 23},
  };
  return rows;
}

RecordingPlanInput plan_input(const Table71Row& row) {
  RecordingPlanInput in;
  in.width = row.width;
  in.height = row.height;
  in.bits = row.bits;
  in.fps = row.fps;
  in.clock_mhz = row.clock_mhz;
  in.minutes = row.minutes;
  return in;
}

std::vector<Table71Check> check_table71() {
  std::vector<Table71Check> out;
  for (const Table71Row& row : table71()) {
    Table71Check c;
    c.row = row;
    c.plan = make_plan(plan_input(row));
    c.bandwidth = round_half_up(c.plan.camera_mib_per_s);
    c.memory = round_half_up(c.plan.camera_gib);
    c.matches = c.bandwidth == row.bandwidth_mb_s && c.memory == row.memory_gb;
    if (!c.matches)
      for (int b = 1; b <= 16 && !c.fits_bits; ++b) {
        RecordingPlanInput in = plan_input(row);
        in.bits = b;
        const RecordingPlan p = make_plan(in);
        if (round_half_up(p.camera_mib_per_s) == row.bandwidth_mb_s &&
            round_half_up(p.camera_gib) == row.memory_gb)
          c.fits_bits = b;
      }
    out.push_back(c);
  }
  return out;
}

double parse_bytes(const std::string& text) {
  size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    throw std::invalid_argument("'" + text + "' is not a size (e.g. 128GB, 128GiB, 150MB/s)");
  }
  std::string unit;
  for (size_t i = used; i < text.size(); ++i)
    if (!std::isspace(static_cast<unsigned char>(text[i]))) unit += text[i];
  if (unit.size() >= 2 && unit.compare(unit.size() - 2, 2, "/s") == 0) unit.resize(unit.size() - 2);
  double scale = 0;
  if (unit.empty() || unit == "B")
    scale = 1;
  else if (unit == "kB" || unit == "KB")
    scale = 1e3;
  else if (unit == "MB")
    scale = 1e6;
  else if (unit == "GB")
    scale = 1e9;
  else if (unit == "TB")
    scale = 1e12;
  else if (unit == "KiB")
    scale = 1024.0;
  else if (unit == "MiB")
    scale = 1024.0 * 1024;
  else if (unit == "GiB")
    scale = 1024.0 * 1024 * 1024;
  else if (unit == "TiB")
    scale = 1024.0 * 1024 * 1024 * 1024;
  if (scale == 0 || !(v > 0) || !std::isfinite(v))
    throw std::invalid_argument("'" + text +
                                "' is not a positive size (units B, kB, MB, GB, TB, KiB, MiB, GiB, TiB)");
  return v * scale;
}

}  // namespace omma::design
