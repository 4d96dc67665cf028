// The integer primitives of the hardware model (src/omma/hw/fixed.h, docs/hw-model.md §1) as
// SystemVerilog functions: round half up by an arithmetic shift, the restoring divider and the
// restoring square root. Functions take 64-bit operands; synthesis trims the bits that are
// constant (sign extensions of narrower registers).
package omma_arith_pkg;

  // rshift_round: (v + 2^(s-1)) >>> s, round half up (s = 0: v).
  function automatic logic signed [63:0] rs(input logic signed [63:0] v, input integer s);
    if (s <= 0) rs = v;
    else rs = (v + ($signed(64'(1)) <<< (s - 1))) >>> s;
  endfunction

  // align_frac: from `a` to `b` fraction bits; exact left shift or rs.
  function automatic logic signed [63:0] align(input logic signed [63:0] v, input integer a, input integer b);
    if (b >= a) align = v <<< (b - a);
    else align = rs(v, a - b);
  endfunction

  // v sign-extended from its low n bits, v zero-extended from its low n bits. The callers use them
  // where the value is known to fit (worst case over the inputs' widths), so the value does not
  // change; they let the synthesizer see the width (everything else is written in 64 bits).
  function automatic logic signed [63:0] sx(input logic signed [63:0] v, input integer n);
    sx = (v <<< (64 - n)) >>> (64 - n);
  endfunction
  function automatic logic [63:0] zx(input logic [63:0] v, input integer n);
    zx = (n >= 64) ? v : v & (($unsigned(64'(1)) << n) - 1);
  endfunction

  // Restoring (shift-subtract) divider, n >= 0 (nbn bits), d > 0 (nbd bits): {ovf, floor(n / d)}
  // with qb quotient bits; ovf when the quotient needs more than qb bits (the caller saturates).
  // One compare-subtract per quotient bit, MSB first: hw::restoring_divide, unrolled.
  function automatic logic [64:0] udiv(input logic [63:0] n, input logic [63:0] d, input integer qb,
                                       input integer nbn, input integer nbd);
    logic [63:0] r, q, dd;
    logic ovf;
    r = zx(n, nbn);
    dd = zx(d, nbd);
    q = '0;
    ovf = (qb + nbd < 64) && (r >= (dd << qb));
    for (integer i = 63; i >= 0; i = i - 1) begin
      if (i < qb && i + nbd < 64 && r >= (dd << i)) begin
        r = zx(r - (dd << i), nbd + i);  // the remainder is below d << i
        q = q | ($unsigned(64'(1)) << i);
      end
    end
    udiv = {ovf, q};
  endfunction

  // floor(sqrt(v)) of an nb-bit radicand: restoring square root, two radicand bits per step
  // (hw::isqrt_restoring); the partial remainder never exceeds nb/2 + 4 bits.
  function automatic logic [63:0] isqrt(input logic [63:0] v, input integer nb);
    logic [63:0] rem, root, trial;
    rem = '0;
    root = '0;
    for (integer i = 31; i >= 0; i = i - 1) if (2 * i < nb) begin
      rem = zx((rem << 2) | ((v >> (2 * i)) & $unsigned(64'(3))), (nb + 1) / 2 + 4);
      trial = (root << 2) | $unsigned(64'(1));
      root = root << 1;
      if (rem >= trial) begin
        rem = rem - trial;
        root = root | $unsigned(64'(1));
      end
    end
    isqrt = root;
  endfunction

  // Number of bits of v (the leading-one position + 1; 0 for 0): a leading-zero counter.
  function automatic integer bitlen(input logic [63:0] v);
    bitlen = 0;
    for (integer i = 0; i < 64; i = i + 1)
      if (v[i]) bitlen = i + 1;
  endfunction

  function automatic logic signed [63:0] smin(input logic signed [63:0] a, input logic signed [63:0] b);
    smin = a < b ? a : b;
  endfunction
  function automatic logic signed [63:0] smax(input logic signed [63:0] a, input logic signed [63:0] b);
    smax = a > b ? a : b;
  endfunction
endpackage
