// omma coverage: placeholder until its issue lands.
#include <stdexcept>

#include "apps/command.h"

namespace omma::app {

void add_coverage_command(CLI::App& root) {
  auto* cmd = root.add_subcommand("coverage", "Coverage analysis of a rig (not implemented yet)");
  cmd->callback([] { throw std::runtime_error("'omma coverage' is not implemented yet"); });
}

}  // namespace omma::app
