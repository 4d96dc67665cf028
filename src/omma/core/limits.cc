#include "omma/core/limits.h"

#include <stdexcept>

#include <fmt/format.h>

namespace omma {

namespace {
void check_size(std::int64_t width, std::int64_t height, const std::string& what, std::int64_t side,
                std::int64_t pixels) {
  if (width < 1 || height < 1 || width > side || height > side || width * height > pixels)
    throw std::invalid_argument(
        fmt::format("{} {}x{} is out of range (1..{} pixels a side, at most {} pixels)", what, width, height,
                    side, pixels));
}
}  // namespace

void check_image_size(std::int64_t width, std::int64_t height, const std::string& what) {
  check_size(width, height, what, kMaxImageSide, kMaxImagePixels);
}

void check_banded_size(std::int64_t width, std::int64_t height, const std::string& what) {
  check_size(width, height, what, kMaxBandedSide, kMaxBandedPixels);
}

}  // namespace omma
