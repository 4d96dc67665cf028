// omma design: placeholder until its issue lands.
#include <stdexcept>

#include "apps/command.h"

namespace omma::app {

void add_design_command(CLI::App& root) {
  auto* cmd = root.add_subcommand("design", "Design a dome: place cameras (layered, min-cameras, max-volume, cvt) (not implemented yet)");
  cmd->callback([] { throw std::runtime_error("'omma design' is not implemented yet"); });
}

}  // namespace omma::app
