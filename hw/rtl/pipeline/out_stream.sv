// B8 output stream (thesis §6.3, Fig. 6.5; Fig. 5.15's video interface): raster signals for a
// display or a Video-to-AXI-Stream bridge.
//   clock_out  high for one cycle each time a new pixel value is on data_out ("asserted to logic 1
//              each time a new pixel value is available")
//   DE_out     data enable: high with every active pixel
//   hblank_out high between the end of a line and the beginning of the next one
//   vblank_out low from the beginning of the first line to the end of the last line of a frame
//   data_out   the 24-bit RGB pixel in the 30-bit bus: R, G, B each as a 10-bit field with the 8-bit
//              value in its most significant bits (R in [29:20], G in [19:10], B in [9:0]); the
//              thesis does not state its packing (§6.3: "kept as 30 bits to keep the interface
//              general")
module out_stream (
    input  logic        clk,
    input  logic        rst,
    input  logic [15:0] cols,
    input  logic [15:0] rows,
    input  logic        in_valid,
    input  logic [15:0] in_col,
    input  logic [15:0] in_row,
    input  logic [7:0]  in_r,
    input  logic [7:0]  in_g,
    input  logic [7:0]  in_b,
    output logic        clock_out,
    output logic        de_out,
    output logic        hblank_out,
    output logic        vblank_out,
    output logic [29:0] data_out
);
  logic line_end, frame_end;
  always_ff @(posedge clk) begin
    clock_out <= 1'b0;
    de_out <= 1'b0;
    line_end <= 1'b0;
    frame_end <= 1'b0;
    if (rst) begin
      hblank_out <= 1'b1;
      vblank_out <= 1'b1;
      data_out <= '0;
    end else begin
      if (line_end) hblank_out <= 1'b1;   // the cycle after a line's last pixel
      if (frame_end) vblank_out <= 1'b1;  // the cycle after the frame's last pixel
      if (in_valid) begin
        clock_out <= 1'b1;
        de_out <= 1'b1;
        data_out <= {in_r, 2'b00, in_g, 2'b00, in_b, 2'b00};
        hblank_out <= 1'b0;
        if (in_col == 16'd0 && in_row == 16'd0) vblank_out <= 1'b0;
        line_end <= in_col == cols - 1'b1;
        frame_end <= in_col == cols - 1'b1 && in_row == rows - 1'b1;
      end
    end
  end
endmodule
