// Throughput model of the panorama pipeline (thesis §5.4.3-5.4.4, 6.5.1).
//
// Each block has an initiation interval Th (cycles between two output pixels it can accept). The
// thesis (Fig. 5.13, text): angle generation 2; Cartesian unit 9 with one sin/cos table set (three
// angles, three cycles each), 3 with three sets; frame memory 2; camera search 1 cycle per camera
// (24) before unrolling, N_cam_contr (4) after ("24 parallel dot products and a 24-to-5 priority
// encoder"); pixel value unit N_cam_contr. Th_sys = max over the blocks; at 25 fps an N x M panorama
// needs F_min = 25 N M Th_sys (text: "Fmin = 25xNxMxThsys x10^-6 MHz").
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace omma::hw {

struct ThroughputOptions {
  int cameras = 24;
  int max_contributors = 4;  // N_cam_contr
  int angle_th = 2;
  int table_sets = 3;  // sin/cos table sets in the Cartesian unit: Th = 9 / table_sets
  int memory_th = 2;
  bool unrolled = true;  // camera search: N parallel dot products (Th = N_cam_contr) or 1/camera
  int width = 1080, height = 1080;
  double fps = 25;
  double clock_mhz = 120;

  bool IsValid(std::string* error = nullptr) const;
};

struct BlockTh {
  std::string block;
  int th = 0;  // cycles per output pixel (worst case)
};

struct ThroughputSummary {
  std::vector<BlockTh> blocks;
  int th_sys = 0;                        // max over blocks
  double fmin_mhz = 0;                   // 25 N M Th_sys (at options.fps)
  double fps_at_clock = 0;               // clock / (N M Th_sys)
  double pixels_per_frame_at_clock = 0;  // clock / (fps Th_sys): the largest panorama at the clock
  int square_side_at_clock = 0;          // floor(sqrt(that)): the largest square panorama
};

ThroughputSummary throughput(const ThroughputOptions& options);

// Cycles one output pixel takes in the pipeline of `options` when `contributors` cameras (after the
// priority encoder) contribute: max over the blocks of their Th for that pixel (search and pixel
// value take max(1, n) cycles unrolled; search takes `cameras` cycles when not unrolled).
int pixel_cycles(const ThroughputOptions& options, int contributors);

}  // namespace omma::hw
