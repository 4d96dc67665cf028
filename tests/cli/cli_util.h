// Helpers for command-line tests: run the built omma binary, capture stdout, stderr and exit code.
#pragma once

#include <sys/types.h>

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

namespace omma::test {

struct RunResult {
  int exit_code = -1;
  std::string out;              // stdout
  std::string err;              // stderr
  nlohmann::json json() const;  // parses `out` as exactly one JSON object (throws otherwise)
};

// Runs a shell command line with a time limit in seconds (stdin closed).
RunResult run_command(const std::string& command, int timeout_s = 300);

// Runs `omma ARGS` (ARGS is passed to /bin/sh, quote as needed) with a time limit in seconds.
RunResult run_omma(const std::string& args, int timeout_s = 300);

// Starts `PREFIX omma ARGS` in the background (ARGS and PREFIX are passed to /bin/sh), stdout and
// stderr to DIR/out and DIR/err, stdin closed; its pid is omma's (the shell execs it), -1 if it
// cannot be started.
pid_t spawn_omma(const std::string& args, const std::filesystem::path& dir, const std::string& prefix = "");

// Waits for a spawn_omma process to end and collects its exit status (128 + signal if killed) and
// its output from DIR/out and DIR/err.
RunResult wait_omma(pid_t pid, const std::filesystem::path& dir);

// A fresh empty temporary folder, removed by the caller (or left in /tmp).
std::filesystem::path temp_dir(const std::string& tag);

std::string data_dir();  // ../shared/data beside the source tree

// A fresh folder (temp_dir(tag)) with rig.json, cam_XX.png (the 15-camera test rig of 64 px cameras
// on a 5 mm dome, testing/test_scenes.h) and truth.png (vr180 128x128) of the far-field louvre.jpg.
std::filesystem::path louvre_frames_folder(const std::string& tag);

// `omma eval --pano PANO --truth TRUTH --json`: its PSNR (dB); a failing eval fails the test.
double eval_psnr(const std::filesystem::path& pano, const std::filesystem::path& truth);

// The whole file as bytes ("" if it cannot be read).
std::string slurp(const std::filesystem::path& path);

// How often `what` occurs in `s` (overlapping occurrences count).
int count(const std::string& s, const std::string& what);

// Does `s` contain `part`?
bool has(const std::string& s, const std::string& part);

// A clear error (gtest expectations): exit status 1, "omma: error:" on stderr, mentioning `part`;
// `what` names the case in a failure.
void expect_error(const RunResult& r, const std::string& part, const std::string& what);

}  // namespace omma::test
