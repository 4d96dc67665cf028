// The panorama pipeline core (thesis Fig. 5.9, 5.13, 5.15): configuration registers (Table 6.6
// channels) -> B1 angle generation -> B2 Cartesian unit -> direction FIFO -> B3 camera search with
// the priority encoder -> distance, projection and tap address per contributor -> B5 frame
// memories -> B6 pixel value unit with B7's boundary marker -> B8 output stream (§6.3).
//
// Timing: the angle generator issues one direction per II cycles (3: the thesis's Cartesian unit
// with three table sets); the search passes max(1, n) contributors per direction, one per cycle;
// everything after it takes one contributor per cycle without stalls. The direction FIFO lets a
// direction with few contributors lend its spare cycles to one with many.
module pano_top
  import omma_hw_pkg::*;
#(
    parameter int NCAM = 24,
    parameter int NPIX = 62500,  // words per camera frame memory
    parameter int II = 3,
    parameter SIN_FILE = "sin_rom.hex",
    parameter COS_FILE = "cos_rom.hex"
) (
    input  logic                clk,
    input  logic                rst,
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
    // frame memory load port (RGB565, camera bits on top of the address)
    input  logic                load_we,
    input  logic [CAMB+FAB-1:0] load_addr,
    input  logic [15:0]         load_data,
    // run one panorama (needs pano_cs = 1)
    input  logic                start,
    output logic                busy,
    // panorama pixels (raster order) and the §6.3 video signals
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
  localparam int PPW = PIX_POS_WORDS, CSW = CAM_SEARCH_WORDS;

  // ---- configuration ----
  logic [15:0] row_cnt, col_cnt, frame_w, frame_h;
  logic [M-1:0] theta_min, k_theta, phi_min, k_phi;
  /* verilator lint_off UNUSEDSIGNAL */
  logic [1:0] axes;  // bit 1 (columns wrap) only matters to the MRF neighbours, not built
  /* verilator lint_on UNUSEDSIGNAL */
  logic [1:0] method;
  logic pano_cs;
  logic [8:0] boundary_ctrl;
  logic [16*PPW*NCAM-1:0] pp_flat;
  logic [16*CSW*NCAM-1:0] cs_flat;
  /* verilator lint_off UNUSEDSIGNAL */
  logic [31:0] words_taken;  // for a status register / the waveform
  logic ag_busy;
  logic [5:0] sr_cone;      // cameras passing the cone test (statistics)
  /* verilator lint_on UNUSEDSIGNAL */
  config_regs #(.NCAM(NCAM)) cfg (
      .clk, .rst, .reg_valid, .reg_word, .pp_valid, .pp_word, .cs_valid, .cs_word, .pv_valid, .pv_word,
      .row_cnt, .col_cnt, .theta_min, .k_theta, .phi_min, .k_phi, .frame_w, .frame_h, .axes, .pano_cs,
      .method, .boundary_ctrl, .pp_flat, .cs_flat, .cfg_err, .err_code(cfg_err_code),
      .err_chan(cfg_err_chan), .err_index(cfg_err_index), .words_taken);

  // ---- B1 + B2 ----
  localparam int FD = 8;  // direction FIFO depth
  logic [3:0] fifo_cnt, inflight;
  logic ag_valid, ag_last;
  logic [M-1:0] ag_theta, ag_phi;
  logic [15:0] ag_col;
  /* verilator lint_off UNUSEDSIGNAL */
  logic [15:0] ag_row;  // 15 bits travel in the tag (rows < 32768)
  /* verilator lint_on UNUSEDSIGNAL */
  wire issue_ok = 32'(fifo_cnt) + 32'(inflight) + 1 < FD;
  angle_gen #(.II(II)) ag (
      .clk, .rst, .start(start && pano_cs), .theta_min, .k_theta, .phi_min, .k_phi, .rows(row_cnt),
      .cols(col_cnt), .issue_ok, .valid(ag_valid), .theta(ag_theta), .phi(ag_phi), .col(ag_col),
      .row(ag_row), .last(ag_last), .busy(ag_busy));

  logic ct_valid;
  logic signed [OMEGA_B-1:0] ct_w0, ct_w1, ct_w2;
  logic [31:0] ct_tag;
  cartesian #(.SIN_FILE(SIN_FILE), .COS_FILE(COS_FILE)) cart (
      .clk, .rst, .axes(axes[0]), .in_valid(ag_valid), .theta(ag_theta), .phi(ag_phi),
      .in_tag({ag_last, ag_row[14:0], ag_col}), .out_valid(ct_valid), .w0(ct_w0), .w1(ct_w1), .w2(ct_w2),
      .out_tag(ct_tag));

  // direction FIFO
  logic [3*OMEGA_B+32-1:0] fifo[FD];
  logic [2:0] f_rd, f_wr;
  logic cs_ready;
  wire f_pop = fifo_cnt != 0 && cs_ready;
  always_ff @(posedge clk) begin
    if (rst) begin
      fifo_cnt <= '0;
      inflight <= '0;
      f_rd <= '0;
      f_wr <= '0;
    end else begin
      inflight <= inflight + 4'(ag_valid) - 4'(ct_valid);
      if (ct_valid) begin
        fifo[f_wr] <= {ct_w0, ct_w1, ct_w2, ct_tag};
        f_wr <= f_wr + 1'b1;
      end
      if (f_pop) f_rd <= f_rd + 1'b1;
      fifo_cnt <= fifo_cnt + 4'(ct_valid) - 4'(f_pop);
    end
  end
  wire [3*OMEGA_B+32-1:0] f_head = fifo[f_rd];

  // ---- B3 search ----
  logic [16*3*NCAM-1:0] t_flat;
  logic [16*NCAM-1:0] cos_flat;
  always_comb begin
    for (int i = 0; i < NCAM; i++) begin
      t_flat[48*i+:48] = cs_flat[16*CSW*i+:48];
      cos_flat[16*i+:16] = cs_flat[16*(CSW*i+3)+:16];
    end
  end
  logic sr_valid, sr_last, sr_empty;
  logic [CAMB-1:0] sr_cam;
  logic signed [DOT_B-1:0] sr_dot;
  logic signed [OMEGA_B-1:0] sr_w0, sr_w1, sr_w2;
  logic [31:0] sr_tag;
  cam_search #(.NCAM(NCAM)) search (
      .clk, .rst, .in_valid(fifo_cnt != 0), .in_w0(f_head[32+2*OMEGA_B+:OMEGA_B]),
      .in_w1(f_head[32+OMEGA_B+:OMEGA_B]), .in_w2(f_head[32+:OMEGA_B]), .in_tag(f_head[31:0]),
      .in_ready(cs_ready), .t_flat, .cos_flat, .out_valid(sr_valid), .out_cam(sr_cam), .out_dot(sr_dot),
      .out_w0(sr_w0), .out_w1(sr_w1), .out_w2(sr_w2), .out_tag(sr_tag), .out_last(sr_last),
      .out_empty(sr_empty), .out_cone(sr_cone));

  // ---- distance, projection, address: the registers of the contributing camera ----
  wire [16*PPW-1:0] pp_cam = pp_flat[16*PPW*32'(sr_cam)+:16*PPW];
  wire [47:0] c_cam = cs_flat[16*(CSW*32'(sr_cam)+4)+:48];  // words 4-6: the camera centre
  logic cu_valid, cu_tap, cu_last;
  logic [CAMB+FAB-1:0] cu_a0, cu_a1, cu_a2, cu_a3;
  logic [F-1:0] cu_fx, cu_fy;
  logic [17:0] cu_dist;
  logic [31:0] cu_tag;
  contrib_unit contrib (
      .clk, .rst, .in_valid(sr_valid), .in_cam(sr_cam), .in_dot(sr_dot), .in_w0(sr_w0), .in_w1(sr_w1),
      .in_w2(sr_w2), .in_tag(sr_tag), .in_last(sr_last), .in_empty(sr_empty), .u_r(pp_cam[0+:48]),
      .v_r(pp_cam[48+:48]), .c_r(c_cam),
      .k_r({pp_cam[16*14+:16], pp_cam[16*13+:16], pp_cam[16*8+:16], pp_cam[16*7+:16], pp_cam[16*6+:16]}),
      .fu(pp_cam[16*9+:16]), .fv(pp_cam[16*10+:16]), .cu(pp_cam[16*11+:16]), .cv(pp_cam[16*12+:16]),
      .frame_w, .frame_h, .out_valid(cu_valid), .out_tap(cu_tap), .out_addr0(cu_a0), .out_addr1(cu_a1),
      .out_addr2(cu_a2), .out_addr3(cu_a3), .out_fx(cu_fx), .out_fy(cu_fy), .out_dist(cu_dist),
      .out_tag(cu_tag), .out_last(cu_last));

  // ---- B5 frame memories (read: one cycle) ----
  logic [15:0] q0, q1, q2, q3;
  frame_mem #(.NCAM(NCAM), .NPIX(NPIX)) fm (
      .clk, .load_we, .load_addr, .load_data, .re(cu_valid), .addr0(cu_a0), .addr1(cu_a1), .addr2(cu_a2),
      .addr3(cu_a3), .q0, .q1, .q2, .q3);
  logic m_valid, m_tap, m_last;
  logic [F-1:0] m_fx, m_fy;
  logic [17:0] m_dist;
  logic [31:0] m_tag;
  always_ff @(posedge clk) begin
    if (rst) begin
      m_valid <= 1'b0;
      m_tap <= 1'b0;
      m_last <= 1'b0;
      m_fx <= '0;
      m_fy <= '0;
      m_dist <= '0;
      m_tag <= '0;
    end else begin
      m_valid <= cu_valid;
      m_tap <= cu_tap;
      m_last <= cu_last;
      m_fx <= cu_fx;
      m_fy <= cu_fy;
      m_dist <= cu_dist;
      m_tag <= cu_tag;
    end
  end

  // ---- B6 + B7 ----
  logic pv_out_valid;
  logic [31:0] pv_tag;
  pixel_value pvu (
      .clk, .rst, .method, .boundary_en(boundary_ctrl[8]), .boundary_th(boundary_ctrl[7:0]), .in_valid(m_valid),
      .in_tap(m_tap), .in_dist(m_dist), .in_fx(m_fx), .in_fy(m_fy), .in_tag(m_tag), .in_last(m_last), .q0, .q1,
      .q2, .q3, .out_valid(pv_out_valid), .out_tag(pv_tag), .out_r(pix_r), .out_g(pix_g), .out_b(pix_b),
      .out_n(pix_n), .out_boundary(pix_boundary), .unsupported);
  assign pix_valid = pv_out_valid;
  assign pix_col = pv_tag[15:0];
  assign pix_row = {1'b0, pv_tag[30:16]};

  // ---- B8 ----
  out_stream os (
      .clk, .rst, .cols(col_cnt), .rows(row_cnt), .in_valid(pv_out_valid), .in_col(pix_col), .in_row(pix_row),
      .in_r(pix_r), .in_g(pix_g), .in_b(pix_b), .clock_out, .de_out, .hblank_out, .vblank_out, .data_out);

  // busy from start until the frame's last pixel has left the pixel value unit
  logic run;
  always_ff @(posedge clk) begin
    if (rst) run <= 1'b0;
    else if (start && pano_cs) run <= 1'b1;
    else if (pv_out_valid && pv_tag[31]) run <= 1'b0;
  end
  assign busy = run;
endmodule
