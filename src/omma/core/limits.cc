#include "omma/core/limits.h"

#include <stdexcept>

#include <fmt/format.h>

namespace omma {

void check_image_size(std::int64_t width, std::int64_t height, const std::string& what) {
  if (width < 1 || height < 1 || width > kMaxImageSide || height > kMaxImageSide ||
      width * height > kMaxImagePixels)
    throw std::invalid_argument(fmt::format("{} {}x{} is out of range (1..{} pixels a side, at most {} pixels)",
                                            what, width, height, kMaxImageSide, kMaxImagePixels));
}

}  // namespace omma
