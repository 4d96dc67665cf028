// omma simulate: placeholder until its issue lands.
#include <stdexcept>

#include "apps/command.h"

namespace omma::app {

void add_simulate_command(CLI::App& root) {
  auto* cmd = root.add_subcommand("simulate", "Render camera frames and ground truth with the dome simulator (not implemented yet)");
  cmd->callback([] { throw std::runtime_error("'omma simulate' is not implemented yet"); });
}

}  // namespace omma::app
