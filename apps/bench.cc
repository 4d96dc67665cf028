// omma bench: placeholder until its issue lands.
#include <stdexcept>

#include "apps/command.h"

namespace omma::app {

void add_bench_command(CLI::App& root) {
  auto* cmd = root.add_subcommand("bench", "Benchmarks against OpenCV (not implemented yet)");
  cmd->callback([] { throw std::runtime_error("'omma bench' is not implemented yet"); });
}

}  // namespace omma::app
