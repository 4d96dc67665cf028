// omma link: placeholder until its issue lands.
#include <stdexcept>

#include "apps/command.h"

namespace omma::app {

void add_link_command(CLI::App& root) {
  auto* cmd = root.add_subcommand("link", "Sensor-link serial protocol encoder and decoder (not implemented yet)");
  cmd->callback([] { throw std::runtime_error("'omma link' is not implemented yet"); });
}

}  // namespace omma::app
