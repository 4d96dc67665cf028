// B6 pixel value unit and B7 object-boundary unit (thesis §5.4.1 "Pixel Intensity value
// generation", §5.4.5; hw::bilinear_sample, block_float, reciprocal_weights, blend, gray_level,
// boundary_unit; docs/hw-model.md §4 B6-B8). Per contributor (one per cycle, with the four RGB565
// words of its quad from the frame memory): expand to 8 bits (or keep 5/6/5 with
// EXPAND_AT_OUTPUT), bilinear sample per channel (uQ8.S, round half up), keep it with its
// distance. At the direction's last contributor the pixel is made:
//   nn:     the nearest camera (strict <, lowest index wins ties), weight 1
//   linear: D_i = d_i normalised to MW bits (block floating, m 2^e), w_i = floor(2^(R+MW-2) / m_i)
//           >> (e_i - e_min) (the reciprocal, a restoring divider), out = round(sum w s / sum w)
//   boundary (enabled, >= 2 contributors): gray Y = rs(77 R + 150 G + 29 B, 8) of the nearest and
//           the farthest camera's samples; |dY| > th 2^S -> pure green (the marker of §5.4.5).
// Vignetting (hw::vignetting_gain): each sample is multiplied by rs(radial * channel, 14) unless that
// is exactly 1.0, and saturated at the channel's maximum.
//   mrf:    as linear on the MRF evidence D_i = d(u) prod d(v) of the cameras that see all four
//           neighbours (contrib_unit; weight 0 for the others; the prior alone if none does)
// method 3 does not exist: `unsupported` rises.
module pixel_value
  import omma_hw_pkg::*;
  import omma_arith_pkg::*;
