// omma isp: placeholder until its issue lands.
#include <stdexcept>

#include "apps/command.h"

namespace omma::app {

void add_isp_command(CLI::App& root) {
  auto* cmd = root.add_subcommand("isp", "Single-camera ISP: demosaicing, white balance, vignetting (not implemented yet)");
  cmd->callback([] { throw std::runtime_error("'omma isp' is not implemented yet"); });
}

}  // namespace omma::app
