// Bilinear Bayer demosaic, RGGB ((row 0, col 0) = R), thesis eq. 5.1-5.10 and Fig. 5.7: two line
// buffers build a 3x3 sliding window, a sum generator forms the cross, diagonal, horizontal and
// vertical sums with unsigned adders, and the divisions by 2 and 4 are shifts. The shifts round
// half up ((s + 1) >> 1, (s + 2) >> 2), the rule of isp::demosaic (src/omma/isp/demosaic.h), so
// the output is bit-identical to it; borders are mirrored without repeating the edge pixel
// (reflect-101: row -1 -> row 1), as isp does.
//
// Protocol: a frame arrives row-major, WIDTH pixels per row in consecutive or gapped `in_valid`
// cycles, with at least one idle cycle after each row (the window emits the row's last pixel then)
// and, after the last row, at least WIDTH + 1 idle cycles (the last output row is made from the
// line buffers: `busy` is high until it is out). `proto_err` latches if a pixel arrives when the
// module cannot take it.
//
// Output: one RGB pixel per `out_valid`, row-major, BITS per channel, with its coordinates, and the
// RGB565 word of §5.2 (the 8 most significant bits of each channel, then 5/6/5 of those).
module demosaic_bilinear #(
    parameter int WIDTH = 250,
    parameter int HEIGHT = 250,
    parameter int BITS = 10
) (
    input  logic                      clk,
    input  logic                      rst,
    input  logic                      in_valid,
    input  logic [BITS-1:0]           in_data,
    output logic                      out_valid,
    output logic [BITS-1:0]           out_r,
    output logic [BITS-1:0]           out_g,
    output logic [BITS-1:0]           out_b,
    output logic [15:0]               out_rgb565,
    output logic [$clog2(WIDTH)-1:0]  out_x,
    output logic [$clog2(HEIGHT)-1:0] out_y,
    output logic                      busy,
    output logic                      proto_err
);
  localparam int WB = $clog2(WIDTH);
  localparam int HB = $clog2(HEIGHT + 1);

  // line buffers: lb_a = the previous input row, lb_b = the one before it
  logic [BITS-1:0] lb_a[WIDTH];
  logic [BITS-1:0] lb_b[WIDTH];

  typedef struct packed {
    logic [BITS-1:0] u, c, d;  // up, centre, down rows of one column
  } col_t;
  col_t win1, win2;  // columns x-2 and x-1 relative to the column being shifted in

  logic [HB-1:0] n;     // input row (HEIGHT: the flush row)
  logic [WB-1:0] cx;    // column being shifted in
  logic bubble;         // the cycle after a row: emit its last pixel
  logic flushing;       // shifting the last output row in from the line buffers
  logic flush_done;     // the flush row is in: its bubble ends the frame

  // the column shifted in this cycle
  col_t t;
  logic shift;
  always_comb begin
    shift = flushing || (in_valid && !bubble);
    t.c = lb_a[cx];
    if (flushing) begin  // rows H-2, H-1, H-2 (reflect)
      t.u = lb_b[cx];
      t.d = lb_b[cx];
    end else if (n == HB'(1)) begin  // row -1 = row 1
      t.u = in_data;
      t.d = in_data;
    end else begin
      t.u = lb_b[cx];
      t.d = in_data;
    end
  end

  // the 3x3 window of the pixel emitted this cycle (left, centre, right columns)
  col_t wl, wc, wr;
  logic emit;
  logic [WB-1:0] ex;
  always_comb begin
    emit = 1'b0;
    ex = '0;
    wl = win1;
    wc = win2;
    wr = t;
    if (bubble) begin  // last column: right = column W-2 (reflect)
      emit = 1'b1;
      ex = WB'(WIDTH - 1);
      wl = win1;
      wc = win2;
      wr = win1;
    end else if (shift && n != 0 && cx != 0) begin
      emit = 1'b1;
      ex = cx - 1'b1;
      wl = (cx == WB'(1)) ? t : win1;  // column -1 = column 1
    end
  end

  // sum generator and output selection (eq. 5.1-5.10)
  wire [HB-1:0] ey = n - 1'b1;
  wire [BITS+1:0] s_cross = (BITS + 2)'(wc.u) + (BITS + 2)'(wc.d) + (BITS + 2)'(wl.c) + (BITS + 2)'(wr.c);
  wire [BITS+1:0] s_diag = (BITS + 2)'(wl.u) + (BITS + 2)'(wr.u) + (BITS + 2)'(wl.d) + (BITS + 2)'(wr.d);
  wire [BITS:0] s_horiz = (BITS + 1)'(wl.c) + (BITS + 1)'(wr.c);
  wire [BITS:0] s_vert = (BITS + 1)'(wc.u) + (BITS + 1)'(wc.d);
  wire [BITS-1:0] cross4 = BITS'((s_cross + (BITS + 2)'(2)) >> 2);  // G(B13), G(R7)       (5.5)
  wire [BITS-1:0] diag4 = BITS'((s_diag + (BITS + 2)'(2)) >> 2);    // R(B13), B(R7)       (5.1), (5.8)
  wire [BITS-1:0] horiz2 = BITS'((s_horiz + (BITS + 1)'(1)) >> 1);  // R(G8), B(G12)       (5.3), (5.10)
  wire [BITS-1:0] vert2 = BITS'((s_vert + (BITS + 1)'(1)) >> 1);    // R(G12), B(G8)       (5.4), (5.9)
  logic [BITS-1:0] r, g, b;
  always_comb begin
    unique case ({ey[0], ex[0]})
      2'b00: begin r = wc.c; g = cross4; b = diag4; end    // R site (5.2)
      2'b01: begin r = horiz2; g = wc.c; b = vert2; end    // G on a red row (5.6)
      2'b10: begin r = vert2; g = wc.c; b = horiz2; end    // G on a blue row
      default: begin r = diag4; g = cross4; b = wc.c; end  // B site (5.7)
    endcase
  end

  always_ff @(posedge clk) begin
    out_valid <= 1'b0;
    if (rst) begin
      n <= '0;
      cx <= '0;
      bubble <= 1'b0;
      flushing <= 1'b0;
      flush_done <= 1'b0;
      proto_err <= 1'b0;
      out_r <= '0;
      out_g <= '0;
      out_b <= '0;
      out_rgb565 <= '0;
      out_x <= '0;
      out_y <= '0;
      win1 <= '0;
      win2 <= '0;
    end else begin
      if (in_valid && (bubble || flushing)) proto_err <= 1'b1;
      if (emit) begin
        out_valid <= 1'b1;
        out_r <= r;
        out_g <= g;
        out_b <= b;
        out_rgb565 <= {r[BITS-1-:5], g[BITS-1-:6], b[BITS-1-:5]};
        out_x <= ex;
        out_y <= ey[$clog2(HEIGHT)-1:0];
      end
      if (shift) begin
        win1 <= win2;
        win2 <= t;
        if (!flushing) begin
          lb_a[cx] <= in_data;
          lb_b[cx] <= lb_a[cx];
        end
        if (cx == WB'(WIDTH - 1)) begin
          cx <= '0;
          if (flushing) begin
            flushing <= 1'b0;
            flush_done <= 1'b1;
            bubble <= 1'b1;
          end else if (n == 0) begin
            n <= HB'(1);  // row 0 is only buffered
          end else begin
            bubble <= 1'b1;
          end
        end else begin
          cx <= cx + 1'b1;
        end
      end
      // the row counter advances after the bubble, so that the bubble's pixel is on row n - 1
      if (bubble) begin
        bubble <= 1'b0;
        if (flush_done) begin
          flush_done <= 1'b0;
          n <= '0;  // frame done
        end else if (n == HB'(HEIGHT - 1)) begin
          n <= HB'(HEIGHT);
          flushing <= 1'b1;  // output row H-1 from the line buffers
        end else begin
          n <= n + 1'b1;
        end
      end
    end
  end
  assign busy = n != 0 || bubble || flushing;
endmodule
