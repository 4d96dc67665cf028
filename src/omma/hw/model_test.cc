// The thesis's numbers (§5.4.3-5.4.4, ch. 6) from the throughput and memory models, the register
// map of Table 6.7 / 6.6, export/import round trips and bad-input errors.
#include <cmath>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "omma/core/io.h"
#include "omma/design/prototype.h"
#include "omma/hw/export.h"
#include "omma/hw/memory.h"
#include "omma/hw/regmap.h"
#include "omma/hw/throughput.h"
#include "omma/hw/width_sweep.h"
#include "omma/testing/expect.h"

namespace omma::hw {
namespace {

TEST(Throughput, ThesisFigures) {
  ThroughputOptions o;
  // 20 cameras, 1024 x 1024 at 25 fps, 1 cycle per camera: 524.288 MHz ("a minimum of 525 MHz").
  o.cameras = 20;
  o.unrolled = false;
  o.width = o.height = 1024;
  ThroughputSummary t = throughput(o);
  EXPECT_EQ(t.th_sys, 20);
  EXPECT_NEAR(t.fmin_mhz, 524.288, 1e-9);
  // First implementation at 100 MHz, 24 cameras searched one per cycle: 166,666 px, 408 x 408.
  o.cameras = 24;
  o.clock_mhz = 100;
  t = throughput(o);
  EXPECT_EQ(t.th_sys, 24);
  EXPECT_EQ(static_cast<int>(t.pixels_per_frame_at_clock), 166666);
  EXPECT_EQ(t.square_side_at_clock, 408);
  // The 730 x 182 (360 x 90 deg) the text quotes is 132,860 px: it needs Th_sys = 30, not 24.
  EXPECT_LT(730 * 182, t.pixels_per_frame_at_clock * 0.8);
  EXPECT_EQ(static_cast<int>(100e6 / (25 * 30)), 133333);
  // Unrolled (24 parallel dot products + priority encoder, 3 table sets): Th_sys = 4, 25.72 fps
  // at 120 MHz for 1080 x 1080.
  o.unrolled = true;
  o.clock_mhz = 120;
  o.width = o.height = 1080;
  t = throughput(o);
  EXPECT_EQ(t.th_sys, 4);
  EXPECT_NEAR(t.fps_at_clock, 25.72, 0.005);
  EXPECT_EQ(t.blocks[0].th, 2);  // angle generation
  EXPECT_EQ(t.blocks[1].th, 3);  // Cartesian, three table sets
  o.table_sets = 1;
  EXPECT_EQ(throughput(o).blocks[1].th, 9);
  o.table_sets = 3;
  // 24 -> 4 cycles per pixel: the "6x frame rate increase".
  ThroughputOptions before = o;
  before.unrolled = false;
  EXPECT_NEAR(throughput(o).fps_at_clock / throughput(before).fps_at_clock, 6.0, 1e-12);
  // The ASIC's 175 MHz for 1080 x 1080 at 25 fps implies Th_sys = 6 (174.96 MHz).
  o.max_contributors = 6;
  EXPECT_NEAR(throughput(o).fmin_mhz, 174.96, 1e-9);
  EXPECT_EQ(std::lround(throughput(o).fmin_mhz), 175);
  std::string err;
  o.table_sets = 2;
  EXPECT_FALSE(o.IsValid(&err));
  EXPECT_NE(err.find("table_sets"), std::string::npos);
}

TEST(ThesisTables, WhereThePrintedNumbersDisagree) {
  // Table 5.7 repeats Table 5.6's utilisation row (77 % slices, 3 % DSP) although its totals grew:
  // 59,849 of 75,900 slices is 78.9 %, 185 of 2,800 DSPs 6.6 %.
  EXPECT_NEAR(100.0 * 58568 / 75900, 77.2, 0.05);  // Table 5.6: consistent
  EXPECT_NEAR(100.0 * 59849 / 75900, 78.85, 0.01);
  EXPECT_NEAR(100.0 * 185 / 2800, 6.61, 0.01);
  // §5.4.2: the probabilistic (MRF) hardware is "4x the hardware resources shown in Table 5.5"
  // (dot product 5 + vector magnitude 296 + pipeline registers 78 slices) = 1,516 slices, which is
  // 2.6 % of the 58,568-slice system, not "less than 1 %".
  const int table55_slices = 5 + 296 + 78, table55_regs = 18 + 528 + 352, table55_luts = 16 + 960 + 0,
            table55_dsp = 3 + 3;
  EXPECT_EQ(4 * table55_slices, 1516);
  EXPECT_EQ(4 * table55_regs, 3592);  // "3600 Slice registers"
  EXPECT_EQ(4 * table55_luts, 3904);  // "roughly 4000 LUTs"
  EXPECT_EQ(4 * table55_dsp, 24);     // "24 DSP blocks"
  EXPECT_NEAR(100.0 * 4 * table55_slices / 58568, 2.59, 0.01);
  // Table 5.6/5.7 DSP totals are the row sums; slices and LUTs exceed them by 202 / 369.
  EXPECT_EQ(0 + 0 + 43 + 27 + 16, 86);
  EXPECT_EQ(0 + 0 + 136 + 27 + 16, 179);
  EXPECT_EQ(2448 - (62 + 85 + 1496 + 371 + 232), 202);
  EXPECT_EQ(3614 - (62 + 85 + 2662 + 371 + 232), 202);
  EXPECT_EQ(6928 - (167 + 177 + 4510 + 1038 + 667), 369);
  EXPECT_EQ(10586 - (167 + 177 + 8168 + 1038 + 667), 369);
}

TEST(Memory, Table64ReproducedFromTheConfiguration) {
  const MemoryReport r = memory_report({});
  EXPECT_NEAR(r.total_kbytes, 3415.552, 1e-9);
  EXPECT_NEAR(r.total_area_mm2, 25.620, 1e-9);
  ASSERT_EQ(r.rows.size(), 8u);
  const double kb[8] = {8.192, 36.864, 61.440, 7.680, 3145.728, 16.384, 122.880, 16.384};
  const double area[8] = {0.080, 1.286, 0.921, 0.313, 22.681, 0.066, 0.251, 0.022};
  for (int i = 0; i < 8; ++i) {
    EXPECT_NEAR(r.rows[i].kbytes, kb[i], 1e-9) << r.rows[i].block;
    EXPECT_NEAR(r.rows[i].area_mm2, area[i], 1e-12) << r.rows[i].block;
    EXPECT_FALSE(r.rows[i].area_estimated);
  }
  // Table 6.10: macro area as % of the 32.639 mm^2 core.
  EXPECT_NEAR(r.macro_area_percent_of_core(32.639, "frame_mem_2"), 69.490, 0.002);
  EXPECT_NEAR(r.macro_area_percent_of_core(32.639, "rgb_line_buffer"), 3.939, 0.002);
  EXPECT_NEAR(100 * r.total_area_mm2 / 32.639, 78.494, 0.002);
  // Frame memories: 250 x 250 x 16 bit x 24 = 24 Mbit.
  EXPECT_DOUBLE_EQ(r.frame_memory_bits, 24e6);
  // Table 6.3 pins 151 / 125.
  EXPECT_EQ(r.pins_initial, 151);
  EXPECT_EQ(r.pins_with_io, 125);
  // Table 6.5 / 6.8.
  EXPECT_EQ(r.fifos[0].words, 2048);
  EXPECT_EQ(r.fifos[1].words, 256);
  EXPECT_EQ(r.fifos[2].words, 1024);
  const double wkb[9] = {0.320, 1.280, 4.096, 0.768, 131.072, 4.096, 4.096, 16.384, 16.384};
  for (int i = 0; i < 9; ++i) EXPECT_NEAR(r.wrappers[i].kbytes, wkb[i], 1e-9) << r.wrappers[i].name;
  EXPECT_EQ(r.wrappers[0].name, "fifo_memory_single_w10a8");
  EXPECT_EQ(r.wrappers[2].name, "fifo_memory_single_w16a11");
}

TEST(Memory, PlannerForOtherRigs) {
  MemoryOptions o;
  // The thesis FPGA: 24 frames of 62,500 x 16 bit in 31 blocks each; fits the XC7VX485T.
  FpgaPlan p = plan_fpga(o);
  EXPECT_EQ(p.frame_blocks_per_camera, 31);
  EXPECT_TRUE(p.fits);
  EXPECT_NEAR(p.clock_mhz, 116.64, 1e-9);
  EXPECT_EQ(bram36_blocks(62500, 16), 31);
  EXPECT_EQ(bram36_blocks(1024, 36), 1);
  EXPECT_EQ(bram36_blocks(1025, 36), 2);
  // 40-camera CVT rig: 40 x 31 frame blocks alone exceed 1030.
  o.cameras = 40;
  p = plan_fpga(o);
  EXPECT_FALSE(p.fits);
  EXPECT_GT(p.frame_blocks, 1030);
  // Another configuration gets an estimated area that grows with the memory.
  const MemoryReport big = memory_report(o);
  EXPECT_GT(big.total_area_mm2, 25.62 * 1.5);
  // 10-bit RGB frames (30 bpp) on 24 cameras do not fit either; 4K output needs a faster clock.
  MemoryOptions t = {};
  t.bits_per_pixel = 30;
  EXPECT_FALSE(plan_fpga(t).fits);
  t = {};
  t.pano_width = 3840;
  t.pano_height = 2160;
  EXPECT_NEAR(plan_fpga(t).clock_mhz, 829.44, 1e-9);
  EXPECT_TRUE(memory_report(t).rows[0].area_estimated);  // 2 x 4096 x 16 line buffers
}

TEST(RegisterMap, Table67Defaults) {
  const ThesisAngleDefaults d = thesis_angle_defaults();
  EXPECT_EQ(d.max_phi, 0x17F8u);
  EXPECT_EQ(d.min_phi, 0x740u);
  EXPECT_EQ(d.k_phi, 0x00Au);
  EXPECT_EQ(d.columns_from_phi(), 428);
  EXPECT_EQ(d.columns_from_phi(), static_cast<int>(d.col_cnt));
  // The rows disagree by one: (0xDF8 - 0x300) / 6 = 468 = panorama_row_cnt - 1.
  EXPECT_EQ(d.rows_from_theta(), 468);
  EXPECT_EQ(d.row_cnt, 469u);
  // 13-bit angles: k_phi = 4 over 1080 columns spans 189.84 deg (the App. C "190 deg" videos).
  EXPECT_NEAR(4 * 1080 * 360.0 / 8192, 189.84, 0.005);
  // Array addresses: base + 0x20 word + camera fit Table 6.7's ranges exactly.
  HwConfig cfg;
  EXPECT_EQ(array_address(cfg, 0, 0, 0), 0x0800u);
  EXPECT_EQ(array_address(cfg, 0, 2, 23), 0x0857u);   // pixel_e_u 0x0800-0x0857
  EXPECT_EQ(array_address(cfg, 0, 12, 23), 0x0997u);  // pixel_cc ends at 0x0997
  EXPECT_EQ(array_address(cfg, 1, 3, 23), 0x1077u);   // near_cos_alpha_srch ends at 0x1077
  EXPECT_EQ(array_address(cfg, 1, 0, 0), 0x1000u);
}

TEST(RegisterMap, ThesisAngleRegistersFromTheGrid) {
  // With 13-bit angles a 1080-column vr180 grid needs k = 8192 / 2160 = 3.79 -> 4: the chip then
  // covers 190 deg, not 180 (../shared/notes/hw-spec.md: "M = 11 is sufficient" does not hold for 1080 over
  // 180 deg).
  HwConfig cfg = thesis_config();
  const AngleRegs r = angle_regs(cfg, {Projection::kVr180, 1080, 1080});
  EXPECT_EQ(r.k_phi, 8192u - 4u);  // -4 mod 2^13: the longitude decreases to the right (conventions.h (G2))
  EXPECT_EQ(r.k_theta, 4u);
}

Rig distorted_rig() {
  Rig rig = design::thesis_prototype_rig();
  for (size_t i = 0; i < rig.cameras.size(); ++i) {
    auto& c = rig.cameras[i];
    c.in.k = {-0.2 + 0.01 * i, 0.05, 0.001 * i, -0.002, 0.01};
    c.in.fu += 0.37 * i;
    c.in.fv += 0.21 * i;
    c.in.cu += 0.11 * i;
    c.in.cv -= 0.07 * i;
  }
  return rig;
}

TEST(Export, RoundTripWithinQuantisation) {
  const auto dir = std::filesystem::temp_directory_path() / "omma_hw_export_test";
  std::filesystem::remove_all(dir);
  const Rig rig = distorted_rig();
  ExportOptions o;
  o.method = pano::Method::kMrf;
  o.grid = {Projection::kEquirect, 1920, 512};
  o.vignetting.radial = [](int, double rho) { return 1 + 0.5 * rho * rho; };
  o.vignetting.channel_gain = [](int cam) { return std::array<double, 3>{1.0, 1.0 + 0.001 * cam, 0.9}; };
  const ExportSummary s = export_chip(rig, o, dir);
  EXPECT_EQ(s.pix_pos_words, 24u * 15u);
  EXPECT_EQ(s.cam_search_words, 24u * 7u);
  EXPECT_EQ(s.pix_val_words, 24u * (256u + 3u));
  for (const char* f : {"config.json", "regs.hex", "pix_pos.hex", "cam_search.hex", "pix_val.hex",
                        "sin_rom.hex", "cos_rom.coe", "vig_mem.hex", "omma_hw_config.h", "config_stream.txt"})
    EXPECT_TRUE(std::filesystem::exists(dir / f)) << f;
  const ImportSummary im = import_chip(dir);
  EXPECT_EQ(im.chip.method, pano::Method::kMrf);
  EXPECT_EQ(im.grid.width, 1920);
  EXPECT_EQ(im.chip.angles.k_phi, s.chip.angles.k_phi);
  EXPECT_EQ(im.chip.vignetting.radial, s.chip.vignetting.radial);
  EXPECT_EQ(im.chip.vignetting.channel, s.chip.vignetting.channel);
  const RigDifference d = rig_difference(rig, im.rig), b = quantisation_bound(im.config);
  EXPECT_LE(d.axis_deg, b.axis_deg);
  EXPECT_LE(d.position_mm, b.position_mm);
  EXPECT_LE(d.focal_px, b.focal_px);
  EXPECT_LE(d.centre_px, b.centre_px);
  EXPECT_LE(d.k, b.k);
  EXPECT_LE(d.aov_deg, b.aov_deg);
  EXPECT_GT(d.focal_px, 0.0);  // the quantisation is seen
  // Register-level round trip is exact.
  const auto regs = camera_regs(im.config, im.rig);
  for (size_t i = 0; i < regs.size(); ++i) {
    EXPECT_EQ(regs[i].fu, s.chip.cameras[i].fu);
    EXPECT_EQ(regs[i].k, s.chip.cameras[i].k);
    EXPECT_EQ(regs[i].c, s.chip.cameras[i].c);
  }
  // sin ROM file: 4096 words of 4 hex digits; word 0 = 0, cos word 0 = 0x8000.
  const std::string sin_text = read_text_file(dir / "sin_rom.hex");
  EXPECT_EQ(parse_words(sin_text, "sin").size(), 4096u);
  EXPECT_EQ(parse_words(read_text_file(dir / "cos_rom.hex"), "cos")[0], 0x8000u);
  std::filesystem::remove_all(dir);
}

TEST(Export, CorruptStreamsNameTheField) {
  const auto dir = std::filesystem::temp_directory_path() / "omma_hw_corrupt_test";
  std::filesystem::remove_all(dir);
  ExportOptions o;
  export_chip(design::thesis_prototype_rig(), o, dir);
  auto expect_error = [&](const std::string& file, const std::string& text, const std::string& needle) {
    const std::string saved = read_text_file(dir / file);
    write_text_atomically(dir / file, text);
    try {
      import_chip(dir);
      ADD_FAILURE() << "no error for " << needle;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
    write_text_atomically(dir / file, saved);
  };
  const std::string pp = read_text_file(dir / "pix_pos.hex");
  expect_error("pix_pos.hex", pp + "zz12\n", "not a 32-bit hex word");
  expect_error("pix_pos.hex", pp + "01E00000\n", "array select 15");
  expect_error("pix_pos.hex", "00000000\n", "missing array words");
  expect_error("regs.hex", "00001800\n", "write enable");
  expect_error("regs.hex", read_text_file(dir / "regs.hex") + "87FF0000\n", "unknown register address");
  expect_error("pix_val.hex", "FFFF0000\n", "beyond the vignetting memory");
  expect_error("regs.hex", read_text_file(dir / "regs.hex") + "FE000002\n", "read-only");
  EXPECT_NO_THROW(import_chip(dir));
  std::filesystem::remove_all(dir);
}

TEST(Config, BadWidthsNameTheField) {
  std::string err;
  HwConfig c;
  c.sincos_addr_bits = 12;
  c.angle_bits = 13;  // a table too big for its angle bits
  EXPECT_FALSE(c.IsValid(&err));
  EXPECT_NE(err.find("angle_bits"), std::string::npos);
  c = {};
  c.proj_frac_bits = 17;
  EXPECT_FALSE(c.IsValid(&err));
  EXPECT_NE(err.find("proj_frac_bits"), std::string::npos);
  c = {};
  c.recip_bits = 40;
  EXPECT_FALSE(c.IsValid(&err));
  EXPECT_NE(err.find("recip_bits"), std::string::npos);
  // An address space too small for the frames, a rig with more cameras than the encoder holds.
  c = {};
  c.frame_addr_bits = 15;
  try {
    check_rig(c, design::thesis_prototype_rig());
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("frame_addr_bits"), std::string::npos);
  }
  c = {};
  c.camera_bits = 4;
  try {
    check_rig(c, design::thesis_prototype_rig());
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("camera_bits"), std::string::npos);
  }
  // The grid needs one angle code per pixel step.
  c = {};
  c.angle_bits = 12;
  c.sincos_addr_bits = 10;
  EXPECT_THROW(check_grid(c, {Projection::kVr180, 4096, 4096}), std::invalid_argument);
  EXPECT_THROW(config_from_json(nlohmann::json{{"angle_bitz", 3}}), std::invalid_argument);
}

using testing::refusal;

TEST(Options, ExportOptionsRefuseBadValues) {
  ExportOptions o;
  EXPECT_TRUE(o.IsValid());
  o.grid.height = 0;
  EXPECT_FALSE(o.IsValid());
  const Rig rig = design::thesis_prototype_rig();
  EXPECT_EQ(
      refusal([&] { export_chip(rig, o, std::filesystem::temp_directory_path() / "omma_never_written"); }),
      "panorama size must be positive");
}

TEST(Options, WidthSweepOptionsRefuseBadValues) {
  WidthSweepOptions o;
  EXPECT_TRUE(o.IsValid());
  o.params = {{"angle_bits", {12, 10}}};
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("ascending"), std::string::npos);
  const Rig rig = design::thesis_prototype_rig();
  EXPECT_NE(refusal([&] { run_sweep(rig, {}, o); }).find("width sweep: "), std::string::npos);
}

TEST(Options, ThroughputOptionsAreCheckedWhereTheyEnter) {
  ThroughputOptions o;
  o.fps = 0;
  EXPECT_NE(refusal([&] { throughput(o); }).find("fps"), std::string::npos);
}

}  // namespace
}  // namespace omma::hw
