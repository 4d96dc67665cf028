#include <stdexcept>

#include "omma/bench/real.h"

namespace omma::bench {
nlohmann::json real_stereo_calibration(const RealOptions&) { throw std::runtime_error("not built yet"); }
}  // namespace omma::bench
