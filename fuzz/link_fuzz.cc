// libFuzzer target for the sensor-link decoder (thesis §5.1.3): any bytes must decode without a
// crash, an out-of-bounds read, undefined behaviour or a hang. The first byte picks a link layout
// (small frames so that the fuzzer reaches deep decoder states); every 4th input also runs the
// thesis default layout. Build and run with fuzz/run.sh.
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "omma/isp/link.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const uint8_t sel = data[0];
  omma::isp::LinkConfig c;
  c.width = 1 + (sel & 7);
  c.height = 1 + ((sel >> 3) & 3);
  c.bits = 4 + ((sel >> 5) & 3) * 2;
  c.row_gap_pp = 3;
  c.eof_pp = 2;
  c.config_pp = 2;
  c.resync_pp = 8;
  long rows = 0;
  auto check = [&](const omma::isp::LinkFrame& f) {
    if (f.pixels.size() != size_t(f.width) * size_t(f.height) || f.row_ok.size() != size_t(f.height)) abort();
    for (uint16_t p : f.pixels)
      if (p >= (1u << c.bits)) abort();
    rows += f.height;
  };
  const omma::isp::LinkSummary st = omma::isp::decode_link(data + 1, size - 1, c, check);
  if (st.rows_ok + st.rows_damaged != rows || st.bytes != size - 1) abort();
  if (sel % 4 == 0) {
    const omma::isp::LinkConfig def;
    omma::isp::decode_link(data + 1, size - 1, def, [](const omma::isp::LinkFrame&) {});
  }
  return 0;
}
