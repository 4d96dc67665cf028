// Configuration registers behind the Table 6.6 channels (thesis §6.4.5, Fig. 6.9; the register map
// of hw::encode / hw::decode, src/omma/hw/regmap.h, addresses and widths from omma_hw_pkg):
//   reg        [31] write enable, [30:16] register address, [15:0] data (Table 6.7 globals; an
//              angle register wider than 16 bits takes two addresses, low half first)
//   pix_pos    [31:25] 0, [24:21] array select, [20:16] camera select, [15:0] data (u, v, k1-k3,
//              fu, fv, cu, cv, k4, k5: PIX_POS_WORDS words per camera)
//   cam_search same layout (t, cos(aov/2), c: CAM_SEARCH_WORDS words per camera)
//   pix_val    [31] write enable, [30:16] vignetting memory address, [15:0] data
// A word the chip cannot take is flagged: `cfg_err` latches with the first error's code and the
// channel and index of the word (the register keeps its value):
//   1 write enable clear, 2 unknown register address, 3 value wider than the register,
//   9 write to a read-only register (hw_version: the chip's own value, V_HW_VERSION),
//   4 array word with bits [31:25] set, 5 array select beyond the channel's arrays,
//   6 camera select beyond the cameras built (NCAM), 8 vignetting address beyond the memory.
module config_regs
  import omma_hw_pkg::*;
