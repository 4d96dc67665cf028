// Per contributing camera (one per cycle): B3's distance (eq. 5.19-5.20), B4's projection with
// distortion (eq. 5.21-5.26) and the frame addresses of the bilinear tap (eq. 5.27 with the camera
// on top). Bit-exact with hw::distance_unit, hw::project and hw::tap_address (docs/hw-model.md §4):
//   s = c . omega (sQ.(Pp+W)), sD = align(s -> D), r_k = rs(sD w_k, W) - (c_k << (D-Pp)),
//   d = clamp(isqrt(sum r_k^2), 1, 2^18-1)                                       (uQ.D)
//   x = sat(div_round(dot_u 2^P, dot_t)), y likewise (restoring divider, round half away from 0)
//   xx, yy, xy, R2, R4, R6, p, x', y' (rs at P or K fraction bits), col/row = align(f x') + align(c)
//   quad: xs = col - 2^(F-1), x0 = xs >>> F, fx = xs mod 2^F, X clamped to the frame; likewise y.
// Contributors whose point is not on the frame (or behind the camera) leave with tap = 0. Also the
// address of the radial vignetting entry: i = min(2^VIGA - 1, (dx^2 + dy^2) >> vig_shift).
// One register stage (the combinational depth is the divider's: a pipelined version would cut it).
module contrib_unit
  import omma_hw_pkg::*;
  import omma_arith_pkg::*;
