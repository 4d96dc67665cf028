// Verilator co-simulation of the panorama pipeline core (hw/rtl/pipeline) against the bit-accurate
// model (src/omma/hw Pipeline): the 24-camera prototype, frames of the simulated colon and of a
// far-field photograph loaded into the frame memories as RGB565, the chip configured only through
// the Table 6.6 channels with the word streams `omma hw export` writes (its .hex files, read back),
// a whole small panorama run, every output pixel compared: 0 differing pixels for nn, linear and
// the MRF evidence, with and without the boundary unit. Also: the cycles the simulation counts against the
// model's throughput (hw::pixel_cycles), the §6.3 raster signals, and corrupt configuration streams.
#include <algorithm>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "pano_chip.h"

namespace omma::hw::rtl {
namespace {

void cosim(const std::vector<cv::Mat>& frames, const PanoGrid& grid, const char* scene, bool near_field,
           const VignettingModel& vm = {}) {
  const HwConfig cfg;  // the widths omma_rtl_gen wrote into omma_hw_pkg.sv
  const VignettingTables vt = make_vignetting_tables(cfg, rig24(), vm);
  Pipeline model(cfg, rig24(), grid, &vt);
  model.load_frames(frames);
  Chip chip;
  chip.load(frames);
  for (const auto& [m, boundary] :
       {std::pair{pano::Method::kNearest, false}, std::pair{pano::Method::kLinear, false},
        std::pair{pano::Method::kMrf, false}, std::pair{pano::Method::kLinear, true}}) {
    SCOPED_TRACE(std::string(scene) + " " + pano::to_string(m) + (boundary ? " +boundary" : ""));
    chip.configure(exported_streams(rig24(), ExportOptions{cfg, grid, m, boundary, vm}));
    ASSERT_FALSE(chip.top().cfg_err) << "code " << int(chip.top().cfg_err_code);
    const PipelineSummary ref = model.render(m, boundary);
    const Chip::Run run = chip.run(grid.width, grid.height);
    EXPECT_EQ(run.pixels, uint64_t(grid.width) * grid.height);
    EXPECT_EQ(run.out_of_order, 0u);
    EXPECT_EQ(run.raster_errors, 0u);
    EXPECT_FALSE(chip.top().unsupported);
    const int diff = differing_pixels(run.pano, ref.pano);
    EXPECT_EQ(diff, 0) << "differing pixels";
    for (int k = 0; k <= 8; ++k)
      EXPECT_EQ(run.contributors[k], ref.stats.contributors[k]) << k << " contributors";
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
                pano::to_string(m).c_str(), boundary ? " +boundary" : "", grid.width, grid.height, diff,
                rtl_cpp, model_cpp);
    EXPECT_LE(rtl_cpp, model_cpp * 1.02 + 0.05);
    EXPECT_GE(rtl_cpp, model_cpp * 0.75);
  }
}

TEST(RtlPano, ColonVr180MatchesModelBitForBit) {
  cosim(colon_frames(), {Projection::kVr180, 72, 72}, "colon", true);
}

TEST(RtlPano, LouvreEquirectMatchesModelBitForBit) {
  cosim(louvre_frames(), {Projection::kEquirect, 128, 32}, "louvre", false);
}

// Vignetting memory loaded over pix_val (radial tables in the SRAM, per-camera channel gains): a
// correction that brightens the corners by up to 60 % and tints each camera differently.
TEST(RtlPano, VignettingTablesMatchModelBitForBit) {
  const HwConfig cfg;
  VignettingModel vm;
  vm.radial = [](int cam, double rho) { return 1.0 + (0.4 + 0.01 * cam) * rho * rho; };
  vm.channel_gain = [](int cam) { return std::array<double, 3>{1.0 + 0.02 * (cam % 5), 1.0, 0.93}; };
  cosim(louvre_frames(), {Projection::kVr180, 48, 48}, "louvre vignetting", false, vm);
}

// Bad configuration streams: the chip flags the first word it cannot take (and hw::decode
// refuses the same stream).
TEST(RtlPano, CorruptConfigurationStreamsAreFlagged) {
  const HwConfig cfg;
  Pipeline model(cfg, rig24(), {Projection::kVr180, 16, 16});
  const WordStreams good = exported_streams(
      rig24(), ExportOptions{cfg, {Projection::kVr180, 16, 16}, pano::Method::kLinear, false, {}});
  EXPECT_EQ(good.reg, encode(cfg, chip_config(model, pano::Method::kLinear, false)).reg);
  struct Case {
    const char* what;
    int code, chan;
    std::function<void(WordStreams&)> corrupt;
  };
  const std::vector<Case> cases = {
      {"write enable clear", 1, 0, [](WordStreams& s) { s.reg[3] &= 0x7FFFFFFFu; }},
      {"unknown register address", 2, 0,
       [](WordStreams& s) { s.reg[3] = 0x80000000u | (0x0123u << 16) | 5u; }},
      {"write to the read-only hw_version", 9, 0,
       [](WordStreams& s) { s.reg.insert(s.reg.begin() + 2, 0x80000000u | (0x7E00u << 16) | 1u); }},
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
}  // namespace omma::hw::rtl
