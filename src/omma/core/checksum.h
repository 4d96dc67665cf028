// Checksums of bytes written to and read back from files (zlib's CRC-32).
#pragma once

#include <cstddef>
#include <cstdint>

namespace omma {

// CRC-32 (ISO-HDLC, as zlib, PNG and gzip) of n bytes, continuing from `crc` (0 to start). It detects
// every error of up to 32 consecutive bits (every single bit flip) with certainty and misses random
// damage with probability 2^-32. zlib computes it at several GB/s.
std::uint32_t crc32(const void* data, std::size_t n, std::uint32_t crc = 0);

}  // namespace omma
