// Simple dual-port RAM: one synchronous write port, one synchronous read port (read data one
// cycle after the address), the shape every FPGA block RAM and the ASIC's dual-port SRAM macros
// (thesis Table 6.4) offer. Read-during-write of the same address returns the old word.
// INIT_FILE: optional $readmemh image (ROMs: write enable tied low).
module ram_sdp #(
    parameter int WORDS = 256,
    parameter int BITS = 16,
    parameter INIT_FILE = ""
) (
    input  logic                     clk,
    input  logic                     we,
    input  logic [$clog2(WORDS)-1:0] waddr,
    input  logic [BITS-1:0]          wdata,
    input  logic                     re,
    input  logic [$clog2(WORDS)-1:0] raddr,
    output logic [BITS-1:0]          rdata
);
  logic [BITS-1:0] mem[WORDS];
  initial if (INIT_FILE != "") $readmemh(INIT_FILE, mem);
  always_ff @(posedge clk) begin
    if (we) mem[waddr] <= wdata;
    if (re) rdata <= mem[raddr];
  end
endmodule
