// B3 camera search (thesis §5.4.4, Fig. 5.11; hw::camera_search): NCAM dot products omega . t_i in
// parallel (sQ3.(W+V), exact), the cone test of eq. 2.3 (omega . t >= cos(aov/2), cos shifted left
// by W: exact) and the NCAM-to-log2(NCAM) priority encoder that passes the first MAXC contributing
// cameras in index order, one per cycle: Th = max(1, contributors) cycles per direction, the
// unrolled search of §5.4.4 ("24 parallel dot product operations and 24-to-5 priority encoder").
// A direction with no contributor passes one `empty` item, so that every direction leaves.
module cam_search
  import omma_hw_pkg::*;
#(
    parameter int NCAM = 24,
    parameter int AUXW = 1  // payload passed along with the direction (the MRF neighbours)
) (
    input  logic                      clk,
    input  logic                      rst,
    input  logic                      in_valid,
    input  logic signed [OMEGA_B-1:0] in_w0,
    input  logic signed [OMEGA_B-1:0] in_w1,
    input  logic signed [OMEGA_B-1:0] in_w2,
    input  logic [31:0]               in_tag,
    input  logic [AUXW-1:0]           in_aux,
    output logic                      in_ready,
    input  logic [16*3*NCAM-1:0]      t_flat,     // t_i (sQ1.V x 3) of every camera
    input  logic [16*NCAM-1:0]        cos_flat,   // cos(aov/2)_i (sQ1.V)
    output logic                      out_valid,
    output logic [CAMB-1:0]           out_cam,
    output logic signed [DOT_B-1:0]   out_dot,
    output logic signed [OMEGA_B-1:0] out_w0,
    output logic signed [OMEGA_B-1:0] out_w1,
    output logic signed [OMEGA_B-1:0] out_w2,
    output logic [31:0]               out_tag,
    output logic [AUXW-1:0]           out_aux,
    output logic                      out_last,   // last item of this direction
    output logic                      out_empty,  // no camera sees this direction
    output logic [5:0]                out_cone    // cameras that passed (statistics)
);
  // parallel dot products and cone tests on the incoming direction
  logic [NCAM-1:0] pass;
  logic signed [DOT_B-1:0] dot[NCAM];
  always_comb begin
    for (int i = 0; i < NCAM; i++) begin
      dot[i] = DOT_B'(in_w0 * $signed(t_flat[16*(3*i)+:16])) + DOT_B'(in_w1 * $signed(t_flat[16*(3*i+1)+:16])) +
               DOT_B'(in_w2 * $signed(t_flat[16*(3*i+2)+:16]));
      pass[i] = dot[i] >= (DOT_B'($signed(cos_flat[16*i+:16])) <<< W);
    end
  end

  // the direction being passed on
  logic have;
  logic [NCAM-1:0] rem;
  logic signed [DOT_B-1:0] dots[NCAM];
  logic signed [OMEGA_B-1:0] w0, w1, w2;
  logic [31:0] tag;
  logic [AUXW-1:0] aux;
  logic [3:0] sent;
  logic [5:0] cone;

  // priority encoder: the lowest remaining camera
  logic found;
  logic [CAMB-1:0] idx;
  always_comb begin
    found = 1'b0;
    idx = '0;
    for (int i = NCAM - 1; i >= 0; i--)
      if (rem[i]) begin
        found = 1'b1;
        idx = CAMB'(i);
      end
  end
  logic [NCAM-1:0] rem_next;
  always_comb begin
    rem_next = rem;
    if (found) rem_next[idx] = 1'b0;
  end
  wire is_last = !found || rem_next == '0 || {1'b0, sent} + 5'd1 >= 5'(MAXC);
  assign in_ready = !have || is_last;

  function automatic logic [5:0] popcount(input logic [NCAM-1:0] m);
    popcount = '0;
    for (int i = 0; i < NCAM; i++) popcount = popcount + 6'(m[i]);
  endfunction

  always_ff @(posedge clk) begin
    out_valid <= 1'b0;
    if (rst) begin
      have <= 1'b0;
      rem <= '0;
      sent <= '0;
      cone <= '0;
      w0 <= '0;
      w1 <= '0;
      w2 <= '0;
      tag <= '0;
      aux <= '0;
      out_aux <= '0;
      for (int i = 0; i < NCAM; i++) dots[i] <= '0;
      out_cam <= '0;
      out_dot <= '0;
      out_w0 <= '0;
      out_w1 <= '0;
      out_w2 <= '0;
      out_tag <= '0;
      out_last <= 1'b0;
      out_empty <= 1'b0;
      out_cone <= '0;
    end else begin
      if (have) begin
        out_valid <= 1'b1;
        out_cam <= idx;
        out_dot <= dots[idx];
        out_w0 <= w0;
        out_w1 <= w1;
        out_w2 <= w2;
        out_tag <= tag;
        out_aux <= aux;
        out_last <= is_last;
        out_empty <= !found;
        out_cone <= cone;
        rem <= rem_next;
        sent <= sent + 1'b1;
        if (is_last) have <= 1'b0;
      end
      if (in_valid && in_ready) begin
        have <= 1'b1;
        rem <= pass;
        sent <= '0;
        cone <= popcount(pass);
        for (int i = 0; i < NCAM; i++) dots[i] <= dot[i];
        w0 <= in_w0;
        w1 <= in_w1;
        w2 <= in_w2;
        tag <= in_tag;
        aux <= in_aux;
      end
    end
  end
endmodule
