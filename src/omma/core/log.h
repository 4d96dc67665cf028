// Logging: spdlog to stderr (stdout is reserved for --json output and the command's result).
#pragma once

#include <spdlog/spdlog.h>

namespace omma {
// Sends spdlog's default logger to stderr with a short pattern; level "info" unless verbose/quiet.
void init_logging(bool verbose, bool quiet);
}  // namespace omma
