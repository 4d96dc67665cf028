// One camera's front end (thesis §5.1.2, Fig. 5.4): serial link deserialiser -> Bayer frame store
// -> bilinear demosaic -> RGB and RGB565 pixels (what the panorama's frame memory stores, §5.2).
// The raw stream between the store and the demosaic is brought out for verification.
module single_cam_top #(
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
    output logic                      done,
    output logic                      raw_valid,
    output logic [BITS-1:0]           raw_data,
    output logic                      raw_row_ok,
    output logic                      raw_last,
    output logic                      rgb_valid,
    output logic [BITS-1:0]           rgb_r,
    output logic [BITS-1:0]           rgb_g,
    output logic [BITS-1:0]           rgb_b,
    output logic [15:0]               rgb565,
    output logic [$clog2(WIDTH)-1:0]  rgb_x,
    output logic [$clog2(HEIGHT)-1:0] rgb_y,
    output logic                      busy,
    output logic [31:0]               frames,
    output logic [31:0]               rows_ok,
    output logic [31:0]               rows_damaged,
    output logic [31:0]               overruns,
    output logic                      proto_err
);
  logic pix_we, row_commit, frame_end, store_busy, dm_busy;
  logic [$clog2(WIDTH)-1:0] pix_col;
  logic [BITS-1:0] pix_data;
  logic [$clog2(HEIGHT)-1:0] row_idx;

  link_deser #(.WIDTH(WIDTH), .HEIGHT(HEIGHT), .BITS(BITS), .ROW_GAP_PP(ROW_GAP_PP),
               .EOF_PP(EOF_PP), .RESYNC_PP(RESYNC_PP)) deser (
      .clk, .rst, .chip_valid, .chip, .flush, .pix_we, .pix_col, .pix_data, .row_commit, .row_idx,
      .frame_end, .done);

  bayer_store #(.WIDTH(WIDTH), .HEIGHT(HEIGHT), .BITS(BITS)) store (
      .clk, .rst, .pix_we, .pix_col, .pix_data, .row_commit, .row_idx, .frame_end,
      .sink_busy(dm_busy), .raw_valid, .raw_data, .raw_row_ok, .raw_last, .busy(store_busy),
      .frames, .rows_ok, .rows_damaged, .overruns);

  demosaic_bilinear #(.WIDTH(WIDTH), .HEIGHT(HEIGHT), .BITS(BITS)) demosaic (
      .clk, .rst, .in_valid(raw_valid), .in_data(raw_data), .out_valid(rgb_valid), .out_r(rgb_r),
      .out_g(rgb_g), .out_b(rgb_b), .out_rgb565(rgb565), .out_x(rgb_x), .out_y(rgb_y),
      .busy(dm_busy), .proto_err);

  assign busy = store_busy || dm_busy;
endmodule
