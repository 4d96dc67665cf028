// omma eval: placeholder until its issue lands.
#include <stdexcept>

#include "apps/command.h"

namespace omma::app {

void add_eval_command(CLI::App& root) {
  auto* cmd = root.add_subcommand("eval", "Compare a panorama with a ground truth (not implemented yet)");
  cmd->callback([] { throw std::runtime_error("'omma eval' is not implemented yet"); });
}

}  // namespace omma::app
