// The panorama RTL (Verilated pano_top) behind a small C++ harness: clock, reset, the four Table
// 6.6 configuration channels, the frame-memory load port and one panorama run; shared by the
// co-simulation test and the 1080x1080 benchmark.
#pragma once

#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "Vsys.h"
#include "omma/core/frames.h"
#include "omma/core/io.h"
#include "omma/design/prototype.h"
#include "omma/hw/export.h"
#include "omma/hw/pipeline.h"
#include "omma/hw/regmap.h"
#include "omma/isp/link.h"
#include "omma/sim/scene.h"
#include "omma/sim/simulate.h"
#include "omma/testing/test_scenes.h"
#include "verilated.h"

namespace omma::hw::rtl {

inline const Rig& rig24() {
  static const Rig rig = design::thesis_prototype_rig();
  return rig;
}

inline const std::vector<cv::Mat>& colon_frames() {
  static const std::vector<cv::Mat> frames = [] {
    sim::SimulateOptions opt;
    opt.truth = false;
    opt.progress = false;
    const auto scene = sim::make_colon_scene();
    std::vector<cv::Mat> out;
    for (const auto& f : sim::simulate(rig24(), *scene, opt).frames) out.push_back(f.image);
    return out;
  }();
  return frames;
}

inline const std::vector<cv::Mat>& louvre_frames() {
  static const std::vector<cv::Mat> frames = [] {
    return testing::render_frames_u8(
        rig24(), testing::photo_texture(std::string(OMMA_DATA_DIR) + "/louvre.jpg", 1440));
  }();
  return frames;
}

// The RTL with its clock, reset and the four configuration channels.
class Chip {
 public:
  Chip() : top_(std::make_unique<Vsys>(&ctx_)) { reset(); }
  Vsys& top() { return *top_; }
  uint64_t cycles = 0;

  void tick() {
    top_->clk = 0;
    top_->eval();
    top_->clk = 1;
    top_->eval();
    ++cycles;
  }
  void reset() {
    top_->rst = 1;
    top_->reg_valid = top_->pp_valid = top_->cs_valid = top_->pv_valid = 0;
    top_->load_we = 0;
    top_->start = 0;
    top_->chip_valid = 0;
    top_->flush = 0;
    top_->serial_data_in = 0;
    tick();
    tick();
    top_->rst = 0;
  }
  // One word per channel per cycle, the four channels side by side.
  void configure(const WordStreams& s) {
    const size_t n = std::max({s.reg.size(), s.pix_pos.size(), s.cam_search.size(), s.pix_val.size()});
    for (size_t i = 0; i < n; ++i) {
      top_->reg_valid = i < s.reg.size();
      top_->reg_word = i < s.reg.size() ? s.reg[i] : 0;
      top_->pp_valid = i < s.pix_pos.size();
      top_->pp_word = i < s.pix_pos.size() ? s.pix_pos[i] : 0;
      top_->cs_valid = i < s.cam_search.size();
      top_->cs_word = i < s.cam_search.size() ? s.cam_search[i] : 0;
      top_->pv_valid = i < s.pix_val.size();
      top_->pv_word = i < s.pix_val.size() ? s.pix_val[i] : 0;
      tick();
    }
    top_->reg_valid = top_->pp_valid = top_->cs_valid = top_->pv_valid = 0;
  }
  // Loads every camera's RGB565 frame, all cameras in parallel (one word each per cycle).
  void load(const std::vector<cv::Mat>& frames) {
    std::vector<std::vector<uint16_t>> words;
    for (const cv::Mat& f : frames) words.push_back(frame_to_rgb565(f));
    for (size_t a = 0; a < words.at(0).size(); ++a) {
      top_->load_we = (frames.size() >= 32 ? ~0u : (1u << frames.size()) - 1);
      top_->load_addr = uint32_t(a);
      for (size_t cam = 0; cam < words.size(); ++cam) top_->load_data[cam / 2] = 0;
      for (size_t cam = 0; cam < words.size(); ++cam)
        top_->load_data[cam / 2] |= uint32_t(words[cam][a]) << (16 * (cam % 2));
      tick();
    }
    top_->load_we = 0;
  }

