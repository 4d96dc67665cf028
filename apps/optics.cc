// omma optics: placeholder until its issue lands.
#include <stdexcept>

#include "apps/command.h"

namespace omma::app {

void add_optics_command(CLI::App& root) {
  auto* cmd = root.add_subcommand("optics", "Optics, illumination and size-efficiency calculators (not implemented yet)");
  cmd->callback([] { throw std::runtime_error("'omma optics' is not implemented yet"); });
}

}  // namespace omma::app
