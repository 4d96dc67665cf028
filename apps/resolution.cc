// omma resolution: placeholder until its issue lands.
#include <stdexcept>

#include "apps/command.h"

namespace omma::app {

void add_resolution_command(CLI::App& root) {
  auto* cmd = root.add_subcommand("resolution", "USAF 1951 resolution measurement in simulation (not implemented yet)");
  cmd->callback([] { throw std::runtime_error("'omma resolution' is not implemented yet"); });
}

}  // namespace omma::app
