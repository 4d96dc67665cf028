// Unit tests of the integer blocks against the floating-point camera model they implement.
#include "omma/hw/blocks.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "omma/core/camera.h"
#include "omma/design/prototype.h"
#include "omma/hw/fixed.h"
#include "omma/hw/pipeline.h"
#include "omma/hw/tables.h"
#include "omma/isp/color.h"
#include "omma/pano/contributors.h"

namespace omma::hw {
namespace {

TEST(Fixed, RoundingRules) {
  EXPECT_EQ(rshift_round(5, 1), 3);    // 2.5 -> 3
  EXPECT_EQ(rshift_round(-5, 1), -2);  // -2.5 -> -2 (half up)
  EXPECT_EQ(rshift_round(-6, 1), -3);
  EXPECT_EQ(div_round(5, 2), 3);
  EXPECT_EQ(div_round(-5, 2), -3);  // half away from zero
  EXPECT_EQ(div_round(7, 3), 2);
  EXPECT_EQ(align_frac(3, 2, 4), 12);
  EXPECT_EQ(align_frac(13, 4, 2), 3);
  EXPECT_EQ(bit_length(0), 0);
  EXPECT_EQ(bit_length(1), 1);
  EXPECT_EQ(bit_length(255), 8);
}

TEST(Fixed, BitSerialReferencesAgreeWithFastForms) {
  std::mt19937_64 rng(3);
  for (int i = 0; i < 20000; ++i) {
    const uint64_t n = rng() >> (rng() % 40 + 16), d = (rng() >> (rng() % 50 + 14)) + 1;
    const uint64_t q = udiv_floor(n, d);
    EXPECT_EQ(restoring_divide(n, d, 64, 64), q);
    const uint64_t v = rng() >> (rng() % 62 + 2);
    EXPECT_EQ(isqrt_restoring(v, 64), isqrt_floor(v)) << v;
  }
  for (uint64_t v : {0ull, 1ull, 3ull, 4ull, (1ull << 52) - 1, (1ull << 60) + 12345, ~0ull >> 1}) {
    const uint64_t s = isqrt_floor(v);
    EXPECT_LE(s * s, v);
    EXPECT_GT((s + 1) * (s + 1), v);
  }
}

TEST(Rgb565, SameRuleAsTheIsp) {
  cv::Mat img(16, 16, CV_8UC3);
  cv::randu(img, 0, 256);
  const cv::Mat packed = isp::pack_rgb565(img), back = isp::unpack_rgb565(packed);
  for (int r = 0; r < 16; ++r)
    for (int c = 0; c < 16; ++c) {
      const cv::Vec3b p = img.at<cv::Vec3b>(r, c);
      const uint16_t w = rgb888_to_rgb565(p[2], p[1], p[0]);
      EXPECT_EQ(w, packed.at<uint16_t>(r, c));
      const auto rgb = rgb565_to_rgb888(w);
      EXPECT_EQ(cv::Vec3b(rgb[2], rgb[1], rgb[0]), back.at<cv::Vec3b>(r, c));
    }
  EXPECT_EQ(rgb565_to_rgb888(0xFFFF), (std::array<uint32_t, 3>{255, 255, 255}));
}

TEST(Rgb565, SixteenBitFramesKeepTheirEightMostSignificantBits) {
  cv::Mat f(1, 2, CV_16UC3);
  f.at<cv::Vec3w>(0, 0) = cv::Vec3w(0x01FF, 0x04FF, 0xFFFF);  // B, G, R: MSBs 1, 4, 255 (no rounding)
  f.at<cv::Vec3w>(0, 1) = cv::Vec3w(0x0800, 0x0000, 0x07FF);
  const std::vector<uint16_t> w = frame_to_rgb565(f);
  EXPECT_EQ(w[0], rgb888_to_rgb565(255, 4, 1));
  EXPECT_EQ(w[1], rgb888_to_rgb565(7, 0, 8));
}

// Max component error of the Cartesian unit over many angles, against eq. 5.15 in double.
double cartesian_error(const HwConfig& cfg, bool printed_eq_5_17 = false) {
  const SinCosRom rom = make_sincos_rom(cfg);
  std::mt19937 rng(11);
  double worst = 0;
  const double turn = std::ldexp(1.0, cfg.angle_bits), unit = std::ldexp(1.0, cfg.sincos_word_bits);
  for (int i = 0; i < 20000; ++i) {
    Angles a{static_cast<uint32_t>(rng() % static_cast<uint64_t>(turn)),
             static_cast<uint32_t>(rng() % static_cast<uint64_t>(turn))};
    const Omega o = cartesian(cfg, rom, a, AxisMap::kDome);
    const double th = 2 * kPi * a.theta / turn, ph = 2 * kPi * a.phi / turn;
    const Vec3 w = direction_from_spherical(th, ph);
    double wy = o.w[1] / unit;
    if (printed_eq_5_17) wy = (std::cos(th - ph) - std::sin(th + ph)) / 2;  // as printed
    worst = std::max(
        {worst, std::abs(o.w[0] / unit - w.x()), std::abs(wy - w.y()), std::abs(o.w[2] / unit - w.z())});
  }
  return worst;
}

TEST(Cartesian, SumDifferenceIdentitiesWithinTheTableResolution) {
  HwConfig cfg;
  // Address rounding: half a table step (pi/2 / 2^T / 2) of angle error on each of two terms.
  const double step = (kPi / 2) / cfg.quarter_entries();
  EXPECT_LT(cartesian_error(cfg), step * 0.5 + std::ldexp(1.0, -cfg.sincos_word_bits + 1));
  EXPECT_GT(cartesian_error(cfg), step * 0.05);  // and it does depend on the table
  // eq. 5.17 as printed (cos(t-p) - sin(t+p)) / 2 is not sin t sin p: errors of order 1.
  EXPECT_GT(cartesian_error(cfg, true), 0.5);
  HwConfig thesis = thesis_config();
  EXPECT_LT(cartesian_error(thesis), (kPi / 2) / thesis.quarter_entries());
}

TEST(Cartesian, Vr180AxisMapMatchesTheGrid) {
  HwConfig cfg;
  const SinCosRom rom = make_sincos_rom(cfg);
  const PanoGrid grid{Projection::kVr180, 90, 60};
  const AngleRegs regs = angle_regs(cfg, grid);
  const double unit = std::ldexp(1.0, cfg.sincos_word_bits);
  for (int row = 0; row < grid.height; row += 7)
    for (int col = 0; col < grid.width; col += 5) {
      const Omega o = cartesian(cfg, rom, angles_at(cfg, regs, col, row), regs.axes);
      const Vec3 w = grid.pixel_direction(col, row);
      for (int k = 0; k < 3; ++k) EXPECT_NEAR(o.w[k] / unit, w[k], 1e-3) << col << "," << row;
    }
  // Every longitude-latitude grid (conventions.h (G1): phi decreases to the right, the column step
  // held as its two's complement).
  for (const PanoGrid& eq :
       {PanoGrid{Projection::kEquirect, 96, 24}, PanoGrid{Projection::kEquirectFull, 96, 48},
        PanoGrid{Projection::kEquirect100, 90, 25}}) {
    const AngleRegs r2 = angle_regs(cfg, eq);
    for (int row = 0; row < eq.height; row += 5)
      for (int col = 0; col < eq.width; col += 7) {
        const Omega o = cartesian(cfg, rom, angles_at(cfg, r2, col, row), r2.axes);
        const Vec3 w = eq.pixel_direction(col, row);
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(o.w[k] / unit, w[k], 1e-3) << to_string(eq.projection);
      }
  }
}

// Camera search, distance and projection against the float camera model on the 24-camera rig.
TEST(Blocks, SearchDistanceProjectionMatchTheFloatModel) {
  HwConfig cfg;
  const Rig rig = design::thesis_prototype_rig();
  const auto cams = camera_regs(cfg, rig);
  const double unit = std::ldexp(1.0, cfg.sincos_word_bits);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u01(0, 1);
  int checked = 0, cone_disagree = 0;
  double worst_px = 0, worst_d = 0;
  for (int i = 0; i < 4000; ++i) {
    const Vec3 w = direction_from_spherical(std::acos(u01(rng)), 2 * kPi * u01(rng));
    Omega o;
    for (int k = 0; k < 3; ++k) o.w[k] = static_cast<int32_t>(std::lround(w[k] * unit));
    for (size_t c = 0; c < cams.size(); ++c) {
      const CameraModel m = rig.cameras[c].model();
      const int64_t dt = dot_omega(o, cams[c].t);
      const bool hw = cone_test(cfg, dt, cams[c].cos_half_aov);
      if (hw != m.sees(w)) {
        ++cone_disagree;  // only within a few LSB of the cone edge
        EXPECT_NEAR(w.dot(m.frame.t), std::cos(m.in.aov / 2), 2e-4);
        continue;
      }
      if (!hw) continue;
      const PixelPos p = project(cfg, cams[c], o, dt);
      const auto f = m.project(w);
      ASSERT_TRUE(f.has_value());
      if (!p.valid || !m.inside(*f)) continue;
      const double F = std::ldexp(1.0, cfg.pix_frac_bits);
      worst_px = std::max({worst_px, std::abs(p.col / F - f->x()), std::abs(p.row / F - f->y())});
      const double d = distance_unit(cfg, cams[c].c, o) * std::ldexp(1.0, -cfg.dist_frac_bits);
      worst_d = std::max(
          worst_d, std::abs(d - pano::orthographic_distance(Vec3::Zero(), rig.cameras[c].position_mm, w)));
      ++checked;
    }
  }
  EXPECT_GT(checked, 4000);
  EXPECT_LT(cone_disagree, 10);
  EXPECT_LT(worst_px, 0.05);  // register quantisation + 1/64 px rounding
  EXPECT_LT(worst_d, 2e-3);   // mm
  EXPECT_GT(worst_px, 1e-4);  // the test sees the quantisation at all
}

TEST(Blocks, DistortedProjectionMatchesTheFloatModel) {
  HwConfig cfg;
  RigCamera cam = design::thesis_prototype_rig().cameras[5];
  cam.in.k = {-0.21, 0.07, 0.004, -0.003, -0.01};
  cam.in.cu = 126.3;
  cam.in.cv = 123.9;
  const CameraRegs r = camera_regs(cfg, cam);
  const CameraModel m = cam.model();
  const double unit = std::ldexp(1.0, cfg.sincos_word_bits), F = std::ldexp(1.0, cfg.pix_frac_bits);
  double worst = 0;
  int n = 0;
  for (int row = 5; row < 250; row += 10)
    for (int col = 5; col < 250; col += 10) {
      const Vec3 w = m.unproject(Vec2(col + 0.3, row + 0.7));
      if (!m.sees(w)) continue;
      Omega o;
      for (int k = 0; k < 3; ++k) o.w[k] = static_cast<int32_t>(std::lround(w[k] * unit));
      const PixelPos p = project(cfg, r, o, dot_omega(o, r.t));
      ASSERT_TRUE(p.valid);
      worst = std::max({worst, std::abs(p.col / F - (col + 0.3)), std::abs(p.row / F - (row + 0.7))});
      ++n;
    }
  EXPECT_GT(n, 300);
  EXPECT_LT(worst, 0.06);
}

TEST(Blocks, ReciprocalWeightsAreProportionalToInverseProducts) {
  HwConfig cfg;
  const uint32_t d[3] = {4096, 8192, 3 * 4096};  // 1, 2, 3 mm in uQ.12
  BlockFloat D[3];
  for (int i = 0; i < 3; ++i) D[i] = block_float(cfg, d[i]);
  uint32_t w[3];
  reciprocal_weights(cfg, D, 3, w);
  EXPECT_EQ(w[0], 1u << (cfg.recip_bits - 1));
  EXPECT_EQ(w[1], w[0] / 2);
  EXPECT_NEAR(w[2], w[0] / 3.0, 1.0);
  // Products of five distances keep their ratio (block floating: no underflow for tiny distances).
  BlockFloat a = block_float(cfg, 3), b = block_float(cfg, 6);
  for (int k = 0; k < 4; ++k) {
    a = block_float_mul(cfg, a, 3);
    b = block_float_mul(cfg, b, 3);
  }
  BlockFloat ab[2] = {a, b};
  reciprocal_weights(cfg, ab, 2, w);
  EXPECT_EQ(w[0], 2 * w[1]);
  const uint32_t s[2] = {100 << 4, 200 << 4};
  EXPECT_EQ(blend(cfg, w, s, 2, 255), 133u);  // (2*100 + 200) / 3
}

TEST(Blocks, BoundaryUnitTakesTheFirstOfTies) {
  HwConfig cfg;
  const uint32_t dist[3] = {5, 3, 3}, gray[3] = {10u << 4, 200u << 4, 0};
  const BoundaryResult b = boundary_unit(cfg, dist, gray, 3);
  EXPECT_EQ(b.nearest, 1);
  EXPECT_EQ(b.farthest, 0);
  EXPECT_TRUE(b.boundary);
  EXPECT_EQ(b.diff, 190u << 4);
}

}  // namespace
}  // namespace omma::hw
