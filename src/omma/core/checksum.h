// Checksums of bytes written to and read back from files: CRC-32 (zlib) inside binary formats,
// XXH3-64 (libxxhash) of whole files in job manifests.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

namespace omma {

// CRC-32 (ISO-HDLC, as zlib, PNG and gzip) of n bytes, continuing from `crc` (0 to start). It detects
// every error of up to 32 consecutive bits (every single bit flip) with certainty and misses random
// damage with probability 2^-32. zlib computes it at several GB/s.
std::uint32_t crc32(const void* data, std::size_t n, std::uint32_t crc = 0);

// XXH3-64 of a buffer, written as "xxh3:<16 hex digits>", the digits exactly as `xxhsum -H3 FILE`
// prints them, so that a manifest can be checked with the standard tool. Memory speed.
std::string xxh3_hex(const void* data, std::size_t bytes);

struct FileDigest {
  std::uint64_t size = 0;  // bytes
  std::string checksum;    // "xxh3:0123456789abcdef"
};

// Size and XXH3-64 of a whole file. Throws IoError (core/io.h) if it cannot be read.
FileDigest file_digest(const std::filesystem::path& path);

}  // namespace omma
