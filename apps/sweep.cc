// omma sweep: placeholder until its issue lands.
#include <stdexcept>

#include "apps/command.h"

namespace omma::app {

void add_sweep_command(CLI::App& root) {
  auto* cmd = root.add_subcommand("sweep", "Parameter sweeps (thesis Fig. 3.3, 3.7, 3.9) (not implemented yet)");
  cmd->callback([] { throw std::runtime_error("'omma sweep' is not implemented yet"); });
}

}  // namespace omma::app
