// B5 frame memories (thesis §5.2, Fig. 5.15; hw::FrameMemory): one RGB565 memory per camera
// (R bits 15-11, G 10-5, B 4-0; row-major from address 0, eq. 5.27). frame_addr[CAMB+FAB-1:FAB]
// selects the camera (the 5-to-24 decoder of Fig. 5.15), frame_addr[FAB-1:0] the word. The four
// words of a bilinear quad are read in the same cycle (four read ports: the ASIC's frame memory is
// also four SRAM macros per camera, Table 6.10 frame_mem_2 x 96); the data arrive one cycle later.
// Each camera's memory has its own write port (its front end, system_top); the load port writes any
// camera's word (the testbench).
module frame_mem
  import omma_hw_pkg::*;
#(
    parameter int NCAM = 24,
    parameter int NPIX = 62500  // words per camera (frame width x height)
) (
    input  logic                 clk,
    input  logic                 load_we,
    input  logic [CAMB+FAB-1:0]  load_addr,
    input  logic [15:0]          load_data,
    // one write port per camera (its front end: single_cam_top's RGB565 pixels)
    input  logic [NCAM-1:0]      cam_we,
    input  logic [NCAM*FAB-1:0]  cam_waddr,
    input  logic [NCAM*16-1:0]   cam_wdata,
    input  logic                 re,
    input  logic [CAMB+FAB-1:0]  addr0,
    input  logic [CAMB+FAB-1:0]  addr1,
    input  logic [CAMB+FAB-1:0]  addr2,
    input  logic [CAMB+FAB-1:0]  addr3,
    output logic [15:0]          q0,
    output logic [15:0]          q1,
    output logic [15:0]          q2,
    output logic [15:0]          q3
);
  localparam int AB = $clog2(NPIX);
  logic [15:0] mem[NCAM][NPIX];
  function automatic logic [15:0] rd(input logic [CAMB+FAB-1:0] a);
    logic [CAMB-1:0] cam;
    logic [FAB-1:0] w;
    cam = a[CAMB+FAB-1:FAB];
    w = a[FAB-1:0];
    if (32'(cam) < NCAM && 32'(w) < NPIX) rd = mem[cam][AB'(w)];
    else rd = '0;
  endfunction
  always_ff @(posedge clk) begin
    for (int i = 0; i < NCAM; i++)
      if (cam_we[i] && 32'(cam_waddr[FAB*i+:FAB]) < NPIX) mem[i][AB'(cam_waddr[FAB*i+:FAB])] <= cam_wdata[16*i+:16];
    if (load_we && 32'(load_addr[CAMB+FAB-1:FAB]) < NCAM && 32'(load_addr[FAB-1:0]) < NPIX)
      mem[load_addr[CAMB+FAB-1:FAB]][AB'(load_addr[FAB-1:0])] <= load_data;
    if (re) begin
      q0 <= rd(addr0);
      q1 <= rd(addr1);
      q2 <= rd(addr2);
      q3 <= rd(addr3);
    end
  end
endmodule
