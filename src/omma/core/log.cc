#include "omma/core/log.h"

#include <spdlog/sinks/stdout_color_sinks.h>

namespace omma {
void init_logging(bool verbose, bool quiet) {
  auto logger = spdlog::stderr_color_mt("omma");
  logger->set_pattern("%^[%l]%$ %v");
  logger->set_level(verbose ? spdlog::level::debug : quiet ? spdlog::level::warn : spdlog::level::info);
  spdlog::set_default_logger(logger);
}
}  // namespace omma
