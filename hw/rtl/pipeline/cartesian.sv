// B2 Cartesian unit (thesis eq. 5.15-5.18, Fig. 5.10; hw::sincos_lookup, hw::cartesian):
// omega from the sin and cos of theta+phi, theta-phi and theta, read from three sets of
// quarter-wave ROMs (2^T words of W bits, uQ1.(W-1)) in parallel:
//   a = S(t+p) + S(t-p) = 2 sin t cos p                       (5.16)
//   b = C(t-p) - C(t+p) = 2 sin t sin p                       (5.17 corrected: the thesis prints
//                                                               -sin(t+p), the identity needs cos)
//   c = 2 C(t)          = 2 cos t                             (5.18)
// The sums of two sQ1.(W-1) values are the halves in sQ1.W: exact. A lookup rounds the M-bit
// angle to T+2 bits (round half up, modulo a full turn); the top two bits are the quadrant.
// axes = 0 (dome): omega = (a, b, c); axes = 1 (vr180): omega = (b, c, a).
// Pipelined: one direction per cycle, latency 3 (address, ROM read, sum).
module cartesian
  import omma_hw_pkg::*;
#(
    parameter SIN_FILE = "sin_rom.hex",
    parameter COS_FILE = "cos_rom.hex"
) (
    input  logic                      clk,
    input  logic                      rst,
    input  logic                      axes,
    input  logic                      in_valid,
    input  logic [M-1:0]              theta,
    input  logic [M-1:0]              phi,
    input  logic [31:0]               in_tag,
    output logic                      out_valid,
    output logic signed [OMEGA_B-1:0] w0,
    output logic signed [OMEGA_B-1:0] w1,
    output logic signed [OMEGA_B-1:0] w2,
    output logic [31:0]               out_tag
);
  localparam int SH = M - T - 2;

  // uQ0.M -> uQ0.(T+2): round half up, modulo a full turn
  function automatic logic [T+1:0] rom_angle(input logic [M-1:0] a);
    /* verilator lint_off UNUSEDSIGNAL */
    logic [M:0] r;  // only the low T+2 bits: modulo a full turn
    /* verilator lint_on UNUSEDSIGNAL */
    if (SH > 0) r = ({1'b0, a} + ((M + 1)'(1) << (SH > 0 ? SH - 1 : 0))) >> SH;
    else r = {1'b0, a};
    rom_angle = r[T+1:0];
  endfunction

  // stage 1: angles and ROM addresses
  logic v1;
  logic [31:0] tag1;
  logic [1:0] q1[3];
  logic [T-1:0] i1[3];
  logic [T+1:0] ra[3];
  always_comb begin
    ra[0] = rom_angle(theta + phi);
    ra[1] = rom_angle(theta - phi);
    ra[2] = rom_angle(theta);
  end
  always_ff @(posedge clk) begin
    if (rst) begin
      v1 <= 1'b0;
      tag1 <= '0;
      for (int k = 0; k < 3; k++) begin
        q1[k] <= '0;
        i1[k] <= '0;
      end
    end else begin
      v1 <= in_valid;
      tag1 <= in_tag;
      for (int k = 0; k < 3; k++) begin
        q1[k] <= ra[k][T+1:T];
        i1[k] <= ra[k][T-1:0];
      end
    end
  end

  // stage 2: three table sets (sin, cos) read in parallel
  logic v2;
  logic [31:0] tag2;
  logic [1:0] q2[3];
  logic [W-1:0] sr[3], cr[3];
  genvar g;
  generate
    for (g = 0; g < 3; g++) begin : g_rom
      ram_sdp #(.WORDS(1 << T), .BITS(W), .INIT_FILE(SIN_FILE)) sin_rom (
          .clk, .we(1'b0), .waddr(T'(0)), .wdata(W'(0)), .re(1'b1), .raddr(i1[g]), .rdata(sr[g]));
      ram_sdp #(.WORDS(1 << T), .BITS(W), .INIT_FILE(COS_FILE)) cos_rom (
          .clk, .we(1'b0), .waddr(T'(0)), .wdata(W'(0)), .re(1'b1), .raddr(i1[g]), .rdata(cr[g]));
    end
  endgenerate
  always_ff @(posedge clk) begin
    if (rst) begin
      v2 <= 1'b0;
      tag2 <= '0;
      for (int k = 0; k < 3; k++) q2[k] <= '0;
    end else begin
      v2 <= v1;
      tag2 <= tag1;
      for (int k = 0; k < 3; k++) q2[k] <= q1[k];
    end
  end

  // stage 3: quadrant signs, sums, axis map
  logic signed [W:0] sn[3], cs[3];  // sQ1.(W-1)
  always_comb begin
    for (int k = 0; k < 3; k++) begin
      unique case (q2[k])
        2'd0: begin sn[k] = $signed({1'b0, sr[k]}); cs[k] = $signed({1'b0, cr[k]}); end
        2'd1: begin sn[k] = $signed({1'b0, cr[k]}); cs[k] = -$signed({1'b0, sr[k]}); end
        2'd2: begin sn[k] = -$signed({1'b0, sr[k]}); cs[k] = -$signed({1'b0, cr[k]}); end
        default: begin sn[k] = -$signed({1'b0, cr[k]}); cs[k] = $signed({1'b0, sr[k]}); end
      endcase
    end
  end
  wire signed [OMEGA_B-1:0] a = OMEGA_B'(sn[0]) + OMEGA_B'(sn[1]);
  wire signed [OMEGA_B-1:0] b = OMEGA_B'(cs[1]) - OMEGA_B'(cs[0]);
  wire signed [OMEGA_B-1:0] c = OMEGA_B'(cs[2]) <<< 1;
  always_ff @(posedge clk) begin
    if (rst) begin
      out_valid <= 1'b0;
      out_tag <= '0;
      w0 <= '0;
      w1 <= '0;
      w2 <= '0;
    end else begin
      out_valid <= v2;
      out_tag <= tag2;
      if (!axes) begin
        w0 <= a;
        w1 <= b;
        w2 <= c;
      end else begin
        w0 <= b;
        w1 <= c;
        w2 <= a;
      end
    end
  end
endmodule
