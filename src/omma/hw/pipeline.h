// The whole bit-accurate panorama pipeline (thesis Fig. 5.9-5.15): the blocks of blocks.h chained
// over every output pixel, in the thesis's scan order (rows top to bottom, columns left to right).
// This is the golden model the RTL (hw/rtl/) is compared with pixel by pixel.
//
// Frames: CV_8UC3 BGR as OpenCV reads them (8-bit; 16-bit frames are reduced to their 8 most
// significant bits, as §5.2); each is stored as RGB565 (blocks.h rgb888_to_rgb565). The panorama
// is CV_8UC3 BGR, black where no camera contributes.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/core/grid.h"
#include "omma/core/rig.h"
#include "omma/hw/blocks.h"
#include "omma/hw/tables.h"
#include "omma/hw/throughput.h"
#include "omma/pano/method.h"

namespace omma::hw {

struct PipelineCounters {
  uint64_t cycles = 0;                      // sum over pixels of pixel_cycles (throughput.h)
  std::array<uint64_t, 9> contributors{};   // histogram of valid contributors per pixel (0..8)
  std::array<uint64_t, 33> cone_cameras{};  // histogram of cameras passing the cone test (0..32+)
  uint64_t dropped_by_encoder = 0;          // pixels where more cameras passed than max_contributors
  uint64_t boundary_pixels = 0;
  uint64_t mrf_fallback_pixels = 0;  // MRF: no camera complete, prior alone
};

struct PipelineSummary {
  cv::Mat pano;      // CV_8UC3 BGR
  cv::Mat boundary;  // CV_8UC1, 255 where the boundary unit fired (empty if boundary was off)
  PipelineCounters stats;
};

// Everything that happens to one output pixel, for debugging and for RTL comparison.
struct PixelTrace {
  Angles angles;
  Omega omega;
  SearchResult search;
  int n = 0;  // valid contributors
  std::array<int, 8> camera{};
  std::array<PixelPos, 8> pos{};
  std::array<uint32_t, 8> dist{};  // uQ.D
  std::array<TapAddress, 8> addr{};
  std::array<std::array<uint32_t, 3>, 8> sample{};  // R, G, B uQ8.S (after vignetting)
  std::array<uint32_t, 8> weight{};                 // uQ0.R
  bool mrf_fallback = false;
  BoundaryResult boundary;
  std::array<uint32_t, 3> rgb{};  // output R, G, B (8 bits)
  int cycles = 0;
};

class Pipeline {
 public:
  // Checks cfg (IsValid), the rig (check_rig) and the grid (check_grid); throws
  // std::invalid_argument naming the field. `vignetting` defaults to unit tables.
  Pipeline(const HwConfig& cfg, const Rig& rig, const PanoGrid& grid,
           const VignettingTables* vignetting = nullptr);

  // Loads one frame per camera (rig order), checking sizes; stores RGB565.
  void load_frames(const std::vector<cv::Mat>& frames);

  // Renders the panorama with nn, linear or mrf (others: std::invalid_argument).
  PipelineSummary render(pano::Method method, bool boundary, bool progress = false) const;
  PixelTrace trace(int col, int row, pano::Method method, bool boundary) const;

  const HwConfig& config() const { return cfg_; }
  const AngleRegs& angle_registers() const { return regs_; }
  const std::vector<CameraRegs>& cameras() const { return cams_; }
  const SinCosRom& rom() const { return rom_; }
  const VignettingTables& vignetting() const { return vig_; }
  ThroughputOptions timing() const;

 private:
  HwConfig cfg_;
  PanoGrid grid_;
  AngleRegs regs_;
  std::vector<CameraRegs> cams_;
  SinCosRom rom_;
  VignettingTables vig_;
  FrameMemory mem_;
};

// A frame as its RGB565 words (row-major), from 8-bit BGR (or the 8 MSBs of 16-bit).
std::vector<uint16_t> frame_to_rgb565(const cv::Mat& frame);
// The frames the float reference should see: each frame reduced to RGB565 and expanded again with
// rgb565_to_rgb888 (CV_8UC3 BGR), i.e. exactly what the frame memories hold.
std::vector<cv::Mat> rgb565_frames(const std::vector<cv::Mat>& frames);

}  // namespace omma::hw
