// libFuzzer target for the compiled-map loader (render/compiled_map.h parse_map): the input is a
// map file without its last 4 bytes, the CRC-32, which the target appends (so that the fuzzer gets
// past the checksum to the structural checks). Any bytes must be refused or give a map whose every
// tap lies inside the frame store with weights summing to 128 (what the renderers rely on); small
// maps are also rendered by a plain scalar loop over a real store. Build and run with fuzz/run.sh.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "omma/core/checksum.h"
#include "omma/render/compiled_map.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::vector<uint8_t> file(data, data + size);
  const uint32_t crc = omma::crc32(file.data(), file.size());
  file.resize(size + 4);
  std::memcpy(file.data() + size, &crc, 4);
  const auto m = omma::render::parse_map(file.data(), file.size());
  if (!m) return 0;
  if (!m->IsValid()) abort();
  const size_t store_bytes = m->layout.bytes();
  std::vector<uint8_t> store(store_bytes <= (size_t(64) << 20) ? store_bytes : 0, 7);
  long long pixels = 0, taps_read = 0, bytes_sum = 0;
  m->visit([&](int col, int row, int n, const omma::render::MapTap* taps) {
    if (col < 0 || col >= m->width || row < 0 || row >= m->height || n < 0 || n > omma::render::kMaxTaps)
      abort();
    int weights = 0;
    for (int i = 0; i < n; ++i) {
      if (taps[i].offset + 16 > store_bytes) abort();
      if (!store.empty()) {  // the 16 bytes the SIMD kernels load
        for (int k = 0; k < 16; ++k) bytes_sum += store[taps[i].offset + k];
        ++taps_read;
      }
      weights += taps[i].weight();
    }
    if (n > 0 && m->method != omma::pano::Method::kSad && weights != 128) abort();
    ++pixels;
  });
  if (pixels != (long long)m->width * m->height || bytes_sum != 7 * 16 * taps_read) abort();
  if (pixels != (long long)m->width * m->height) abort();
  return 0;
}
