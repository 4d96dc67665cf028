// omma run: placeholder until its issue lands.
#include <stdexcept>

#include "apps/command.h"

namespace omma::app {

void add_run_command(CLI::App& root) {
  auto* cmd = root.add_subcommand("run", "Live panoramic video engine (not implemented yet)");
  cmd->callback([] { throw std::runtime_error("'omma run' is not implemented yet"); });
}

}  // namespace omma::app
