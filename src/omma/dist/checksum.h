// File checksums for job manifests: XXH3-64 (libxxhash), written as "xxh3:<16 hex digits>", the
// digits exactly as `xxhsum -H3 FILE` prints them, so that a manifest can be checked with the
// standard tool. Fast enough (memory speed) to hash every output after it is written.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

namespace omma::dist {

struct FileDigest {
  uint64_t size = 0;         // bytes
  std::string checksum;      // "xxh3:0123456789abcdef"
};

// Reads the whole file. Throws IoError (core/io.h) if it cannot be read.
FileDigest file_digest(const std::filesystem::path& path);
std::string xxh3_hex(const void* data, size_t bytes);  // "xxh3:..." of a buffer

}  // namespace omma::dist