#(
    parameter int NCAM = 24
) (
    input  logic                            clk,
    input  logic                            rst,
    input  logic                            reg_valid,
    input  logic [31:0]                     reg_word,
    input  logic                            pp_valid,
    input  logic [31:0]                     pp_word,
    input  logic                            cs_valid,
    input  logic [31:0]                     cs_word,
    input  logic                            pv_valid,
    input  logic [31:0]                     pv_word,
    // globals (Table 6.7)
    output logic [15:0]                     row_cnt,
    output logic [15:0]                     col_cnt,
    output logic [M-1:0]                    theta_min,
    output logic [M-1:0]                    k_theta,
    output logic [M-1:0]                    phi_min,
    output logic [M-1:0]                    k_phi,
    output logic [15:0]                     frame_w,
    output logic [15:0]                     frame_h,
    output logic [1:0]                      axes,
    output logic                            pano_cs,
    output logic [1:0]                      method,
    output logic [8:0]                      boundary_ctrl,
    output logic [4:0]                      vig_shift,
    output logic                            vig_mem_select, // 0: power-up ROM (unit gains), 1: SRAM
    // vignetting memory: radial tables (SRAM write port) and the channel gains (registers)
    output logic                            vig_we,
    output logic [CAMB+VIGA-1:0]            vig_waddr,
    output logic [15:0]                     vig_wdata,
    output logic [16*3*NCAM-1:0]            vig_channel,  // (camera, R/G/B) gains, uQ2.14
    // register arrays, camera-major: camera i's words at [16*WORDS*i +: 16*WORDS]
    output logic [16*PIX_POS_WORDS*NCAM-1:0]    pp_flat,
    output logic [16*CAM_SEARCH_WORDS*NCAM-1:0] cs_flat,
    output logic                            cfg_err,
    output logic [3:0]                      err_code,
    output logic [1:0]                      err_chan,   // 0 reg, 1 pix_pos, 2 cam_search, 3 pix_val
    output logic [31:0]                     err_index,  // word index within its channel
    output logic [31:0]                     words_taken
);
  localparam int NG = 18;
  localparam int CB = (NCAM > 1) ? $clog2(NCAM) : 1;                           // camera select bits used
  localparam int PWB = $clog2(PIX_POS_WORDS), CWB = $clog2(CAM_SEARCH_WORDS);  // array select bits used
  // the global registers (regmap.cc global_registers order)
  function automatic int gaddr(input int i);
    case (i)
      0: gaddr = A_PANORAMA_ROW_CNT;
      1: gaddr = A_PANORAMA_COL_CNT;
      2: gaddr = A_PANO_MAX_PHI;
      3: gaddr = A_PANO_K_PHI;
      4: gaddr = A_PANO_MAX_THETA;
      5: gaddr = A_PANO_MIN_THETA;
      6: gaddr = A_PANO_K_THETA;
      7: gaddr = A_PANO_MIN_PHI;
      8: gaddr = A_FRAME_WIDTH;
      9: gaddr = A_FRAME_HEIGHT;
      10: gaddr = A_PANO_AXES;
      11: gaddr = A_PANO_CS;
      12: gaddr = A_VIG_SHIFT;
      13: gaddr = A_SEL_COLOR_SOURCE;
      14: gaddr = A_PIX_METHOD;
      15: gaddr = A_BOUNDARY_CTRL;
      16: gaddr = A_CAMERA_SELECT;
      default: gaddr = A_VIG_MEM_SELECT;
    endcase
  endfunction
  function automatic int gbits(input int i);
    case (i)
      0: gbits = B_PANORAMA_ROW_CNT;
      1: gbits = B_PANORAMA_COL_CNT;
      2: gbits = B_PANO_MAX_PHI;
      3: gbits = B_PANO_K_PHI;
      4: gbits = B_PANO_MAX_THETA;
      5: gbits = B_PANO_MIN_THETA;
      6: gbits = B_PANO_K_THETA;
      7: gbits = B_PANO_MIN_PHI;
      8: gbits = B_FRAME_WIDTH;
      9: gbits = B_FRAME_HEIGHT;
      10: gbits = B_PANO_AXES;
      11: gbits = B_PANO_CS;
      12: gbits = B_VIG_SHIFT;
      13: gbits = B_SEL_COLOR_SOURCE;
      14: gbits = B_PIX_METHOD;
      15: gbits = B_BOUNDARY_CTRL;
      16: gbits = B_CAMERA_SELECT;
      default: gbits = B_VIG_MEM_SELECT;
    endcase
  endfunction

  logic [31:0] g[NG];
  // the register arrays, one 16-bit word per (camera, array word): a write enables one word
  logic [15:0] pp_r[NCAM][PIX_POS_WORDS];
  logic [15:0] cs_r[NCAM][CAM_SEARCH_WORDS];
  logic [15:0] vg_r[NCAM][3];  // channel gains R, G, B
  genvar gc, gw;
  generate
    for (gc = 0; gc < NCAM; gc++) begin : g_cam
      for (gw = 0; gw < PIX_POS_WORDS; gw++) begin : g_pp
        assign pp_flat[16*(PIX_POS_WORDS*gc+gw)+:16] = pp_r[gc][gw];
      end
      for (gw = 0; gw < CAM_SEARCH_WORDS; gw++) begin : g_cs
        assign cs_flat[16*(CAM_SEARCH_WORDS*gc+gw)+:16] = cs_r[gc][gw];
      end
      for (gw = 0; gw < 3; gw++) begin : g_vg
        assign vig_channel[16*(3*gc+gw)+:16] = vg_r[gc][gw];
      end
    end
  endgenerate
  logic [31:0] n_reg, n_pp, n_cs, n_pv;

  // decode of a reg-channel word: which register, which half, and whether the value fits
  logic r_hit, r_hi, r_fits;
  logic [4:0] r_idx;
  always_comb begin
    r_hit = 1'b0;
    r_hi = 1'b0;
    r_idx = '0;
    r_fits = 1'b1;
    for (int i = 0; i < NG; i++) begin
      if (32'(reg_word[30:16]) == 32'(gaddr(i))) begin
        r_hit = 1'b1;
        r_idx = 5'(i);
        r_hi = 1'b0;
        if (gbits(i) < 16) r_fits = (32'(reg_word[15:0]) >> gbits(i)) == 0;
      end else if (gbits(i) > 16 && 32'(reg_word[30:16]) == 32'(gaddr(i)) + 1) begin
        r_hit = 1'b1;
        r_idx = 5'(i);
        r_hi = 1'b1;
        if (gbits(i) < 32) r_fits = (32'(reg_word[15:0]) >> (gbits(i) - 16)) == 0;
      end
    end
  end

  // an array-channel word (pix_pos, cam_search): 0 if the chip takes it, else the error code
  function automatic logic [3:0] array_code(input logic [31:16] w, input int words);
    if (w[31:25] != '0) array_code = 4'd4;
    else if (32'(w[24:21]) >= words) array_code = 4'd5;
    else if (32'(w[20:16]) >= NCAM) array_code = 4'd6;
    else array_code = 4'd0;
  endfunction
  wire [3:0] pp_code = array_code(pp_word[31:16], PIX_POS_WORDS);
  wire [3:0] cs_code = array_code(cs_word[31:16], CAM_SEARCH_WORDS);
  wire reg_ok = reg_word[31] && r_hit && r_fits && 32'(reg_word[30:16]) != A_HW_VERSION;
  wire pv_ok = pv_word[31] && 32'(pv_word[30:16]) < VIG_WORDS;
  wire [2:0] taken = 3'(reg_valid && reg_ok) + 3'(pp_valid && pp_code == 0) + 3'(cs_valid && cs_code == 0) +
                     3'(pv_valid && pv_ok);

  task automatic flag(input logic [3:0] code, input logic [1:0] chan, input logic [31:0] index);
    if (!cfg_err) begin
      cfg_err <= 1'b1;
      err_code <= code;
      err_chan <= chan;
      err_index <= index;
    end
  endtask

  always_ff @(posedge clk) begin
    vig_we <= 1'b0;
    if (rst) begin
      for (int i = 0; i < NG; i++) g[i] <= '0;
      vig_waddr <= '0;
      vig_wdata <= '0;
      for (int c = 0; c < NCAM; c++)
        for (int k = 0; k < 3; k++) vg_r[c][k] <= '0;
      for (int c = 0; c < NCAM; c++) begin
        for (int w = 0; w < PIX_POS_WORDS; w++) pp_r[c][w] <= '0;
        for (int w = 0; w < CAM_SEARCH_WORDS; w++) cs_r[c][w] <= '0;
      end
      cfg_err <= 1'b0;
      err_code <= '0;
      err_chan <= '0;
      err_index <= '0;
      n_reg <= '0;
      n_pp <= '0;
      n_cs <= '0;
      n_pv <= '0;
      words_taken <= '0;
    end else begin
      words_taken <= words_taken + 32'(taken);
      if (reg_valid) begin
        n_reg <= n_reg + 1;
        if (!reg_word[31]) flag(4'd1, 2'd0, n_reg);
        else if (32'(reg_word[30:16]) == A_HW_VERSION) flag(4'd9, 2'd0, n_reg);
        else if (!r_hit) flag(4'd2, 2'd0, n_reg);
        else if (!r_fits) flag(4'd3, 2'd0, n_reg);
        else if (r_hi) g[r_idx][31:16] <= reg_word[15:0];
        else g[r_idx][15:0] <= reg_word[15:0];
      end
      if (pp_valid) begin
        n_pp <= n_pp + 1;
        if (pp_code != 0) flag(pp_code, 2'd1, n_pp);
        else pp_r[pp_word[16+:CB]][pp_word[21+:PWB]] <= pp_word[15:0];
      end
      if (cs_valid) begin
        n_cs <= n_cs + 1;
        if (cs_code != 0) flag(cs_code, 2'd2, n_cs);
        else cs_r[cs_word[16+:CB]][cs_word[21+:CWB]] <= cs_word[15:0];
      end
      if (pv_valid) begin
        n_pv <= n_pv + 1;
        if (!pv_word[31]) flag(4'd1, 2'd3, n_pv);
        else if (32'(pv_word[30:16]) >= VIG_WORDS) flag(4'd8, 2'd3, n_pv);
        else begin
          if (32'(pv_word[30:16]) < (1 << (CAMB + VIGA))) begin
            vig_we <= 1'b1;  // radial entry (camera << VIGA) + i
            vig_waddr <= pv_word[16+:CAMB+VIGA];
            vig_wdata <= pv_word[15:0];
          end else if (32'(pv_word[30:18]) - (1 << (CAMB + VIGA - 2)) < NCAM && pv_word[17:16] != 2'd3) begin
            // channel gain at (1 << (CAMB+VIGA)) + 4 camera + channel
            vg_r[pv_word[18+:CB]][pv_word[17:16]] <= pv_word[15:0];
          end
        end
      end
    end
  end

  assign row_cnt = g[0][15:0];
  assign col_cnt = g[1][15:0];
  assign k_phi = g[3][M-1:0];
  assign theta_min = g[5][M-1:0];
  assign k_theta = g[6][M-1:0];
  assign phi_min = g[7][M-1:0];
  assign frame_w = g[8][15:0];
  assign frame_h = g[9][15:0];
  assign axes = g[10][1:0];
  assign pano_cs = g[11][0];
  assign method = g[14][1:0];
  assign boundary_ctrl = g[15][8:0];
  assign vig_shift = g[12][4:0];
  assign vig_mem_select = g[17][0];
endmodule
