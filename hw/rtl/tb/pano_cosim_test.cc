// Verilator co-simulation of the panorama pipeline core (hw/rtl/pipeline) against the bit-accurate
// model (src/omma/hw Pipeline): the 24-camera prototype, frames of the simulated colon and of a
// far-field photograph loaded into the frame memories as RGB565, the chip configured only through
// the Table 6.6 channels with the word streams hw::encode writes (what `omma hw export` writes),
// a whole small panorama run, every output pixel compared: 0 differing pixels for nn and linear,
// with and without the boundary unit. Also: the cycles the simulation counts against the model's
// throughput (hw::pixel_cycles), the §6.3 raster signals, and corrupt configuration streams.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "Vpano.h"
#include "omma/core/frames.h"
#include "omma/design/prototype.h"
#include "omma/hw/pipeline.h"
#include "omma/hw/regmap.h"
#include "omma/pano/test_scene.h"
#include "omma/sim/scene.h"
#include "omma/sim/simulate.h"
#include "verilated.h"

namespace omma::hw {
namespace {

const Rig& rig24() {
  static const Rig rig = design::thesis_prototype_rig();
  return rig;
}

const std::vector<cv::Mat>& colon_frames() {
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

const std::vector<cv::Mat>& louvre_frames() {
  static const std::vector<cv::Mat> frames = [] {
    const cv::Mat tex = pano::testing::photo_texture(std::string(OMMA_DATA_DIR) + "/louvre.jpg", 1440);
    std::vector<cv::Mat> out;
    for (const cv::Mat& f : pano::testing::render_frames(rig24(), tex)) out.push_back(to_u8(f));
    return out;
  }();
  return frames;
}

// The RTL with its clock, reset and the four configuration channels.
class Chip {
 public:
  Chip() : top_(std::make_unique<Vpano>(&ctx_)) { reset(); }
  Vpano& top() { return *top_; }
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
  void load(const HwConfig& cfg, const std::vector<cv::Mat>& frames) {
    for (size_t cam = 0; cam < frames.size(); ++cam) {
      const std::vector<uint16_t> words = frame_to_rgb565(frames[cam]);
      for (size_t a = 0; a < words.size(); ++a) {
        top_->load_we = 1;
        top_->load_addr = uint32_t(cam << cfg.frame_addr_bits) | uint32_t(a);
        top_->load_data = words[a];
        tick();
      }
    }
    top_->load_we = 0;
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
  std::unique_ptr<Vpano> top_;
};

ChipConfig chip_config(const Pipeline& p, pano::Method m, bool boundary) {
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

int differing_pixels(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat d;
  cv::compare(a.reshape(1), b.reshape(1), d, cv::CMP_NE);
  d = d.reshape(3);
  int n = 0;
  for (int y = 0; y < d.rows; ++y)
    for (int x = 0; x < d.cols; ++x) n += d.at<cv::Vec3b>(y, x) != cv::Vec3b(0, 0, 0);
  return n;
}

void cosim(const std::vector<cv::Mat>& frames, const PanoGrid& grid, const char* scene, bool near_field) {
  const HwConfig cfg;  // the widths omma_rtl_gen wrote into omma_hw_pkg.sv
  Pipeline model(cfg, rig24(), grid);
  model.load_frames(frames);
  Chip chip;
  chip.load(cfg, frames);
  for (const auto& [m, boundary] : {std::pair{pano::Method::kNearest, false}, std::pair{pano::Method::kLinear, false},
                                    std::pair{pano::Method::kLinear, true}}) {
    SCOPED_TRACE(std::string(scene) + " " + pano::to_string(m) + (boundary ? " +boundary" : ""));
    chip.configure(encode(cfg, chip_config(model, m, boundary)));
    ASSERT_FALSE(chip.top().cfg_err) << "code " << int(chip.top().cfg_err_code);
    const PipelineResult ref = model.render(m, boundary);
    const Chip::Run run = chip.run(grid.width, grid.height);
    EXPECT_EQ(run.pixels, uint64_t(grid.width) * grid.height);
    EXPECT_EQ(run.out_of_order, 0u);
    EXPECT_EQ(run.raster_errors, 0u);
    EXPECT_FALSE(chip.top().unsupported);
    const int diff = differing_pixels(run.pano, ref.pano);
    EXPECT_EQ(diff, 0) << "differing pixels";
    for (int k = 0; k <= 8; ++k) EXPECT_EQ(run.contributors[k], ref.stats.contributors[k]) << k << " contributors";
    // not a trivial panorama: most pixels are seen and lit; the near field has object boundaries
    EXPECT_GT(cv::countNonZero(run.pano.reshape(1)), int(run.pano.total()));
    if (boundary && near_field) {
      EXPECT_GT(ref.stats.boundary_pixels, 0u);
    }
    // cycles: the model's Th_sys per pixel (max of angle 2, Cartesian 3, memory 2, search and
    // pixel value n) summed; the RTL's direction FIFO lends spare cycles, so it may take fewer
    const double px = double(grid.width) * grid.height;
    const double rtl_cpp = double(run.cycles) / px, model_cpp = double(ref.stats.cycles) / px;
    std::printf("%s %s%s %dx%d: %d differing pixels; cycles per pixel RTL %.3f, model %.3f\n", scene,
                pano::to_string(m).c_str(), boundary ? " +boundary" : "", grid.width, grid.height, diff, rtl_cpp,
                model_cpp);
    EXPECT_LE(rtl_cpp, model_cpp * 1.02 + 0.05);
    EXPECT_GE(rtl_cpp, model_cpp * 0.75);
  }
}

TEST(RtlPano, ColonVr180MatchesModelBitForBit) { cosim(colon_frames(), {Projection::kVr180, 72, 72}, "colon", true); }

TEST(RtlPano, LouvreEquirectMatchesModelBitForBit) {
  cosim(louvre_frames(), {Projection::kEquirect, 128, 32}, "louvre", false);
}

// Bad configuration streams: the chip flags the first word it cannot take (and hw::decode
// refuses the same stream).
TEST(RtlPano, CorruptConfigurationStreamsAreFlagged) {
  const HwConfig cfg;
  Pipeline model(cfg, rig24(), {Projection::kVr180, 16, 16});
  const WordStreams good = encode(cfg, chip_config(model, pano::Method::kLinear, false));
  struct Case {
    const char* what;
    int code, chan;
    std::function<void(WordStreams&)> corrupt;
  };
  const std::vector<Case> cases = {
      {"write enable clear", 1, 0, [](WordStreams& s) { s.reg[3] &= 0x7FFFFFFFu; }},
      {"unknown register address", 2, 0, [](WordStreams& s) { s.reg[3] = 0x80000000u | (0x0123u << 16) | 5u; }},
      {"value wider than its register", 3, 0,
       [](WordStreams& s) { s.reg[0] = 0x80000000u | (0x1800u << 16) | 0xFFFFu; }},  // 11-bit row count
      {"array word with bits [31:25] set", 4, 1, [](WordStreams& s) { s.pix_pos[5] |= 1u << 27; }},
      {"array select beyond the arrays", 5, 2, [](WordStreams& s) { s.cam_search[2] |= 15u << 21; }},
      {"camera beyond the cameras built", 6, 1, [](WordStreams& s) { s.pix_pos[7] |= 31u << 16; }},
      {"vignetting address beyond the memory", 8, 3, [](WordStreams& s) { s.pix_val[0] |= 0x7FFFu << 16; }},
  };
  Chip chip;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    WordStreams s = good;
    c.corrupt(s);
    EXPECT_THROW(decode(cfg, s), std::invalid_argument);
    chip.reset();
    chip.configure(s);
    EXPECT_TRUE(chip.top().cfg_err);
    EXPECT_EQ(int(chip.top().cfg_err_code), c.code);
    EXPECT_EQ(int(chip.top().cfg_err_chan), c.chan);
  }
  chip.reset();
  chip.configure(good);
  EXPECT_FALSE(chip.top().cfg_err);
}

}  // namespace
}  // namespace omma::hw
