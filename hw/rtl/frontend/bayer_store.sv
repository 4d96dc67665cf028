// Bayer frame store between the deserialiser and the demosaic (thesis Fig. 5.4: the camera
// pipeline buffers rows, row_fifo249 of Table 6.5, and frames).
//
// Pixels of the row being decoded go into one of two row buffers (ping-pong); when the
// deserialiser commits a row (intact, inside the frame) that buffer is copied, one pixel per
// cycle, into the frame being assembled, and the other buffer takes the next row. Rows are placed
// by index, so a row decoded twice keeps its last intact copy, and rows never decoded read as 0
// (a per-row "intact" bit masks them): the frame isp::decode_link hands on. At a frame boundary
// with at least one intact row the frame is emitted: the two frame banks swap and the reader
// streams the finished one, row-major, one pixel per cycle with one idle cycle after each row (the
// demosaic's protocol), while the next frame is assembled in the other bank. A frame that ends
// while the reader is still busy is dropped and counted in `overruns`.
//
// Statistics as isp::LinkSummary: frames emitted, intact and damaged rows of emitted frames.
module bayer_store #(
    parameter int WIDTH = 250,
    parameter int HEIGHT = 250,
    parameter int BITS = 10
) (
    input  logic                      clk,
    input  logic                      rst,
    // from link_deser
    input  logic                      pix_we,
    input  logic [$clog2(WIDTH)-1:0]  pix_col,
    input  logic [BITS-1:0]           pix_data,
    input  logic                      row_commit,
    input  logic [$clog2(HEIGHT)-1:0] row_idx,
    input  logic                      frame_end,
    input  logic                      sink_busy,  // the demosaic is still finishing a frame
    // raw frame stream (row-major; row_ok = the row was received intact, else data 0)
    output logic                      raw_valid,
    output logic [BITS-1:0]           raw_data,
    output logic                      raw_row_ok,
    output logic                      raw_last,   // last pixel of the frame
    output logic                      busy,       // copying or reading
    output logic [31:0]               frames,
    output logic [31:0]               rows_ok,
    output logic [31:0]               rows_damaged,
    output logic [31:0]               overruns
);
  localparam int WB = $clog2(WIDTH);
  localparam int HB = $clog2(HEIGHT);
  localparam int NPIX = WIDTH * HEIGHT;
  localparam int FB = $clog2(2 * NPIX);
  localparam int RB = $clog2(2 * WIDTH);

  // ---- row buffers ----
  logic wsel;  // buffer taking the row being decoded
  logic cp_busy, cp_wr, cp_sel;
  logic [WB-1:0] cp_col, cp_wcol;
  logic [HB-1:0] cp_row;
  logic [BITS-1:0] rb_q;
  logic [RB-1:0] rb_waddr, rb_raddr;  // buffer * W + col
  assign rb_waddr = (wsel ? RB'(WIDTH) : RB'(0)) + RB'(pix_col);
  assign rb_raddr = (cp_sel ? RB'(WIDTH) : RB'(0)) + RB'(cp_col);
  ram_sdp #(.WORDS(2 * WIDTH), .BITS(BITS)) rowbuf (
      .clk, .we(pix_we), .waddr(rb_waddr), .wdata(pix_data), .re(cp_busy), .raddr(rb_raddr),
      .rdata(rb_q));

  // ---- frame banks ----
  logic wbank;                     // bank being assembled
  logic [HEIGHT-1:0] row_ok[2];
  logic [HB:0] ok_cnt;             // distinct intact rows of the frame being assembled
  logic fe_pend;
  logic rd_busy, rd_bank, rd_gap;
  logic [WB-1:0] rd_col;
  logic [HB-1:0] rd_row;
  logic [BITS-1:0] fm_q;
  logic fm_re;
  logic [HB-1:0] cp_wrow;
  logic [FB-1:0] fm_waddr, fm_raddr;  // bank * W * H + row * W + col
  assign fm_waddr = (wbank ? FB'(NPIX) : FB'(0)) + FB'(cp_wrow) * FB'(WIDTH) + FB'(cp_wcol);
  assign fm_raddr = (rd_bank ? FB'(NPIX) : FB'(0)) + FB'(rd_row) * FB'(WIDTH) + FB'(rd_col);
  ram_sdp #(.WORDS(2 * NPIX), .BITS(BITS)) frame (
      .clk, .we(cp_wr), .waddr(fm_waddr), .wdata(rb_q), .re(fm_re), .raddr(fm_raddr), .rdata(fm_q));

  assign fm_re = rd_busy && !rd_gap;
  assign busy = cp_busy || cp_wr || rd_busy || fe_pend || frame_end || row_commit;

  // read pipeline: the word arrives one cycle after its address
  logic r1_valid, r1_ok, r1_last;
  always_ff @(posedge clk) begin
    if (rst) begin
      r1_valid <= 1'b0;
      r1_ok <= 1'b0;
      r1_last <= 1'b0;
    end else begin
      r1_valid <= fm_re;
      r1_ok <= row_ok[rd_bank][rd_row];
      r1_last <= fm_re && rd_row == HB'(HEIGHT - 1) && rd_col == WB'(WIDTH - 1);
    end
  end
  assign raw_valid = r1_valid;
  assign raw_data = r1_ok ? fm_q : '0;
  assign raw_row_ok = r1_ok;
  assign raw_last = r1_last;

  always_ff @(posedge clk) begin
    if (rst) begin
      wsel <= 1'b0;
      cp_busy <= 1'b0;
      cp_wr <= 1'b0;
      cp_sel <= 1'b0;
      cp_col <= '0;
      cp_wcol <= '0;
      cp_row <= '0;
      cp_wrow <= '0;
      wbank <= 1'b0;
      row_ok[0] <= '0;
      row_ok[1] <= '0;
      ok_cnt <= '0;
      fe_pend <= 1'b0;
      rd_busy <= 1'b0;
      rd_bank <= 1'b0;
      rd_gap <= 1'b0;
      rd_col <= '0;
      rd_row <= '0;
      frames <= '0;
      rows_ok <= '0;
      rows_damaged <= '0;
      overruns <= '0;
    end else begin
      // copy engine: read the row buffer, write the frame one cycle later
      cp_wr <= cp_busy;
      cp_wcol <= cp_col;
      cp_wrow <= cp_row;
      if (cp_busy) begin
        if (cp_col == WB'(WIDTH - 1)) cp_busy <= 1'b0;
        else cp_col <= cp_col + 1'b1;
      end
      if (row_commit) begin
        cp_busy <= 1'b1;
        cp_sel <= wsel;
        cp_col <= '0;
        cp_row <= row_idx;
        wsel <= !wsel;
        if (!row_ok[wbank][row_idx]) ok_cnt <= ok_cnt + 1'b1;
        row_ok[wbank][row_idx] <= 1'b1;
      end

      // frame boundary, once the last row is in the frame
      if (frame_end) fe_pend <= 1'b1;
      if ((fe_pend || frame_end) && !cp_busy && !cp_wr && !row_commit) begin
        fe_pend <= 1'b0;
        if (ok_cnt != 0) begin
          if (rd_busy || sink_busy) begin
            overruns <= overruns + 1;
          end else begin
            frames <= frames + 1;
            rows_ok <= rows_ok + 32'(ok_cnt);
            rows_damaged <= rows_damaged + 32'(HEIGHT) - 32'(ok_cnt);
            rd_busy <= 1'b1;
            rd_bank <= wbank;
            rd_row <= '0;
            rd_col <= '0;
            rd_gap <= 1'b0;
            wbank <= !wbank;
          end
          row_ok[(rd_busy || sink_busy) ? wbank : !wbank] <= '0;
          ok_cnt <= '0;
        end
      end

      // reader: WIDTH reads, one idle cycle, next row
      if (rd_busy) begin
        if (rd_gap) begin
          rd_gap <= 1'b0;
          if (rd_row == HB'(HEIGHT - 1)) rd_busy <= 1'b0;
          else rd_row <= rd_row + 1'b1;
        end else if (rd_col == WB'(WIDTH - 1)) begin
          rd_col <= '0;
          rd_gap <= 1'b1;
        end else begin
          rd_col <= rd_col + 1'b1;
        end
      end
    end
  end
endmodule
