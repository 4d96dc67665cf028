#include "omma/core/checksum.h"

#include <cstdio>
#include <memory>
#include <vector>

#include <fmt/format.h>
#include <xxhash.h>
#include <zlib.h>

#include "omma/core/io.h"

namespace omma {

std::uint32_t crc32(const void* data, std::size_t n, std::uint32_t crc) {
  return static_cast<std::uint32_t>(::crc32_z(crc, static_cast<const Bytef*>(data), n));
}

namespace {
std::string format_hash(XXH64_hash_t h) { return fmt::format("xxh3:{:016x}", static_cast<uint64_t>(h)); }
}  // namespace

std::string xxh3_hex(const void* data, size_t bytes) { return format_hash(XXH3_64bits(data, bytes)); }

FileDigest file_digest(const std::filesystem::path& path) {
  std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) throw IoError("cannot read '" + path.string() + "' to checksum it");
  std::unique_ptr<XXH3_state_t, XXH_errorcode (*)(XXH3_state_t*)> st(XXH3_createState(), &XXH3_freeState);
  XXH3_64bits_reset(st.get());
  std::vector<char> buf(1 << 20);
  FileDigest d;
  for (;;) {
    const size_t n = std::fread(buf.data(), 1, buf.size(), f.get());
    if (n > 0) {
      XXH3_64bits_update(st.get(), buf.data(), n);
      d.size += n;
    }
    if (n < buf.size()) break;
  }
  if (std::ferror(f.get())) throw IoError("error reading '" + path.string() + "' to checksum it");
  d.checksum = format_hash(XXH3_64bits_digest(st.get()));
  return d;
}

}  // namespace omma
