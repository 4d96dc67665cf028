// Sampling and deserialisation of one camera's serial link (thesis §5.1.2 "Sampling and
// Deserialization", the stream of §5.1.3): start bit 1, BITS data bits MSB first, stop bit 0, every
// bit XOR the clock; rows separated by ROW_GAP_PP pixel periods of zeros XOR clock; end of frame =
// EOF_PP of constant 0, then the configuration window, then RESYNC_PP of zeros XOR clock.
//
// Input: one line sample ("chip") per `chip_valid` cycle, two samples per bit clock (clock high in
// the first half), exactly the chip stream of src/omma/isp/link.h. One chip is consumed per cycle.
//
// This is the streaming form of isp::decode_link (src/omma/isp/link.cc) and decides exactly as it
// does: the same run-length counters (saturating at the largest threshold), the same row detection
// (a start bit after >= CPP+4 alternating chips), frame boundaries (a constant run of >= half the
// end-of-frame marker, or the long resynchronisation run), row placement by timing relative to the
// last intact row (round half up of distance / row period, kept as an incrementing quotient and
// phase so that no divider is needed) and the first-row slot test. Where the C++ decoder reads a
// pixel ahead, this module keeps a window of CPP+1 chips: position i is decided when chip i+CPP
// arrives (or the stream has ended: `flush`).
//
// Outputs: every decoded pixel of the row in progress (speculative: the store keeps it in a row
// buffer), `row_commit` when a whole row decoded intact inside the frame (its index in `row_idx`),
// and `frame_end` at every frame boundary (isp's finish_frame; the store decides whether the frame
// had intact rows). `done` rises once the flushed stream has been consumed.
module link_deser #(
    parameter int WIDTH = 250,
    parameter int HEIGHT = 250,
    parameter int BITS = 10,
    parameter int ROW_GAP_PP = 3,
    parameter int EOF_PP = 4,
    parameter int RESYNC_PP = 250
) (
    input  logic                      clk,
    input  logic                      rst,
    input  logic                      chip_valid,
    input  logic                      chip,
    input  logic                      flush,
    output logic                      pix_we,
    output logic [$clog2(WIDTH)-1:0]  pix_col,
    output logic [BITS-1:0]           pix_data,
    output logic                      row_commit,
    output logic [$clog2(HEIGHT)-1:0] row_idx,
    output logic                      frame_end,
    output logic                      done
);
  // ---- derived constants (isp::LinkConfig / Decoder) ----
  localparam int CL = BITS + 2;             // clocks per pixel period
  localparam int CPP = 2 * CL;              // chips per pixel period
  localparam int RT = CPP + 4;              // row threshold (alternating run)
  localparam int CT = (EOF_PP * CPP / 2 > 6) ? EOF_PP * CPP / 2 : 6;  // constant-run threshold
  localparam bit LONG_EN = RESYNC_PP >= 4;  // the resync run marks a frame
  localparam int LT = (ROW_GAP_PP + RESYNC_PP / 2) * CPP;              // long-run threshold
  localparam int RP = (ROW_GAP_PP + WIDTH) * CPP;                      // row period in chips
  localparam int HALF = RP / 2;             // RP is even
  localparam int ACAP = ((LT > RT) ? LT : RT) + 1;
  localparam int CCAP = CT + 1;
  localparam int AB = $clog2(ACAP + 1);
  localparam int CB = $clog2(CCAP + 1);
  localparam int PB = $clog2(RP);
  localparam int WB = $clog2(WIDTH);
  localparam int HB = $clog2(HEIGHT);
  localparam int KB = $clog2(WIDTH + 1);
  localparam int SB = $clog2(CPP);

  // Position relative to the anchor (the chip where the last placed row started), d, is kept as
  // qt = floor((d + HALF) / RP) (the rounded row offset) and ph = (d + HALF) mod RP.
  function automatic integer fdiv(input integer a, input integer b);
    fdiv = a / b;
    if (a % b != 0 && a < 0) fdiv = fdiv - 1;
  endfunction
  localparam int X_INIT = -(ROW_GAP_PP * CPP);                 // stream start: row 0 expected here
  localparam int X_CONST = -((RESYNC_PP + ROW_GAP_PP) * CPP);  // end of the end-of-frame run
  localparam int X_COMMIT = (WIDTH - 1) * CPP;                 // last pixel of a row started at d=0
  localparam int QT_INIT = fdiv(X_INIT + HALF, RP), PH_INIT = X_INIT + HALF - QT_INIT * RP;
  localparam int QT_CONST = fdiv(X_CONST + HALF, RP), PH_CONST = X_CONST + HALF - QT_CONST * RP;
  localparam int QT_LONG = fdiv(HALF, RP), PH_LONG = HALF - QT_LONG * RP;
  localparam int QT_COMMIT = fdiv(X_COMMIT + HALF, RP), PH_COMMIT = X_COMMIT + HALF - QT_COMMIT * RP;
  localparam int QMAX = HEIGHT + 1;  // saturation: any row beyond is outside the frame anyway
  localparam int QMIN = (QT_CONST < QT_INIT) ? QT_CONST : QT_INIT;
  localparam int QB = $clog2(((QMAX > -QMIN) ? QMAX : -QMIN) + 1) + 2;  // signed

  // ---- chip window: w[0] = chip i-1, w[1] = chip i, ..., w[CPP] = chip i+CPP-1 ----
  logic [CPP:0] w, vld;
  wire step = vld[1] && (chip_valid || flush);
  wire first = !vld[0];  // position 0: no previous chip

  // ---- state ----
  logic [AB-1:0] alt;   // alternating run ending at chip i-1 (saturating)
  logic [CB-1:0] cst;   // constant run ending at chip i-1
  logic [PB-1:0] ph;
  logic signed [QB-1:0] qt;
  logic [HB-1:0] anchor_idx;
  logic in_const, synced, any_row;
  logic row_act, row_in;
  logic [KB-1:0] pk;    // next pixel of the row (WIDTH: the row is complete)
  logic [SB-1:0] skip;  // chips until that pixel's first chip
  logic [HB-1:0] ridx;
  logic done_r;

  // ---- the pixel at the window: start 1, BITS data, stop 0, each bit two differing chips ----
  logic pix_ok;
  logic [BITS-1:0] pix_val;
  always_comb begin
    pix_ok = vld[CPP];
    for (int b = 0; b < CL; b++)
      if (w[1+2*b] == w[2+2*b]) pix_ok = 1'b0;
    if (!w[2] || w[CPP]) pix_ok = 1'b0;
    for (int b = 1; b <= BITS; b++) pix_val[BITS-b] = w[2+2*b];
  end

  // ---- one step at position i ----
  logic n_in_const, n_synced, n_any_row, n_row_act, n_row_in;
  logic [HB-1:0] n_anchor_idx, n_ridx;
  logic [KB-1:0] n_pk;
  logic [SB-1:0] n_skip;
  logic signed [QB-1:0] qt_i;  // d(i) after this step's anchor events
  logic [PB-1:0] ph_i;
  logic fin, commit, we;
  logic [WB-1:0] wcol;
  logic scan;
  logic signed [QB+HB:0] idx;

  always_comb begin
    n_in_const = in_const;
    n_synced = synced;
    n_any_row = any_row;
    n_row_act = row_act;
    n_row_in = row_in;
    n_anchor_idx = anchor_idx;
    n_ridx = ridx;
    n_pk = pk;
    n_skip = skip;
    qt_i = qt;
    ph_i = ph;
    fin = 1'b0;
    commit = 1'b0;
    we = 1'b0;
    wcol = '0;
    idx = '0;
    scan = 1'b0;

    // -- row in progress (isp take_row's pixel loop) --
    if (row_act) begin
      if (skip != 0) begin
        n_skip = skip - 1'b1;
      end else if (pk == KB'(WIDTH)) begin
        n_row_act = 1'b0;  // row complete: scanning resumes at this chip
        scan = 1'b1;
      end else if (pix_ok) begin
        we = 1'b1;
        wcol = WB'(pk);
        n_pk = pk + 1'b1;
        n_skip = SB'(CPP - 1);
        if (pk == KB'(WIDTH - 1) && row_in) begin
          commit = 1'b1;  // intact row inside the frame: it becomes the anchor
          n_anchor_idx = ridx;
          qt_i = QB'(QT_COMMIT);
          ph_i = PB'(PH_COMMIT);
        end
      end else begin
        n_row_act = 1'b0;  // damaged: scanning resumes at this pixel's first chip
        scan = 1'b1;
      end
    end else begin
      scan = 1'b1;
    end

    // -- the main scan (isp Decoder::run) --
    if (scan && !first) begin
      if (w[1] != w[0]) begin
        if (in_const) begin  // the end-of-frame run is over: row 0 follows the resync pattern
          n_in_const = 1'b0;
          qt_i = QB'(QT_CONST);
          ph_i = PB'(PH_CONST);
          n_anchor_idx = '0;
          n_synced = 1'b1;
        end
      end else begin
        if (!in_const && cst >= CB'(CT - 1)) begin
          n_in_const = 1'b1;
          fin = 1'b1;
        end
        if (!w[1] && alt >= AB'(RT) && vld[2] && w[2]) begin
          // a start bit after the row gap: a row begins at this chip
          if (LONG_EN && alt >= AB'(LT)) begin
            fin = 1'b1;
            qt_i = QB'(QT_LONG);
            ph_i = PB'(PH_LONG);
            n_anchor_idx = '0;
            n_synced = 1'b1;
          end
          if (!n_synced && !any_row) begin  // the first row: in a row slot from the stream start?
            if (ph_i >= PB'(HALF - CPP) && ph_i <= PB'(HALF + CPP)) n_synced = 1'b1;
          end
          n_any_row = 1'b1;
          idx = (QB + HB + 1)'(qt_i) + (QB + HB + 1)'(n_anchor_idx);
          n_row_in = n_synced && idx >= 0 && idx < (QB + HB + 1)'(HEIGHT);
          n_ridx = HB'(idx);
          if (pix_ok) begin
            n_row_act = 1'b1;
            we = 1'b1;
            wcol = '0;
            n_pk = KB'(1);
            n_skip = SB'(CPP - 1);
          end
        end
      end
    end
  end

  wire [PB-1:0] ph_next = (ph_i == PB'(RP - 1)) ? '0 : ph_i + 1'b1;
  wire signed [QB-1:0] qt_next = (ph_i == PB'(RP - 1) && qt_i < $signed(QB'(QMAX))) ? qt_i + 1'b1 : qt_i;

  always_ff @(posedge clk) begin
    pix_we <= 1'b0;
    row_commit <= 1'b0;
    frame_end <= 1'b0;
    if (rst) begin
      w <= '0;
      vld <= '0;
      alt <= AB'(1);
      cst <= CB'(1);
      ph <= PB'(PH_INIT);
      qt <= QB'(QT_INIT);
      anchor_idx <= '0;
      in_const <= 1'b0;
      synced <= 1'b0;
      any_row <= 1'b0;
      row_act <= 1'b0;
      row_in <= 1'b0;
      pk <= '0;
      skip <= '0;
      ridx <= '0;
      done_r <= 1'b0;
      pix_col <= '0;
      pix_data <= '0;
      row_idx <= '0;
    end else begin
      if (chip_valid || step) begin
        w <= {chip, w[CPP:1]};
        vld <= {chip_valid, vld[CPP:1]};
      end
      if (step) begin
        // run lengths ending at chip i (for the next position)
        if (first) begin
          alt <= AB'(1);
          cst <= CB'(1);
        end else if (w[1] != w[0]) begin
          alt <= (alt < AB'(ACAP)) ? alt + 1'b1 : alt;
          cst <= CB'(1);
        end else begin
          alt <= AB'(1);
          cst <= (cst < CB'(CCAP)) ? cst + 1'b1 : cst;
        end
        ph <= ph_next;
        qt <= qt_next;
        anchor_idx <= n_anchor_idx;
        in_const <= n_in_const;
        synced <= n_synced;
        any_row <= n_any_row;
        row_act <= n_row_act;
        row_in <= n_row_in;
        pk <= n_pk;
        skip <= n_skip;
        ridx <= n_ridx;
        pix_we <= we;
        pix_col <= wcol;
        pix_data <= pix_val;
        row_commit <= commit;
        row_idx <= ridx;
        frame_end <= fin;
      end else if (flush && !vld[1] && !done_r) begin
        done_r <= 1'b1;  // end of stream: the last frame is finished
        frame_end <= 1'b1;
      end
    end
  end
  assign done = done_r;
endmodule
