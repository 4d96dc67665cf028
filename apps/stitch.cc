// omma stitch: placeholder until its issue lands.
#include <stdexcept>

#include "apps/command.h"

namespace omma::app {

void add_stitch_command(CLI::App& root) {
  auto* cmd = root.add_subcommand("stitch", "Stitch camera frames into a panorama (reference renderer) (not implemented yet)");
  cmd->callback([] { throw std::runtime_error("'omma stitch' is not implemented yet"); });
}

}  // namespace omma::app
