// omma pto: placeholder until its issue lands.
#include <stdexcept>

#include "apps/command.h"

namespace omma::app {

void add_pto_command(CLI::App& root) {
  auto* cmd = root.add_subcommand("pto", "Hugin PTO import and export (not implemented yet)");
  cmd->callback([] { throw std::runtime_error("'omma pto' is not implemented yet"); });
}

}  // namespace omma::app
