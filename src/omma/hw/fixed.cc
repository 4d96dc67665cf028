#include "omma/hw/fixed.h"

#include <cmath>

namespace omma::hw {

uint64_t restoring_divide(uint64_t n, uint64_t d, int quotient_bits, int dividend_bits) {
  // Bit-serial long division over the dividend's bits, MSB first. The quotient register has
  // quotient_bits bits; bits above it are dropped (the caller guarantees they are zero).
  uint64_t r = 0, q = 0;
  for (int i = dividend_bits - 1; i >= 0; --i) {
    r = (r << 1) | ((n >> i) & 1u);
    q <<= 1;
    if (r >= d) {
      r -= d;
      q |= 1u;
    }
  }
  return quotient_bits >= 64 ? q : q & ((uint64_t{1} << quotient_bits) - 1);
}

uint64_t isqrt_floor(uint64_t v) {
  if (v == 0) return 0;
  uint64_t s = static_cast<uint64_t>(std::sqrt(static_cast<double>(v)));
  // Exact correction of the double estimate (off by at most one or two near 2^53 and above).
  while (s > 0 && s * s > v) --s;
  while ((s + 1) * (s + 1) <= v) ++s;
  return s;
}

uint64_t isqrt_restoring(uint64_t v, int radicand_bits) {
  // Digit-by-digit square root: two radicand bits per step, one root bit per step.
  if (radicand_bits % 2) ++radicand_bits;
  uint64_t rem = 0, root = 0;
  for (int i = radicand_bits - 2; i >= 0; i -= 2) {
    rem = (rem << 2) | ((v >> i) & 3u);
    const uint64_t trial = (root << 2) | 1u;
    root <<= 1;
    if (rem >= trial) {
      rem -= trial;
      root |= 1u;
    }
  }
  return root;
}

int bit_length(uint64_t v) { return v == 0 ? 0 : 64 - __builtin_clzll(v); }

}  // namespace omma::hw
