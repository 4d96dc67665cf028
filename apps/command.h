// The omma command line: a table of subcommands (main.cc), one file per subcommand.
// Each file defines one `void add_<name>_command(CLI::App& root)` that adds its subcommand with
// its options and a callback. Conventions every subcommand follows:
//   * --json prints exactly one JSON object on stdout (print_json); logs and progress go to stderr.
//   * Errors are thrown as exceptions (std::exception); main prints "omma: error: ..." and exits 1.
//   * Output files are written atomically (omma/core/io.h).
#pragma once

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

namespace omma::app {

// Prints `j` as one JSON object on stdout (pretty-printed, newline-terminated).
void print_json(const nlohmann::json& j);

// Command-wide flags set by main: true when the current subcommand was given --json.
// Subcommands with --json should call set_json_mode(true) in their callback so that
// progress output is silenced.
void set_json_mode(bool on);

// Thrown by a command that fails on a process whose error another process reports (ranks other
// than 0 under mpirun): main exits with `code` and prints nothing.
struct ExitSilently {
  int code = 1;
};

using AddCommand = void (*)(CLI::App& root);
struct CommandEntry {
  const char* name;
  AddCommand add;
};

// One per subcommand file.
void add_rig_command(CLI::App& root);
void add_design_command(CLI::App& root);
void add_coverage_command(CLI::App& root);
void add_sweep_command(CLI::App& root);
void add_optics_command(CLI::App& root);
void add_simulate_command(CLI::App& root);
void add_stitch_command(CLI::App& root);
void add_view3d_command(CLI::App& root);
void add_eval_command(CLI::App& root);
void add_resolution_command(CLI::App& root);
void add_demo_command(CLI::App& root);
void add_link_command(CLI::App& root);
void add_isp_command(CLI::App& root);
void add_calibrate_command(CLI::App& root);
void add_rig_diff_command(CLI::App& root);
void add_pto_command(CLI::App& root);
void add_real_command(CLI::App& root);
void add_refocus_command(CLI::App& root);
void add_run_command(CLI::App& root);
void add_bench_command(CLI::App& root);
void add_plan_command(CLI::App& root);
void add_render_command(CLI::App& root);
void add_record_command(CLI::App& root);
void add_recording_command(CLI::App& root);
void add_hw_command(CLI::App& root);
void add_meta_command(CLI::App& root);

}  // namespace omma::app