(
    input  logic         clk,
    input  logic         rst,
    input  logic [1:0]   method,      // 0 nn, 1 linear, 2 mrf
    input  logic         boundary_en,
    input  logic [7:0]   boundary_th,
    input  logic         in_valid,
    input  logic         in_tap,
    input  logic [17:0]  in_dist,
    input  logic [MW-1:0] in_ev_m,     // MRF evidence (contrib_unit), block floating
    input  logic signed [7:0] in_ev_e,
    input  logic         in_ev_complete,
    input  logic [F-1:0] in_fx,
    input  logic [F-1:0] in_fy,
    input  logic [31:0]  in_tag,
    input  logic         in_last,
    input  logic [15:0]  q0,
    input  logic [15:0]  q1,
    input  logic [15:0]  q2,
    input  logic [15:0]  q3,
    input  logic [15:0]  vig_radial,  // uQ2.14 radial gain of this contributor's pixel
    input  logic [47:0]  vig_channel, // uQ2.14 R, G, B gains of its camera ([15:0] R)
    output logic         out_valid,
    output logic [31:0]  out_tag,
    output logic [7:0]   out_r,
    output logic [7:0]   out_g,
    output logic [7:0]   out_b,
    output logic [3:0]   out_n,       // valid contributors of this pixel
    output logic         out_boundary,
    output logic         out_mrf_fallback,  // mrf: no camera complete, the prior alone
    output logic         unsupported
);
  localparam int NS = MAXC;
  localparam int IW = NS > 1 ? $clog2(NS) : 1;  // slot index bits
  // worst-case widths (see contrib_unit): a sample, a gain, the weighted sums
  localparam int SMPB = 8 + S + 2;                 // uQ8.S sample (signed container)
  localparam int GB = 2 * 16 - VIGF + 2;           // rs(radial * channel, 14)
  localparam int NB = R + SMPB + 3, DB = R + 3;    // sum of <= 8 products w * s, sum of <= 8 weights

  function automatic logic [7:0] chan(input logic [15:0] w, input integer ch);
    logic [7:0] f;
    if (ch == 0) f = {3'b0, w[15:11]};
    else if (ch == 1) f = {2'b0, w[10:5]};
    else f = {3'b0, w[4:0]};
    if (EXPAND_AT_OUTPUT != 0) chan = f;
    else if (ch == 1) chan = {f[5:0], f[5:4]};  // G8 = G6 << 2 | G6 >> 4
    else chan = {f[4:0], f[4:2]};               // R8 = R5 << 3 | R5 >> 2
  endfunction

  function automatic logic signed [63:0] max_of(input integer ch);
    if (EXPAND_AT_OUTPUT != 0) max_of = ch == 1 ? 63 : 31;
    else max_of = 255;
  endfunction

  // bilinear sample of the current contributor (uQ8.S)
  logic signed [63:0] smp[3];
  always_comb begin
    logic signed [63:0] one, v, g;
    one = $signed(64'(1)) <<< F;
    for (int ch = 0; ch < 3; ch++) begin
      v = $signed(64'(chan(q0, ch))) * (one - $signed(64'(in_fx))) * (one - $signed(64'(in_fy))) +
          $signed(64'(chan(q1, ch))) * $signed(64'(in_fx)) * (one - $signed(64'(in_fy))) +
          $signed(64'(chan(q2, ch))) * (one - $signed(64'(in_fx))) * $signed(64'(in_fy)) + $signed(64'(chan(q3, ch))) * $signed(64'(in_fx)) * $signed(64'(in_fy));
      smp[ch] = sx(rs(zx(v, 8 + 2 * F + 4), 2 * F - S), SMPB);
      // vignetting: g = rs(radial * channel, 14); the sample is scaled unless g is exactly 1.0
      g = sx(rs($signed(64'(vig_radial)) * $signed(64'(vig_channel[16*ch+:16])), VIGF), GB);
      if (g != (1 << VIGF)) smp[ch] = sx(smin(rs(sx(smp[ch] * g, SMPB + GB), VIGF), max_of(ch) <<< S), SMPB);
    end
  end

  // contributors of the direction so far
  logic [3:0] n;
  logic [17:0] sdist[NS];
  logic [MW-1:0] sev_m[NS];
  logic signed [7:0] sev_e[NS];
  logic [NS-1:0] sev_c;
  logic signed [63:0] ssmp[NS][3];

  // the pixel, from the stored contributors plus the current one
  logic [3:0] cn;
  logic [17:0] cd[NS];
  logic [MW-1:0] cev_m[NS];
  logic signed [7:0] cev_e[NS];
  logic [NS-1:0] cev_c;
  logic pfallback;
  logic signed [63:0] cs[NS][3];
  logic [7:0] pr, pg, pb;
  logic pbound;
  always_comb begin
    logic signed [63:0] wt[NS];
    logic signed [63:0] num, den, emin, e[NS];
    logic [63:0] m[NS];
    integer bl;
    logic [IW-1:0] best, nearest, farthest;
    logic ovf;
    logic [63:0] qw;
    logic first;
    logic signed [63:0] px[3], gray[NS], diff;
    bl = 0;
    ovf = 1'b0;
    qw = '0;
    first = 1'b1;
    num = 0;
    den = 0;
    diff = 0;
    for (int ch = 0; ch < 3; ch++) px[ch] = 0;
    for (int i = 0; i < NS; i++) gray[i] = 0;
    cn = n;
    for (int i = 0; i < NS; i++) begin
      cd[i] = sdist[i];
      cev_m[i] = sev_m[i];
      cev_e[i] = sev_e[i];
      cev_c[i] = sev_c[i];
      for (int ch = 0; ch < 3; ch++) cs[i][ch] = ssmp[i][ch];
    end
    if (in_tap && 32'(n) < NS) begin
      cd[IW'(n)] = in_dist;
      cev_m[IW'(n)] = in_ev_m;
      cev_e[IW'(n)] = in_ev_e;
      cev_c[IW'(n)] = in_ev_complete;
      for (int ch = 0; ch < 3; ch++) cs[IW'(n)][ch] = smp[ch];
      cn = n + 1'b1;
    end
    // weights
    for (int i = 0; i < NS; i++) begin
      wt[i] = 0;
      m[i] = 0;
      e[i] = 0;
    end
    best = '0;
    for (int i = 1; i < NS; i++)
      if (i < 32'(cn) && cd[i] < cd[best]) best = IW'(i);
    emin = 0;
    pfallback = 1'b0;
    if (method == 2'd0) begin
      wt[best] = 1;
    end else begin
      // D_i: the MRF evidence of the complete cameras (weight 0 for the others), or, for linear and
      // when no camera is complete, d_i normalised (hw::block_float)
      for (int i = 0; i < NS; i++)
        if (i < 32'(cn)) begin
          bl = bitlen($unsigned(64'(cd[i])));
          if (bl >= MW) m[i] = $unsigned(64'(cd[i])) >> (bl - MW);
          else m[i] = $unsigned(64'(cd[i])) << (MW - bl);
          e[i] = $signed(64'(bl)) - $signed(64'(MW));
        end
      if (method == 2'd2) begin
        if ((cev_c & ((NS)'(1) << cn) - 1'b1) != '0) begin
          for (int i = 0; i < NS; i++)
            if (i < 32'(cn)) begin
              m[i] = cev_c[i] ? $unsigned(64'(cev_m[i])) : '0;
              e[i] = $signed(64'(cev_e[i]));
            end
        end else begin
          pfallback = 1'b1;
        end
      end
      // the reciprocal unit: e_min over the non-zero mantissas, w = floor(2^(R+MW-2) / m) >> (e - e_min)
      first = 1'b1;
      for (int i = 0; i < NS; i++)
        if (i < 32'(cn) && m[i] != 0 && (first || e[i] < emin)) begin
          emin = e[i];
          first = 1'b0;
        end
      for (int i = 0; i < NS; i++)
        if (i < 32'(cn) && m[i] != 0) begin
          {ovf, qw} = udiv($unsigned(64'(1)) << (R + MW - 2), m[i], R, R + MW - 1, MW);
          wt[i] = sx($signed(qw), R + 1);
          if (e[i] - emin >= 64) wt[i] = 0;
          else wt[i] = wt[i] >>> (e[i] - emin);
        end
    end
    // blend
    for (int ch = 0; ch < 3; ch++) begin
      logic [63:0] q;
      q = 0;
      num = 0;
      den = 0;
      for (int i = 0; i < NS; i++)
        if (i < 32'(cn)) begin
          num = sx(num + wt[i] * cs[i][ch], NB);
          den = sx(den + wt[i], DB);
        end
      if (den == 0) begin
        px[ch] = 0;
      end else begin
        {ovf, q} = udiv($unsigned(64'(2 * num + (den <<< S))), $unsigned(64'(den <<< (S + 1))), 10, NB + 2,
                        DB + S + 1);
        px[ch] = ovf ? max_of(ch) : smin($signed(64'(q)), max_of(ch));
      end
    end
    if (EXPAND_AT_OUTPUT != 0) begin
      pr = {px[0][4:0], px[0][4:2]};
      pg = {px[1][5:0], px[1][5:4]};
      pb = {px[2][4:0], px[2][4:2]};
    end else begin
      pr = px[0][7:0];
      pg = px[1][7:0];
      pb = px[2][7:0];
    end
    // boundary unit
    pbound = 1'b0;
    nearest = '0;
    farthest = '0;
    for (int i = 0; i < NS; i++) gray[i] = sx(rs(77 * cs[i][0] + 150 * cs[i][1] + 29 * cs[i][2], 8), SMPB + 2);
    for (int i = 1; i < NS; i++)
      if (i < 32'(cn)) begin
        if (cd[i] < cd[nearest]) nearest = IW'(i);
        if (cd[i] > cd[farthest]) farthest = IW'(i);
      end
    diff = gray[farthest] - gray[nearest];
    if (diff < 0) diff = -diff;
    if (boundary_en && 32'(cn) >= 2 && diff > ($signed(64'(boundary_th)) <<< S)) begin
      pbound = 1'b1;
      pr = 8'd0;
      pg = 8'd255;
      pb = 8'd0;
    end
  end

  always_ff @(posedge clk) begin
    out_valid <= 1'b0;
    if (rst) begin
      n <= '0;
      for (int i = 0; i < NS; i++) begin
        sdist[i] <= '0;
        for (int ch = 0; ch < 3; ch++) ssmp[i][ch] <= '0;
      end
      out_tag <= '0;
      out_r <= '0;
      out_g <= '0;
      out_b <= '0;
      out_n <= '0;
      out_boundary <= 1'b0;
      out_mrf_fallback <= 1'b0;
      unsupported <= 1'b0;
      for (int i = 0; i < NS; i++) begin
        sev_m[i] <= '0;
        sev_e[i] <= '0;
      end
      sev_c <= '0;
    end else begin
      if (method == 2'd3) unsupported <= 1'b1;
      if (in_valid) begin
        if (in_last) begin
          out_valid <= 1'b1;
          out_tag <= in_tag;
          out_r <= pr;
          out_g <= pg;
          out_b <= pb;
          out_n <= cn;
          out_boundary <= pbound;
          out_mrf_fallback <= pfallback && 32'(cn) != 0;
          n <= '0;
        end else if (in_tap && 32'(n) < NS) begin
          sdist[IW'(n)] <= in_dist;
          sev_m[IW'(n)] <= in_ev_m;
          sev_e[IW'(n)] <= in_ev_e;
          sev_c[IW'(n)] <= in_ev_complete;
          for (int ch = 0; ch < 3; ch++) ssmp[IW'(n)][ch] <= smp[ch];
          n <= n + 1'b1;
        end
      end
    end
  end
endmodule