  // Every camera's link, one chip per camera per cycle (all streams of the same length), then the
  // end of the streams; waits until the front ends have written their frames.
  void feed_links(const std::vector<isp::ChipStream>& streams) {
    const size_t n = streams.at(0).bytes.size() * 8;
    for (size_t i = 0; i < n; ++i) {
      uint32_t bits = 0;
      for (size_t c = 0; c < streams.size(); ++c)
        if ((streams[c].bytes[i >> 3] >> (7 - (i & 7))) & 1) bits |= 1u << c;
      top_->chip_valid = 1;
      top_->serial_data_in = bits;
      tick();
    }
    top_->chip_valid = 0;
    top_->flush = 1;
    tick();
    for (int guard = 0; top_->cams_busy && guard < 10000000; ++guard) tick();
    for (int k = 0; k < 8; ++k) tick();
  }

  struct Run {
    cv::Mat pano;  // CV_8UC3 BGR
    uint64_t cycles = 0, pixels = 0, out_of_order = 0, raster_errors = 0;
    std::array<uint64_t, 9> contributors{};
  };
  // Starts a panorama and collects it; checks the raster signals on the way.
  Run run(int cols, int rows) {
    Run r;
    r.pano = cv::Mat(rows, cols, CV_8UC3, cv::Scalar::all(0));
    top_->start = 1;
    tick();
    top_->start = 0;
    const uint64_t t0 = cycles;
    uint64_t expect = 0;
    bool in_frame = false;
    while (top_->busy && cycles - t0 < 200ull * cols * rows + 1000) {
      tick();
      if (top_->pix_valid) {
        const int c = top_->pix_col, w = top_->pix_row;
        if (uint64_t(w) * cols + c != expect) ++r.out_of_order;
        ++expect;
        r.pano.at<cv::Vec3b>(w, c) = cv::Vec3b(top_->pix_b, top_->pix_g, top_->pix_r);
        ++r.contributors[std::min<int>(top_->pix_n, 8)];
        ++r.pixels;
      }
      // §6.3: one clock_out per pixel (one cycle after it leaves the pixel value unit), hblank high
      // only between lines, vblank low only inside the frame
      if (top_->clock_out) {
        in_frame = true;
        if (top_->hblank_out || top_->vblank_out || !top_->de_out) ++r.raster_errors;
      }
    }
    r.cycles = cycles - t0;
    tick();
    tick();
    if (!in_frame || !top_->vblank_out || !top_->hblank_out) ++r.raster_errors;
    return r;
  }

 private:
  VerilatedContext ctx_;
  std::unique_ptr<Vsys> top_;
};

// The configuration the way a chip gets it: `omma hw export` (hw::export_chip) writes the folder,
// and its four word-stream files (regs.hex, pix_pos.hex, cam_search.hex, pix_val.hex: $readmemh
// text) are read back exactly as written.
inline WordStreams exported_streams(const Rig& rig, const ExportOptions& o) {
  static std::atomic<int> n{0};
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() /
      ("omma_rtl_export_" + std::to_string(::getpid()) + "_" + std::to_string(n++));
  export_chip(rig, o, dir);
  WordStreams s;
  s.reg = parse_words(read_text_file(dir / "regs.hex"), "regs.hex");
  s.pix_pos = parse_words(read_text_file(dir / "pix_pos.hex"), "pix_pos.hex");
  s.cam_search = parse_words(read_text_file(dir / "cam_search.hex"), "cam_search.hex");
  s.pix_val = parse_words(read_text_file(dir / "pix_val.hex"), "pix_val.hex");
  std::filesystem::remove_all(dir);
  return s;
}

inline ChipConfig chip_config(const Pipeline& p, pano::Method m, bool boundary) {
  ChipConfig c;
  c.angles = p.angle_registers();
  c.frame_width = p.cameras()[0].width;
  c.frame_height = p.cameras()[0].height;
  c.method = m;
  c.boundary = boundary;
  c.boundary_threshold = p.config().boundary_threshold;
  c.cameras = p.cameras();
  c.vignetting = p.vignetting();
  c.vig_shift = p.vignetting().vig_shift;
  return c;
}

inline int differing_pixels(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat d;
  cv::compare(a.reshape(1), b.reshape(1), d, cv::CMP_NE);
  d = d.reshape(3);
  int n = 0;
  for (int y = 0; y < d.rows; ++y)
    for (int x = 0; x < d.cols; ++x) n += d.at<cv::Vec3b>(y, x) != cv::Vec3b(0, 0, 0);
  return n;
}

}  // namespace omma::hw::rtl
