#include "omma/core/version.h"

#ifndef OMMA_VERSION
#error "OMMA_VERSION is defined by src/omma/core/CMakeLists.txt from the file VERSION"
#endif

namespace omma {

std::string version() { return OMMA_VERSION; }

}  // namespace omma
