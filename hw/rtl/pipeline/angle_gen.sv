// B1 angle generation (thesis eq. 5.11-5.14, Fig. 5.10; hw::angles_at): two M-bit accumulators.
// theta starts at theta_min and grows by k_theta per row, phi restarts at phi_min at each row and
// grows by k_phi per pixel; both wrap modulo 2^M (the natural overflow of the registers, eq. 5.13).
// The host loads k_phi as the two's complement of the column step: the panorama's column angle
// decreases to the right (omma's conventions.h (G1)/(G2), an unmirrored panorama), and the wrap
// makes that a subtraction with no extra logic.
// Rows top to bottom, columns left to right (§5.4: "starting from the top left corner").
// One direction per II cycles at most (II = 3: the thesis's Cartesian unit with three table sets,
// §5.4.4), and only while `issue_ok` (room downstream).
module angle_gen
  import omma_hw_pkg::*;
#(
    parameter int II = 3
) (
    input  logic         clk,
    input  logic         rst,
    input  logic         start,
    input  logic [M-1:0] theta_min,
    input  logic [M-1:0] k_theta,
    input  logic [M-1:0] phi_min,
    input  logic [M-1:0] k_phi,
    input  logic [15:0]  rows,
    input  logic [15:0]  cols,
    input  logic         issue_ok,
    output logic         valid,
    output logic [M-1:0] theta,
    output logic [M-1:0] phi,
    output logic [15:0]  col,
    output logic [15:0]  row,
    output logic         last,
    output logic         busy
);
  localparam int IB = (II > 1) ? $clog2(II) : 1;
  logic run;
  logic [M-1:0] th_acc, ph_acc;
  logic [15:0] c, r;
  logic [IB-1:0] wait_cnt;
  wire issue = run && issue_ok && wait_cnt == '0;

  always_ff @(posedge clk) begin
    valid <= 1'b0;
    last <= 1'b0;
    if (rst) begin
      run <= 1'b0;
      th_acc <= '0;
      ph_acc <= '0;
      c <= '0;
      r <= '0;
      wait_cnt <= '0;
      theta <= '0;
      phi <= '0;
      col <= '0;
      row <= '0;
    end else begin
      if (wait_cnt != '0) wait_cnt <= wait_cnt - 1'b1;
      if (start && !run) begin
        run <= rows != 0 && cols != 0;
        th_acc <= theta_min;
        ph_acc <= phi_min;
        c <= '0;
        r <= '0;
        wait_cnt <= '0;
      end else if (issue) begin
        valid <= 1'b1;
        theta <= th_acc;
        phi <= ph_acc;
        col <= c;
        row <= r;
        wait_cnt <= IB'(II - 1);
        if (c == cols - 1'b1) begin
          c <= '0;
          ph_acc <= phi_min;
          th_acc <= th_acc + k_theta;
          r <= r + 1'b1;
          if (r == rows - 1'b1) begin
            last <= 1'b1;
            run <= 1'b0;
          end
        end else begin
          c <= c + 1'b1;
          ph_acc <= ph_acc + k_phi;
        end
      end
    end
  end
  assign busy = run;
endmodule
