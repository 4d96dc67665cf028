// The panorama grid of a command's --projection and --size, with the defaults every command shares.
#pragma once

#include <string>

#include "omma/core/grid.h"

namespace omma::app {

// --projection NAME and --size WxH (empty: 1080x1080 vr180, 1920x512 equirect (the thesis's grid,
// non-square pixels: no GPano, io/metadata.h), 1920x960 equirect-full, 1920x533 equirect-100 (square
// pixels)). Throws std::invalid_argument on an unknown projection or a malformed size.
PanoGrid grid_from_args(const std::string& projection, const std::string& size);

}  // namespace omma::app
