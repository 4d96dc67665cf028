// The Giga-Eye recording planner (thesis ch. 7, Table 7.1, §7.1; ../shared/notes/gigaeye-spec.md §3).
//
// Per camera: bytes/s = W * H * fps * bits / 8 (raw Bayer, packed). Table 7.1 prints bandwidth in
// binary units ("MB/s" = MiB/s = 2^20 B/s) and memory in GiB (2^30 B) for `minutes` of recording,
// rounded half up; decimal units do not reproduce it (row 1 would be 105.8 MB/s, 190.5 GB).
// Cameras share storage devices (`cameras_per_device`, 2 per SSD in the thesis); a plan holds when
//   pixel-clock:        clock_mhz < max_clock_mhz (80 MHz: the cables are noisy above it, L6576-6580)
//   pixel-rate:         clock_mhz * 1e6 >= W * H * fps (the sensor cannot read faster than its clock)
//   device-write-rate:  cameras_per_device * bytes/s <= device sustained write rate
//   device-capacity:    cameras_per_device * bytes/s * duration <= device size
// Sizes and rates are bytes and bytes/s in the API (the CLI takes units, parse_bytes).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace omma::design {

struct RecordingPlanInput {
  int width = 2592, height = 1944;  // output resolution per camera (after skip / window), pixels
  int bits = 12;                    // bits per pixel as stored
  double fps = 9.5;
  double clock_mhz = 66;      // pixel clock
  double max_clock_mhz = 80;  // exclusive limit
  int cameras = 44;
  int cameras_per_device = 2;
  double device_bytes = 128e9;  // capacity of one storage device
  double device_rate = 150e6;   // its sustained write rate, bytes/s
  double minutes = 14;          // planned duration
  bool IsValid(std::string* why = nullptr) const;
};

struct PlanCheck {
  std::string name;  // "pixel-clock", "pixel-rate", "device-write-rate", "device-capacity"
  bool ok = false;
  std::string detail;  // the numbers compared, in words
};

struct RecordingPlan {
  RecordingPlanInput in;
  double camera_bytes_per_s = 0;                    // exact
  double camera_mib_per_s = 0;                      // Table 7.1's "BW (MB/s)"
  double camera_gib = 0;                            // Table 7.1's "Memory (GB)" for in.minutes
  double device_bytes_per_s = 0, device_bytes = 0;  // per device for in.minutes
  int devices = 0;                                  // ceil(cameras / cameras_per_device)
  double rig_bytes_per_s = 0, rig_bytes = 0;        // the whole rig for in.minutes
  double max_minutes = 0;                           // what one device holds at this rate
  std::vector<PlanCheck> checks;
  bool feasible() const;
  std::string failed() const;  // the failed checks' names and details, "; "-separated
  // `omma plan --json` (and omma.plan's dict, which adds "failed"): {"input": {...}, "camera",
  // "device", "rig", "checks": [{"name", "ok", "detail"}], "feasible"}.
  nlohmann::json to_json() const;
};

RecordingPlan make_plan(const RecordingPlanInput& in);  // throws std::invalid_argument if !IsValid

// Round half up to an integer (the table's rounding: row 8's 22.5 prints as 23).
long round_half_up(double x);

// One row of Table 7.1 as printed (thesis L6489-6503).
struct Table71Row {
  int option = 0;
  int observed_w = 0, observed_h = 0;
  std::string skip_bin;
  int bits = 0;
  double clock_mhz = 0;
  double aov_h_deg = 0, aov_v_deg = 0;
  int width = 0, height = 0;
  double fps = 0;
  double minutes = 0;
  int memory_gb = 0, bandwidth_mb_s = 0;  // printed
};
const std::vector<Table71Row>& table71();
RecordingPlanInput plan_input(const Table71Row& row);

// A Table 7.1 row recomputed: matches when both printed figures equal the computed ones rounded
// half up. When a row does not match, `fits_bits` is the bit depth (1..16) that reproduces it, if any.
struct Table71Check {
  Table71Row row;
  RecordingPlan plan;
  long bandwidth = 0, memory = 0;  // rounded
  bool matches = false;
  std::optional<int> fits_bits;
};
std::vector<Table71Check> check_table71();

// "128GB", "128 GiB", "150MB/s", "2.5e9", "1TB" -> bytes (or bytes/s): decimal k, M, G, T and binary
// Ki, Mi, Gi, Ti; a trailing "/s" is accepted. Throws std::invalid_argument on anything else.
double parse_bytes(const std::string& text);

}  // namespace omma::design
