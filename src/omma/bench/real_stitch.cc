#include <stdexcept>

#include "omma/bench/real.h"

namespace omma::bench {
std::vector<std::string> real_stitch_pairs() { return {"leuven", "aero", "graf"}; }
nlohmann::json real_stitch(const std::string&, const RealOptions&) {
  throw std::runtime_error("not built yet");
}
}  // namespace omma::bench
