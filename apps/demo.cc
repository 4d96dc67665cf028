// omma demo: placeholder until its issue lands.
#include <stdexcept>

#include "apps/command.h"

namespace omma::app {

void add_demo_command(CLI::App& root) {
  auto* cmd = root.add_subcommand("demo", "The main job: simulate, stitch, evaluate, report (not implemented yet)");
  cmd->callback([] { throw std::runtime_error("'omma demo' is not implemented yet"); });
}

}  // namespace omma::app
