// Progress display for long operations, on stderr. On a terminal it redraws one line; otherwise
// (CI, pipes) it prints a line at every 10 %. Thread-safe: step() may be called from workers.
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <mutex>
#include <string>

namespace omma {

class Progress {
 public:
  Progress(std::string label, size_t total, bool enabled = true);
  ~Progress();
  void step(size_t n = 1);
  void finish();

 private:
  void draw(size_t done, bool final);
  std::string label_;
  size_t total_;
  bool enabled_;
  bool tty_;
  std::atomic<size_t> done_{0};
  std::atomic<int> last_decile_{-1};
  std::mutex mutex_;
  std::chrono::steady_clock::time_point start_, last_draw_;
  bool finished_ = false;
};

// Global quiet switch (set by the CLI's --quiet / --json): disables Progress output.
void set_progress_enabled(bool on);
bool progress_enabled();

}  // namespace omma
