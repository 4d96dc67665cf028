#include "apps/grid_args.h"

namespace omma::app {

PanoGrid grid_from_args(const std::string& projection, const std::string& size) {
  PanoGrid grid;
  grid.projection = parse_projection(projection);
  if (size.empty()) {
    grid.width = grid.projection == Projection::kVr180 ? 1080 : 1920;
    grid.height = grid.projection == Projection::kVr180         ? 1080
                  : grid.projection == Projection::kEquirect    ? 512
                  : grid.projection == Projection::kEquirect100 ? 533
                                                                : 960;
  } else {
    const Size2 s = parse_size(size);
    grid.width = s.width;
    grid.height = s.height;
  }
  return grid;
}

}  // namespace omma::app
