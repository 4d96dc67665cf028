// omma: compound-eye camera toolkit. The command is a table of subcommands over the library.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <iostream>

#include "apps/command.h"
#include "apps/help.h"
#include "omma/core/log.h"
#include "omma/core/progress.h"
#include "omma/core/version.h"

namespace omma::app {

void print_json(const nlohmann::json& j) {
  nlohmann::json out = j;
  if (out.is_object() && !out.contains("omma_version"))
    out["omma_version"] = omma::version();  // who wrote it
  std::cout << out.dump(2) << std::endl;
}

void set_json_mode(bool on) { omma::set_progress_enabled(!on); }

// Pipeline order: rig files, dome design, simulation, ISP, calibration, panorama, engine.
static const CommandEntry kCommands[] = {
    {"rig", add_rig_command},
    {"design", add_design_command},
    {"coverage", add_coverage_command},
    {"sweep", add_sweep_command},
    {"optics", add_optics_command},
    {"plan", add_plan_command},
    {"simulate", add_simulate_command},
    {"link", add_link_command},
    {"isp", add_isp_command},
    {"calibrate", add_calibrate_command},
    {"rig-diff", add_rig_diff_command},
    {"pto", add_pto_command},
    {"real", add_real_command},
    {"refocus", add_refocus_command},
    {"stitch", add_stitch_command},
    {"view3d", add_view3d_command},
    {"eval", add_eval_command},
    {"resolution", add_resolution_command},
    {"render", add_render_command},
    {"record", add_record_command},
    {"recording", add_recording_command},
    {"run", add_run_command},
    {"bench", add_bench_command},
    {"hw", add_hw_command},
    {"meta", add_meta_command},
    {"demo", add_demo_command},
    {"completion", add_completion_command},
};

// Every numeric option of every command takes only what its type holds, checked where the value
// enters: FLOAT options a finite number (CLI11's own parsing and its Range checks let NaN and inf
// through), INT and UINT options a plain decimal integer in range (strtoull reads "-1" as 2^64 - 1,
// base 0 reads "010" as 8 and "0x10" as 16, and an overflow saturates).
void check_numeric_options(CLI::App& app) {
  static const CLI::Validator finite(
      [](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0') return "";  // not a number: CLI11 says so itself
        return std::isfinite(v) ? "" : "must be a finite number, got '" + text + "'";
      },
      "");
  auto integer = [](bool is_signed) {
    return CLI::Validator(
        [is_signed](std::string& text) -> std::string {
          const size_t digits = is_signed && !text.empty() && text[0] == '-' ? 1 : 0;
          if (text.size() == digits ||
              !std::all_of(text.begin() + digits, text.end(), [](char c) { return c >= '0' && c <= '9'; }))
            return "must be a whole number" + std::string(is_signed ? "" : " >= 0") + ", got '" + text + "'";
          // Decimal: "010" is ten (CLI11 would read it as octal).
          const size_t zeros = std::min(text.find_first_not_of('0', digits), text.size() - 1) - digits;
          text.erase(digits, zeros);
          errno = 0;
          if (is_signed)
            (void)std::strtoll(text.c_str(), nullptr, 10);
          else
            (void)std::strtoull(text.c_str(), nullptr, 10);
          return errno == ERANGE ? "'" + text + "' is out of range" : "";
        },
        "");
  };
  static const CLI::Validator whole = integer(true), natural = integer(false);
  for (CLI::Option* opt : app.get_options()) {
    const std::string type = opt->get_type_name();
    if (type.rfind("FLOAT", 0) == 0) opt->check(finite);
    if (type.rfind("INT", 0) == 0) opt->transform(whole);
    if (type.rfind("UINT", 0) == 0) opt->transform(natural);
  }
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) check_numeric_options(*sub);
}

}  // namespace omma::app

int main(int argc, char** argv) {
  CLI::App app{
      "omma: design, calibrate and run compound-eye (multi-camera dome) panoramic cameras.\n"
      "Conventions: dome axis +z, theta polar from +z, phi azimuth from +x; mm and degrees in\n"
      "files and options; pixel centres at integer + 0.5. See README.md."};
  // A file-size limit (ulimit -f) makes a write fail with EFBIG, reported and cleaned up like a full
  // disk, instead of SIGXFSZ killing the process mid-write with its temporaries left behind.
  std::signal(SIGXFSZ, SIG_IGN);
  app.require_subcommand(1);
  bool verbose = false, quiet = false;
  app.add_flag("-v,--verbose", verbose, "More log output (stderr)");
  app.add_flag("-q,--quiet", quiet, "Only warnings and errors on stderr");
  app.set_version_flag("--version", [] { return omma::app::version_text(); });  // made only when asked
  for (const auto& c : omma::app::kCommands) c.add(app);
  omma::app::check_numeric_options(app);
  omma::app::add_examples(app);
  // A mistyped command is named, with the closest one, before CLI11 would answer "A subcommand is
  // required" or "The following arguments were not expected".
  if (const std::string bad = omma::app::unknown_command_error(app, {argv + 1, argv + argc}); !bad.empty()) {
    std::fprintf(stderr, "omma: error: %s\nRun omma --help for more information.\n", bad.c_str());
    return 1;
  }
  omma::init_logging(false, false);
  app.parse_complete_callback([&] {
    spdlog::set_level(verbose ? spdlog::level::debug : quiet ? spdlog::level::warn : spdlog::level::info);
  });
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version (exit code 0) print as CLI11 does; every parse error (unknown or missing
    // option, a value out of range or of the wrong type) is an error like any other: one
    // "omma: error:" line and exit status 1, not CLI11's own codes (105, 106, 114, ...).
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);
    std::fprintf(stderr, "omma: error: %s\nRun with --help for more information.\n", e.what());
    return 1;
  } catch (const omma::app::ExitSilently& e) {
    return e.code;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "omma: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