(
    input  logic                      clk,
    input  logic                      rst,
    input  logic                      in_valid,
    input  logic [CAMB-1:0]           in_cam,
    input  logic signed [DOT_B-1:0]   in_dot,
    input  logic signed [OMEGA_B-1:0] in_w0,
    input  logic signed [OMEGA_B-1:0] in_w1,
    input  logic signed [OMEGA_B-1:0] in_w2,
    input  logic [31:0]               in_tag,
    input  logic                      in_last,
    input  logic                      in_empty,
    // the registers of camera in_cam (Table 6.7 arrays), 16 bits each
    input  logic [16*3-1:0]           u_r,
    input  logic [16*3-1:0]           v_r,
    input  logic [16*3-1:0]           c_r,
    input  logic [16*3-1:0]           t_r,        // optical axis and cos(aov/2): the MRF's cone tests
    input  logic [15:0]               cos_r,
    // MRF (§5.4.2): the four neighbour directions (left, right, up, down) and whether they exist
    input  logic [4*3*OMEGA_B-1:0]    in_nb,
    input  logic [3:0]                in_nb_exists,
    input  logic [16*5-1:0]           k_r,        // k1..k5
    input  logic [15:0]               fu,
    input  logic [15:0]               fv,
    input  logic [15:0]               cu,
    input  logic [15:0]               cv,
    input  logic [15:0]               frame_w,
    input  logic [15:0]               frame_h,
    input  logic [4:0]                vig_shift,
    output logic                      out_valid,
    output logic                      out_tap,    // a valid tap (projection on the frame)
    output logic [CAMB+FAB-1:0]       out_addr0,
    output logic [CAMB+FAB-1:0]       out_addr1,
    output logic [CAMB+FAB-1:0]       out_addr2,
    output logic [CAMB+FAB-1:0]       out_addr3,
    output logic [F-1:0]              out_fx,
    output logic [F-1:0]              out_fy,
    output logic [17:0]               out_dist,
    output logic [CAMB+VIGA-1:0]      out_vig_addr,  // radial vignetting entry of this camera
    output logic [CAMB-1:0]           out_cam,
    output logic [MW-1:0]             out_ev_m,      // MRF evidence d(u) prod d(v), block floating
    output logic signed [7:0]         out_ev_e,
    output logic                      out_ev_complete, // passes the cone test at every neighbour
    output logic [31:0]               out_tag,
    output logic                      out_last
);
  // Worst-case widths of the intermediate values (from the register widths; sx() marks them so
  // that synthesis sees them, the value never changes)
  localparam int SDB = (PP + W > D) ? DOT_B - (PP + W - D) + 1 : DOT_B + (D - PP - W);  // s at D bits
  localparam int RK1 = SDB + OMEGA_B - W + 1, RK2 = 16 + D - PP;
  localparam int RKB = ((RK1 > RK2) ? RK1 : RK2) + 1;                                    // r_k
  localparam int R2SB = 2 * RKB + 1;                                                     // |r|^2
  localparam int XXB = 2 * PB - P + 1;                                                   // xx, yy, xy
  localparam int R2B = XXB + 1, R4B = 2 * R2B - P + 1, R6B = R4B + R2B - P + 1;          // R^2, R^4, R^6
  localparam int POLYB = 16 + R6B + 2;
  localparam int PW = ((POLYB - K + 1 > P + 2) ? POLYB - K + 1 : P + 2) + 1;              // p
  localparam int XD1 = PW + PB - P + 1, XD2 = 16 + XXB + 4 - K + 1;
  localparam int XDB = ((XD1 > XD2) ? XD1 : XD2) + 1;                                    // x', y' before saturation
  localparam int CA = (FF + P > F) ? 17 + PB - (FF + P - F) + 1 : 17 + PB + (F - FF - P);
  localparam int CB = (F > FC) ? 17 + F - FC : 17;
  localparam int COLB = ((CA > CB) ? CA : CB) + 1;                                       // col, row
  localparam int NUMB = DOT_B + P + 2;                                                   // 2 |dot_u 2^P| + dot_t

  function automatic logic signed [63:0] w16(input logic [127:0] f, input integer k);
    w16 = $signed(64'($signed(f[16*k+:16])));
  endfunction

  logic signed [63:0] w[3];
  logic signed [63:0] du, dv, dt;
  logic signed [63:0] x, y, xd, yd, col, row;
  logic [63:0] d;
  logic tap;
  logic [CAMB+FAB-1:0] a0, a1, a2, a3;
  logic [F-1:0] fx, fy;
  logic [CAMB+VIGA-1:0] vaddr;
  logic [MW+8-1:0] ev;
  logic ev_ok;

  // sign-magnitude restoring divider, round half away from zero, saturated to PB bits
  function automatic logic signed [63:0] div_round_sat(input logic signed [63:0] n, input logic signed [63:0] dd);
    logic [63:0] a, q;
    logic ovf;
    logic signed [63:0] lim;
    lim = ($signed(64'(1)) <<< (PB - 1)) - 1;
    a = n < 0 ? $unsigned(64'(-n)) : $unsigned(64'(n));
    {ovf, q} = udiv(2 * a + $unsigned(64'(dd)), 2 * $unsigned(64'(dd)), PB, NUMB, DOT_B + 1);  // floor((2|n| + d) / 2d)
    if (ovf || $signed(64'(q)) > lim + 1) div_round_sat = n < 0 ? -lim - 1 : lim;
    else if (n < 0) div_round_sat = -$signed(64'(q));
    else div_round_sat = smin($signed(64'(q)), lim);
  endfunction

  // eq. 5.19-5.20 with q = 0 (hw::distance_unit): uQ.D, clamped to [1, 2^18 - 1]
  function automatic logic [63:0] dist_of(input logic signed [OMEGA_B-1:0] a, input logic signed [OMEGA_B-1:0] b,
                                          input logic signed [OMEGA_B-1:0] c);
    logic signed [63:0] ww[3];
    logic signed [63:0] sc, sdd, r2s, rks;
    logic [63:0] q;
    ww[0] = $signed(64'(a));
    ww[1] = $signed(64'(b));
    ww[2] = $signed(64'(c));
    sc = sx(ww[0] * w16(128'(c_r), 0) + ww[1] * w16(128'(c_r), 1) + ww[2] * w16(128'(c_r), 2), DOT_B);  // sQ.(Pp+W)
    sdd = sx(align(sc, PP + W, D), SDB);                                                  // sQ.D
    r2s = '0;
    for (int k = 0; k < 3; k++) begin
      rks = sx(rs(sdd * ww[k], W) - (w16(128'(c_r), k) <<< (D - PP)), RKB);
      r2s = sx(r2s + rks * rks, R2SB);                                                    // uQ.2D
    end
    q = isqrt($unsigned(64'(r2s)), R2SB);
    if (q < 1) q = 1;
    if (q > $unsigned(64'((1 << 18) - 1))) q = $unsigned(64'((1 << 18) - 1));
    dist_of = q;
  endfunction

  // block-floating normalisation: the leading one to bit MW-1 (truncation), exponent += shift
  function automatic logic [MW+8-1:0] norm(input logic [63:0] p, input logic signed [7:0] e);
    integer bl;
    logic [MW-1:0] m;
    bl = bitlen(p);
    if (bl >= MW) m = MW'(p >> (bl - MW));
    else m = MW'(p << (MW - bl));
    norm = {m, 8'(e + 8'(bl - MW))};
  endfunction

  // temporaries of the combinational block below (all assigned before use)
  logic signed [OMEGA_B-1:0] nw[3];
  logic signed [63:0] ndot, lim, xx, yy, xy, rr2, rr4, rr6, p, k1, k2, k3, k4, k5;
  logic signed [63:0] xs, ys, x0, y0, X0, X1, Y0, Y1, lw, base, dx, dy, vi;
  logic [63:0] dk;

  always_comb begin
    for (int j = 0; j < 3; j++) nw[j] = '0;
    ndot = '0;
    dk = '0;
    xs = '0;
    ys = '0;
    x0 = '0;
    y0 = '0;
    w[0] = $signed(64'(in_w0));
    w[1] = $signed(64'(in_w1));
    w[2] = $signed(64'(in_w2));
    dt = $signed(64'(in_dot));
    du = sx(w[0] * w16(128'(u_r), 0) + w[1] * w16(128'(u_r), 1) + w[2] * w16(128'(u_r), 2), DOT_B);  // omega . u, sQ3.(W+V)
    dv = sx(w[0] * w16(128'(v_r), 0) + w[1] * w16(128'(v_r), 1) + w[2] * w16(128'(v_r), 2), DOT_B);

    // distance (q = 0): r = (c . omega) omega - c
    d = dist_of(in_w0, in_w1, in_w2);

    // MRF evidence (hw pipeline.cc, docs/hw-model.md B6 mrf): complete if the camera sees every
    // existing neighbour; D = d(u) d(left) d(right) d(up) d(down), renormalised after each product
    begin
      ev = norm(d, 8'sd0);
      ev_ok = 1'b1;
      for (int k = 0; k < 4; k++)
        if (in_nb_exists[k] && ev_ok) begin
          for (int j = 0; j < 3; j++) nw[j] = in_nb[OMEGA_B*(3*k+j)+:OMEGA_B];
          ndot = sx($signed(64'(nw[0])) * w16(128'(t_r), 0) + $signed(64'(nw[1])) * w16(128'(t_r), 1) +
                    $signed(64'(nw[2])) * w16(128'(t_r), 2), DOT_B);
          if (ndot < ($signed(64'($signed(cos_r))) <<< W)) begin
            ev_ok = 1'b0;
          end else begin
            dk = dist_of(nw[0], nw[1], nw[2]);
            ev = norm(zx($unsigned(64'(ev[MW+8-1:8])) * dk, MW + 18), $signed(ev[7:0]));
          end
        end
    end

    // projection (eq. 5.21-5.26 on normalised coordinates)
    begin
      lim = ($signed(64'(1)) <<< (PB - 1)) - 1;
      k1 = w16(128'(k_r), 0);
      k2 = w16(128'(k_r), 1);
      k3 = w16(128'(k_r), 2);
      k4 = w16(128'(k_r), 3);
      k5 = w16(128'(k_r), 4);
      x = (dt > 0) ? div_round_sat(du <<< P, dt) : '0;
      y = (dt > 0) ? div_round_sat(dv <<< P, dt) : '0;
      x = sx(x, PB);  // saturated to proj_bits
      y = sx(y, PB);
      xx = sx(rs(x * x, P), XXB);
      yy = sx(rs(y * y, P), XXB);
      xy = sx(rs(x * y, P), XXB);
      rr2 = sx(xx + yy, R2B);                                                          // (5.23)
      rr4 = sx(rs(rr2 * rr2, P), R4B);
      rr6 = sx(rs(rr4 * rr2, P), R6B);
      p = sx(($signed(64'(1)) <<< P) + rs(sx(k1 * rr2 + k2 * rr4 + k5 * rr6, POLYB), K), PW);  // (5.24)
      xd = sx(rs(p * x, P) + rs(k4 * 2 * xy + k3 * (rr2 + 2 * xx), K), XDB);           // (5.25)
      yd = sx(rs(p * y, P) + rs(k3 * 2 * xy + k4 * (rr2 + 2 * yy), K), XDB);           // (5.26)
      xd = sx(smax(smin(xd, lim), -lim - 1), PB);
      yd = sx(smax(smin(yd, lim), -lim - 1), PB);
      col = sx(align($signed(64'(fu)) * xd, FF + P, F) + align($signed(64'(cu)), FC, F), COLB);
      row = sx(align($signed(64'(fv)) * yd, FF + P, F) + align($signed(64'(cv)), FC, F), COLB);
      tap = !in_empty && dt > 0 && col >= 0 && row >= 0 && col < ($signed(64'(frame_w)) <<< F) &&
            row < ($signed(64'(frame_h)) <<< F);
    end

    // tap address (eq. 5.27, camera on top)
    begin
      lw = $signed(64'(frame_w));
      base = $signed(64'(in_cam)) <<< FAB;
      if (BILINEAR != 0) begin
        xs = col - ($signed(64'(1)) <<< (F - 1));
        ys = row - ($signed(64'(1)) <<< (F - 1));
        x0 = xs >>> F;
        y0 = ys >>> F;
        fx = xs[F-1:0];
        fy = ys[F-1:0];
        X0 = smax(smin(x0, lw - 1), 0);
        X1 = smax(smin(x0 + 1, lw - 1), 0);
        Y0 = smax(smin(y0, $signed(64'(frame_h)) - 1), 0);
        Y1 = smax(smin(y0 + 1, $signed(64'(frame_h)) - 1), 0);
      end else begin
        fx = '0;
        fy = '0;
        X0 = col >>> F;
        X1 = X0;
        Y0 = row >>> F;
        Y1 = Y0;
      end
      // vignetting (hw::vignetting_gain): the pixel containing the point, its squared distance to
      // the principal point's pixel, >> vig_shift, clamped to the table
      begin
        dx = (col >>> F) - ($signed(64'(cu)) >>> FC);
        dy = (row >>> F) - ($signed(64'(cv)) >>> FC);
        dx = sx(dx, COLB + 1);
        dy = sx(dy, COLB + 1);
        vi = sx(dx * dx + dy * dy, 2 * COLB + 4) >>> vig_shift;
        if (vi > (1 << VIGA) - 1) vi = (1 << VIGA) - 1;
        vaddr = {in_cam, vi[VIGA-1:0]};
      end
      X0 = sx(X0, 17);  // clamped to the frame
      X1 = sx(X1, 17);
      Y0 = sx(Y0, 17);
      Y1 = sx(Y1, 17);
      a0 = (CAMB + FAB)'(base + Y0 * lw + X0);
      a1 = (CAMB + FAB)'(base + Y0 * lw + X1);
      a2 = (CAMB + FAB)'(base + Y1 * lw + X0);
      a3 = (CAMB + FAB)'(base + Y1 * lw + X1);
    end
  end

  always_ff @(posedge clk) begin
    if (rst) begin
      out_valid <= 1'b0;
      out_tap <= 1'b0;
      out_addr0 <= '0;
      out_addr1 <= '0;
      out_addr2 <= '0;
      out_addr3 <= '0;
      out_fx <= '0;
      out_fy <= '0;
      out_dist <= '0;
      out_vig_addr <= '0;
      out_cam <= '0;
      out_ev_m <= '0;
      out_ev_e <= '0;
      out_ev_complete <= 1'b0;
      out_tag <= '0;
      out_last <= 1'b0;
    end else begin
      out_valid <= in_valid;
      out_tap <= in_valid && tap;
      out_addr0 <= a0;
      out_addr1 <= a1;
      out_addr2 <= a2;
      out_addr3 <= a3;
      out_fx <= fx;
      out_fy <= fy;
      out_dist <= d[17:0];
      out_vig_addr <= vaddr;
      out_cam <= in_cam;
      out_ev_m <= ev[MW+8-1:8];
      out_ev_e <= $signed(ev[7:0]);
      out_ev_complete <= ev_ok;
      out_tag <= in_tag;
      out_last <= in_last;
    end
  end
endmodule
