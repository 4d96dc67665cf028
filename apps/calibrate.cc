// omma calibrate: placeholder until its issue lands.
#include <stdexcept>

#include "apps/command.h"

namespace omma::app {

void add_calibrate_command(CLI::App& root) {
  auto* cmd = root.add_subcommand("calibrate", "Calibrate a rig from camera frames (not implemented yet)");
  cmd->callback([] { throw std::runtime_error("'omma calibrate' is not implemented yet"); });
}

}  // namespace omma::app
