#include "omma/core/checksum.h"

#include <zlib.h>

namespace omma {

std::uint32_t crc32(const void* data, std::size_t n, std::uint32_t crc) {
  return static_cast<std::uint32_t>(::crc32_z(crc, static_cast<const Bytef*>(data), n));
}

}  // namespace omma
