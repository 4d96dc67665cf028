// omma rig-diff: placeholder until its issue lands.
#include <stdexcept>

#include "apps/command.h"

namespace omma::app {

void add_rig_diff_command(CLI::App& root) {
  auto* cmd = root.add_subcommand("rig-diff", "Compare two rigs (not implemented yet)");
  cmd->callback([] { throw std::runtime_error("'omma rig-diff' is not implemented yet"); });
}

}  // namespace omma::app
