// Integer primitives of the bit-accurate hardware model (docs/hw-model.md §1). Every block of the
// pipeline (blocks.h) is written with these and nothing else: no floating point in the datapath.
//
// Notation: a value v "in Qm.n" stands for v / 2^n; m counts the integer bits including the sign
// for signed formats ("sQm.n") and excluding it for unsigned ones ("uQm.n"). The width is m + n.
//
// Rounding rules (the only three used anywhere in the model):
//   * rshift_round(v, s)  round half up: (v + 2^(s-1)) >> s with an ARITHMETIC shift (floor), so
//                         -2.5 -> -2 and 2.5 -> 3. One adder and wires in RTL.
//   * div_round(n, d)     round half away from zero of n / d, d > 0: sign(n) * floor((2|n| + d) / (2d)).
//                         RTL: a sign-magnitude restoring divider (restoring_divide below).
//   * isqrt_floor(v)      floor(sqrt(v)) for v >= 0. RTL: the restoring (digit-by-digit) square root.
// Each has a plain bit-serial reference (what the RTL iterates) and the fast form the model uses;
// blocks_test.cc (Fixed.BitSerialReferencesAgreeWithFastForms) checks that they agree on random and
// edge inputs.
#pragma once

#include <cstdint>

namespace omma::hw {

// Round half up, arithmetic shift; s >= 0 (s == 0 returns v).
constexpr int64_t rshift_round(int64_t v, int s) { return s <= 0 ? v : (v + (int64_t{1} << (s - 1))) >> s; }

// Changes the number of fractional bits of v from `from` to `to`: exact left shift when widening,
// rshift_round when narrowing.
constexpr int64_t align_frac(int64_t v, int from, int to) {
  return to >= from ? v * (int64_t{1} << (to - from)) : rshift_round(v, from - to);
}

// Floor division for n >= 0, d > 0 (what a restoring divider computes).
constexpr uint64_t udiv_floor(uint64_t n, uint64_t d) { return n / d; }

// Round half away from zero of n / d for d > 0 (sign-magnitude: divide |n|, restore the sign).
constexpr int64_t div_round(int64_t n, int64_t d) {
  const uint64_t a = n < 0 ? static_cast<uint64_t>(-n) : static_cast<uint64_t>(n);
  const int64_t q = static_cast<int64_t>((2 * a + static_cast<uint64_t>(d)) / (2 * static_cast<uint64_t>(d)));
  return n < 0 ? -q : q;
}

// Bit-serial restoring divider: quotient of n / d (n >= 0, d > 0) with `quotient_bits` bits, one
// bit per step from the MSB: partial remainder r <- 2r + next bit of n; if r >= d then r -= d and
// the quotient bit is 1. Returns floor(n / d) provided it fits in quotient_bits (the caller states
// the width and guarantees the quotient fits; higher bits are dropped). Reference for udiv_floor
// (blocks_test.cc checks that the two agree).
uint64_t restoring_divide(uint64_t n, uint64_t d, int quotient_bits, int dividend_bits);

// floor(sqrt(v)), v >= 0 (fast form: double sqrt then exact integer correction).
uint64_t isqrt_floor(uint64_t v);
// Bit-serial restoring square root (two radicand bits per step), the reference for isqrt_floor.
uint64_t isqrt_restoring(uint64_t v, int radicand_bits);

// Number of bits needed to hold v >= 0 (bit_length(0) = 0), i.e. the position of the leading one
// plus one: a leading-zero counter in RTL.
int bit_length(uint64_t v);

// Saturates v into [lo, hi].
constexpr int64_t saturate(int64_t v, int64_t lo, int64_t hi) { return v < lo ? lo : v > hi ? hi : v; }

}  // namespace omma::hw
