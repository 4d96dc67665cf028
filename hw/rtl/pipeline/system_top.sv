// The chip (thesis Fig. 6.3, Table 6.1): NCAM serial camera links -> NCAM single-camera front ends
// (deserialiser, Bayer store, bilinear demosaic, §5.1.2) -> each camera's RGB565 frame memory
// (§5.2, written at Addr = lw * y + x, eq. 5.27) -> the panorama pipeline core (pano_top) -> the
// §6.3 output stream. serial_data_in[i] is camera i's line sample, one per `chip_valid` cycle.
module system_top
  import omma_hw_pkg::*;
#(
    parameter int NCAM = 24,
    parameter int CAM_W = 250,       // front ends: frame size and link timing (§5.1.3)
    parameter int CAM_H = 250,
    parameter int ROW_GAP_PP = 3,
    parameter int EOF_PP = 4,
    parameter int RESYNC_PP = 250,
    parameter int NPIX = 62500,      // words per camera frame memory
    parameter int II = 3,
    parameter SIN_FILE = "sin_rom.hex",
    parameter COS_FILE = "cos_rom.hex"
) (
    input  logic                clk,
    input  logic                rst,
    // camera links
    input  logic [NCAM-1:0]     serial_data_in,
    input  logic                chip_valid,
    input  logic                flush,
    output logic                cams_busy,     // a front end is still decoding or writing a frame
    output logic [31:0]         cam_frames,    // frames written by camera 0's front end
    // Table 6.6 configuration channels
    input  logic                reg_valid,
    input  logic [31:0]         reg_word,
    input  logic                pp_valid,
    input  logic [31:0]         pp_word,
    input  logic                cs_valid,
    input  logic [31:0]         cs_word,
    input  logic                pv_valid,
    input  logic [31:0]         pv_word,
    output logic                cfg_err,
    output logic [3:0]          cfg_err_code,
    output logic [1:0]          cfg_err_chan,
    output logic [31:0]         cfg_err_index,
    // frame memory load port (testbench, or a DMA): one word per camera per cycle, same address
    input  logic [NCAM-1:0]     load_we,
    input  logic [FAB-1:0]      load_addr,
    input  logic [NCAM*16-1:0]  load_data,
    // panorama
    input  logic                start,
    output logic                busy,
    output logic                pix_valid,
    output logic [15:0]         pix_col,
    output logic [15:0]         pix_row,
    output logic [7:0]          pix_r,
    output logic [7:0]          pix_g,
    output logic [7:0]          pix_b,
    output logic [3:0]          pix_n,
    output logic                pix_boundary,
    output logic                clock_out,
    output logic                de_out,
    output logic                hblank_out,
    output logic                vblank_out,
    output logic [29:0]         data_out,
    output logic                unsupported
);
  localparam int XB = $clog2(CAM_W), YB = $clog2(CAM_H);
  logic [NCAM-1:0] cam_we, fe_busy;
  logic [NCAM*FAB-1:0] cam_waddr;
  logic [NCAM*16-1:0] cam_wdata;
  logic [31:0] frames0;

  genvar i;
  generate
    for (i = 0; i < NCAM; i++) begin : g_cam
      logic done;
      /* verilator lint_off UNUSEDSIGNAL */
      logic raw_valid, raw_row_ok, raw_last, proto_err;
      logic [9:0] raw_data, rgb_r, rgb_g, rgb_b;
      logic [31:0] frames, rows_ok, rows_damaged, overruns;
      /* verilator lint_on UNUSEDSIGNAL */
      logic rgb_valid, fe_b;
      logic [15:0] rgb565;
      logic [XB-1:0] rgb_x;
      logic [YB-1:0] rgb_y;
      single_cam_top #(.WIDTH(CAM_W), .HEIGHT(CAM_H), .BITS(10), .ROW_GAP_PP(ROW_GAP_PP), .EOF_PP(EOF_PP),
                       .RESYNC_PP(RESYNC_PP)) fe (
          .clk, .rst, .chip_valid, .chip(serial_data_in[i]), .flush, .done, .raw_valid, .raw_data, .raw_row_ok,
          .raw_last, .rgb_valid, .rgb_r, .rgb_g, .rgb_b, .rgb565, .rgb_x, .rgb_y, .busy(fe_b), .frames,
          .rows_ok, .rows_damaged, .overruns, .proto_err);
      assign fe_busy[i] = fe_b || (flush && !done);  // after the last chip: until the stream is drained
      always_ff @(posedge clk) begin  // the frame memory write: Addr = lw * y + x (eq. 5.27)
        if (rst) begin
          cam_we[i] <= 1'b0;
          cam_waddr[FAB*i+:FAB] <= '0;
          cam_wdata[16*i+:16] <= '0;
        end else begin
          cam_we[i] <= rgb_valid || load_we[i];
          cam_waddr[FAB*i+:FAB] <= load_we[i] ? load_addr : FAB'(32'(rgb_y) * CAM_W + 32'(rgb_x));
          cam_wdata[16*i+:16] <= load_we[i] ? load_data[16*i+:16] : rgb565;
        end
      end
      if (i == 0) begin : g_count
        assign frames0 = frames;
      end
    end
  endgenerate
  assign cams_busy = |fe_busy || |cam_we;
  assign cam_frames = frames0;

  pano_top #(.NCAM(NCAM), .NPIX(NPIX), .II(II), .SIN_FILE(SIN_FILE), .COS_FILE(COS_FILE)) pano (
      .clk, .rst, .reg_valid, .reg_word, .pp_valid, .pp_word, .cs_valid, .cs_word, .pv_valid, .pv_word, .cfg_err,
      .cfg_err_code, .cfg_err_chan, .cfg_err_index, .load_we(1'b0), .load_addr('0), .load_data('0), .cam_we, .cam_waddr,
      .cam_wdata, .start, .busy, .pix_valid, .pix_col, .pix_row, .pix_r, .pix_g, .pix_b, .pix_n, .pix_boundary,
      .clock_out, .de_out, .hblank_out, .vblank_out, .data_out, .unsupported);
endmodule
