#include "omma/core/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace omma {
namespace {
std::atomic<bool> g_enabled{true};
}

void set_progress_enabled(bool on) { g_enabled = on; }
bool progress_enabled() { return g_enabled; }

Progress::Progress(std::string label, size_t total, bool enabled)
    : label_(std::move(label)),
      total_(total == 0 ? 1 : total),
      enabled_(enabled && g_enabled),
      tty_(isatty(fileno(stderr)) != 0),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

Progress::~Progress() { finish(); }

void Progress::step(size_t n) {
  const size_t done = done_ += n;
  if (!enabled_) return;
  if (tty_) {
    const auto now = std::chrono::steady_clock::now();
    std::lock_guard lock(mutex_);
    if (now - last_draw_ < std::chrono::milliseconds(100) && done < total_) return;
    last_draw_ = now;
    draw(done, false);
  } else {
    const int decile = static_cast<int>(10 * done / total_);
    int prev = last_decile_.load();
    while (decile > prev) {
      if (last_decile_.compare_exchange_weak(prev, decile)) {
        std::lock_guard lock(mutex_);
        draw(done, false);
        break;
      }
    }
  }
}

void Progress::finish() {
  std::lock_guard lock(mutex_);
  if (finished_) return;
  finished_ = true;
  if (enabled_ && tty_) {
    draw(total_, true);
    std::fputc('\n', stderr);
  }
}

void Progress::draw(size_t done, bool) {
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double frac = std::min(1.0, static_cast<double>(done) / total_);
  if (tty_) {
    const int bar = 30, filled = static_cast<int>(frac * bar);
    std::fprintf(stderr, "\r%s [%.*s%*s] %3.0f%% %.1fs", label_.c_str(), filled,
                 "##############################", bar - filled, "", 100 * frac, secs);
  } else {
    std::fprintf(stderr, "%s: %3.0f%% (%.1fs)\n", label_.c_str(), 100 * frac, secs);
  }
  std::fflush(stderr);
}

}  // namespace omma
