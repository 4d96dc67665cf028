#include "omma/testing/real_data.h"

#include <cstdlib>

namespace omma::testing {

std::filesystem::path opencv_samples_dir() {
  const char* env = std::getenv("OMMA_OPENCV_SAMPLES");
  std::filesystem::path dir = env && *env ? env : "/usr/share/doc/opencv-doc/examples/data";
  std::error_code ec;
  return std::filesystem::exists(dir / "aloeL.jpg", ec) ? dir : std::filesystem::path{};
}

}  // namespace omma::testing
