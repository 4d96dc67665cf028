// omma demo --rig gigaeye-44: the Giga-Eye end to end (thesis ch. 7).
#pragma once

#include <string>

namespace omma::app {

struct GigaDemoOptions {
  std::string out = "omma-giga-demo";
  // Far field: the lake photograph beside the checkout when it is there (calibration needs its
  // texture; the checker sphere gives too few matches), else a textured sphere 50 m away.
  std::string scene;
  std::string mode = "skip3";      // sensor mode of the simulated recording (648 x 486: quick)
  std::string size = "9000x2400";  // 21.6 MP, Table 7.4
  std::string perturb = "orient=0.3,focal=0.01,center=2";
  int frame_sets = 3;
  unsigned seed = 1;
  bool json = false;
};

void run_giga_demo(const GigaDemoOptions& o);

}  // namespace omma::app
