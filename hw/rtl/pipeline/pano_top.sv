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
    // per-camera write ports of the frame memories (the front ends, system_top)
    input  logic [NCAM-1:0]     cam_we,
    input  logic [NCAM*FAB-1:0] cam_waddr,
    input  logic [NCAM*16-1:0]  cam_wdata,
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
  logic [1:0] axes;  // bit 0: vr180 axis map, bit 1: columns wrap (MRF neighbours)
  logic [1:0] method;
  logic pano_cs;
  logic [8:0] boundary_ctrl;
  logic [4:0] vig_shift;
  logic vig_mem_select, vig_we;
  logic [CAMB+VIGA-1:0] vig_waddr;
  logic [15:0] vig_wdata;
  logic [16*3*NCAM-1:0] vig_channel;
  logic [16*PPW*NCAM-1:0] pp_flat;
  logic [16*CSW*NCAM-1:0] cs_flat;
  /* verilator lint_off UNUSEDSIGNAL */
  logic [31:0] words_taken;  // for a status register / the waveform
  logic ag_busy;
  logic [5:0] sr_cone;      // cameras passing the cone test (statistics)
  logic mrf_fallback;       // pixels made from the prior alone (statistics)
  /* verilator lint_on UNUSEDSIGNAL */
  config_regs #(.NCAM(NCAM)) cfg (
      .clk, .rst, .reg_valid, .reg_word, .pp_valid, .pp_word, .cs_valid, .cs_word, .pv_valid, .pv_word,
      .row_cnt, .col_cnt, .theta_min, .k_theta, .phi_min, .k_phi, .frame_w, .frame_h, .axes, .pano_cs,
      .method, .boundary_ctrl, .vig_shift, .vig_mem_select, .vig_we, .vig_waddr, .vig_wdata, .vig_channel, .pp_flat, .cs_flat, .cfg_err, .err_code(cfg_err_code),
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

  // MRF (§5.4.2): the four neighbour directions (left, right, up, down) through four more Cartesian
  // units, in step with the centre one
  localparam int NBW = 4 * 3 * OMEGA_B;
  logic [NBW-1:0] ct_nb;
  logic [M-1:0] nb_theta[4], nb_phi[4];
  always_comb begin
    nb_theta[0] = ag_theta;
    nb_phi[0] = ag_phi - k_phi;  // left
    nb_theta[1] = ag_theta;
    nb_phi[1] = ag_phi + k_phi;  // right
    nb_theta[2] = ag_theta - k_theta;
    nb_phi[2] = ag_phi;  // up
    nb_theta[3] = ag_theta + k_theta;
    nb_phi[3] = ag_phi;  // down
  end
  genvar gk;
  generate
    for (gk = 0; gk < 4; gk++) begin : g_nb
      /* verilator lint_off UNUSEDSIGNAL */
      logic nb_valid;
      logic [31:0] nb_tag;
      /* verilator lint_on UNUSEDSIGNAL */
      logic signed [OMEGA_B-1:0] nw0, nw1, nw2;
      cartesian #(.SIN_FILE(SIN_FILE), .COS_FILE(COS_FILE)) cart_nb (
          .clk, .rst, .axes(axes[0]), .in_valid(ag_valid), .theta(nb_theta[gk]), .phi(nb_phi[gk]), .in_tag(32'd0),
          .out_valid(nb_valid), .w0(nw0), .w1(nw1), .w2(nw2), .out_tag(nb_tag));
      assign ct_nb[3*OMEGA_B*gk+:3*OMEGA_B] = {nw2, nw1, nw0};
    end
  endgenerate

  // direction FIFO
  logic [NBW+3*OMEGA_B+32-1:0] fifo[FD];
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
        fifo[f_wr] <= {ct_nb, ct_w0, ct_w1, ct_w2, ct_tag};
        f_wr <= f_wr + 1'b1;
      end
      if (f_pop) f_rd <= f_rd + 1'b1;
      fifo_cnt <= fifo_cnt + 4'(ct_valid) - 4'(f_pop);
    end
  end
  wire [NBW+3*OMEGA_B+32-1:0] f_head = fifo[f_rd];

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
  logic [NBW-1:0] sr_nb;
  cam_search #(.NCAM(NCAM), .AUXW(NBW)) search (
      .clk, .rst, .in_valid(fifo_cnt != 0), .in_w0(f_head[32+2*OMEGA_B+:OMEGA_B]),
      .in_w1(f_head[32+OMEGA_B+:OMEGA_B]), .in_w2(f_head[32+:OMEGA_B]), .in_tag(f_head[31:0]),
      .in_aux(f_head[32+3*OMEGA_B+:NBW]), .in_ready(cs_ready), .t_flat, .cos_flat, .out_valid(sr_valid), .out_cam(sr_cam), .out_dot(sr_dot),
      .out_w0(sr_w0), .out_w1(sr_w1), .out_w2(sr_w2), .out_tag(sr_tag), .out_aux(sr_nb), .out_last(sr_last),
      .out_empty(sr_empty), .out_cone(sr_cone));

  // ---- distance, projection, address: the registers of the contributing camera ----
  wire [16*PPW-1:0] pp_cam = pp_flat[16*PPW*32'(sr_cam)+:16*PPW];
  wire [47:0] c_cam = cs_flat[16*(CSW*32'(sr_cam)+4)+:48];  // words 4-6: the camera centre
  wire [63:0] tcos_cam = cs_flat[16*CSW*32'(sr_cam)+:64];    // words 0-3: t and cos(aov/2)
  // which neighbours exist on the grid (columns wrap on 360-degree grids)
  wire [15:0] sr_col = sr_tag[15:0], sr_row = {1'b0, sr_tag[30:16]};
  wire [3:0] sr_nb_exists = {sr_row != row_cnt - 1'b1, sr_row != 16'd0, sr_col != col_cnt - 1'b1 || axes[1],
                             sr_col != 16'd0 || axes[1]};
  logic [MW-1:0] cu_ev_m;
  logic signed [7:0] cu_ev_e;
  logic cu_ev_c;
  logic cu_valid, cu_tap, cu_last;
  logic [CAMB+FAB-1:0] cu_a0, cu_a1, cu_a2, cu_a3;
  logic [F-1:0] cu_fx, cu_fy;
  logic [17:0] cu_dist;
  logic [31:0] cu_tag;
  logic [CAMB+VIGA-1:0] cu_vig_addr;
  logic [CAMB-1:0] cu_cam;
  contrib_unit contrib (
      .clk, .rst, .in_valid(sr_valid), .in_cam(sr_cam), .in_dot(sr_dot), .in_w0(sr_w0), .in_w1(sr_w1),
      .in_w2(sr_w2), .in_tag(sr_tag), .in_last(sr_last), .in_empty(sr_empty), .u_r(pp_cam[0+:48]),
      .v_r(pp_cam[48+:48]), .c_r(c_cam), .t_r(tcos_cam[47:0]), .cos_r(tcos_cam[63:48]), .in_nb(sr_nb),
      .in_nb_exists(sr_nb_exists),
      .k_r({pp_cam[16*14+:16], pp_cam[16*13+:16], pp_cam[16*8+:16], pp_cam[16*7+:16], pp_cam[16*6+:16]}),
      .fu(pp_cam[16*9+:16]), .fv(pp_cam[16*10+:16]), .cu(pp_cam[16*11+:16]), .cv(pp_cam[16*12+:16]),
      .frame_w, .frame_h, .vig_shift, .out_valid(cu_valid), .out_tap(cu_tap), .out_addr0(cu_a0), .out_addr1(cu_a1),
      .out_addr2(cu_a2), .out_addr3(cu_a3), .out_fx(cu_fx), .out_fy(cu_fy), .out_dist(cu_dist),
      .out_vig_addr(cu_vig_addr), .out_cam(cu_cam), .out_ev_m(cu_ev_m), .out_ev_e(cu_ev_e),
      .out_ev_complete(cu_ev_c), .out_tag(cu_tag), .out_last(cu_last));

  // ---- vignetting memory (Table 6.4/6.8 vig_memory_wrapper): radial tables in an SRAM written over
  // the pix_val channel, read with the frame memories; vig_mem_select = 0 selects the power-up
  // defaults (unit gains: the ROM's content here) ----
  logic [15:0] vig_q;
  ram_sdp #(.WORDS(1 << (CAMB + VIGA)), .BITS(16)) vig_ram (
      .clk, .we(vig_we), .waddr(vig_waddr), .wdata(vig_wdata), .re(cu_valid), .raddr(cu_vig_addr), .rdata(vig_q));

  // ---- B5 frame memories (read: one cycle) ----
  logic [15:0] q0, q1, q2, q3;
  frame_mem #(.NCAM(NCAM), .NPIX(NPIX)) fm (
      .clk, .load_we, .load_addr, .load_data, .cam_we, .cam_waddr, .cam_wdata, .re(cu_valid), .addr0(cu_a0), .addr1(cu_a1), .addr2(cu_a2),
      .addr3(cu_a3), .q0, .q1, .q2, .q3);
  logic m_valid, m_tap, m_last;
  logic [F-1:0] m_fx, m_fy;
  logic [17:0] m_dist;
  logic [31:0] m_tag;
  logic [47:0] m_vig_channel;
  logic [MW-1:0] m_ev_m;
  logic signed [7:0] m_ev_e;
  logic m_ev_c;
  logic m_vig_sel;
  always_ff @(posedge clk) begin
    if (rst) begin
      m_valid <= 1'b0;
      m_tap <= 1'b0;
      m_last <= 1'b0;
      m_fx <= '0;
      m_fy <= '0;
      m_dist <= '0;
      m_tag <= '0;
      m_vig_channel <= '0;
      m_vig_sel <= 1'b0;
      m_ev_m <= '0;
      m_ev_e <= '0;
      m_ev_c <= 1'b0;
    end else begin
      m_valid <= cu_valid;
      m_tap <= cu_tap;
      m_last <= cu_last;
      m_fx <= cu_fx;
      m_fy <= cu_fy;
      m_dist <= cu_dist;
      m_tag <= cu_tag;
      m_vig_channel <= vig_channel[48*32'(cu_cam)+:48];
      m_vig_sel <= vig_mem_select;
      m_ev_m <= cu_ev_m;
      m_ev_e <= cu_ev_e;
      m_ev_c <= cu_ev_c;
    end
  end

  // ---- B6 + B7 ----
  logic pv_out_valid;
  logic [31:0] pv_tag;
  pixel_value pvu (
      .clk, .rst, .method, .boundary_en(boundary_ctrl[8]), .boundary_th(boundary_ctrl[7:0]), .in_valid(m_valid),
      .in_tap(m_tap), .in_dist(m_dist), .in_ev_m(m_ev_m), .in_ev_e(m_ev_e), .in_ev_complete(m_ev_c), .in_fx(m_fx), .in_fy(m_fy), .in_tag(m_tag), .in_last(m_last), .q0, .q1,
      .q2, .q3,
      .vig_radial(m_vig_sel ? vig_q : 16'(1 << VIGF)), .vig_channel(m_vig_sel ? m_vig_channel : {3{16'(1 << VIGF)}}),
      .out_valid(pv_out_valid), .out_tag(pv_tag), .out_r(pix_r), .out_g(pix_g), .out_b(pix_b),
      .out_n(pix_n), .out_boundary(pix_boundary), .out_mrf_fallback(mrf_fallback), .unsupported);
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
