// Verilator co-simulation of the single-camera front end (hw/rtl/frontend, thesis §5.1.2-5.1.3)
// against src/omma/isp: chip streams made by isp::encode_link (and damaged by isp::impair_link)
// go into the RTL one chip per cycle; every frame it emits must equal, row for row and pixel for
// pixel, what isp::decode_link hands on (pixels, intact-row flags, statistics), and its demosaiced
// output must equal isp::demosaic(bilinear, 10 bits) of that frame (R, G, B and the RGB565 word).
//
// Two builds of the same RTL: the thesis's link (250 x 250, 10 bits, 3 / 4 / 505 / 250 PP) and a
// small one (20 x 10, resync 16 PP) on which many random streams run quickly.
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "Vfe_small.h"
#include "Vfe_thesis.h"
#include "omma/isp/color.h"
#include "omma/isp/demosaic.h"
#include "omma/isp/link.h"
#include "verilated.h"

namespace {

using omma::isp::ChipStream;
using omma::isp::LinkConfig;
using omma::isp::LinkFrame;

// The parameters each model was verilated with (hw/rtl/CMakeLists.txt).
LinkConfig thesis_link() { return LinkConfig{}; }
LinkConfig small_link() {
  LinkConfig c;
  c.width = 20;
  c.height = 10;
  c.row_gap_pp = 3;
  c.eof_pp = 4;
  c.config_pp = 30;
  c.resync_pp = 16;
  return c;
}

struct RtlFrame {
  std::vector<uint16_t> raw;
  std::vector<uint8_t> row_ok;
  cv::Mat rgb;     // CV_16UC3 BGR, 10 bits
  cv::Mat rgb565;  // CV_16UC1
};

struct RtlRun {
  std::vector<RtlFrame> frames;
  long frames_count = 0, rows_ok = 0, rows_damaged = 0, overruns = 0;
  bool proto_err = false;
  uint64_t cycles = 0;
};

// Feeds every chip of the packed stream (bytes * 8, as decode_link reads them), then flushes.
template <class V>
RtlRun run_rtl(const ChipStream& s, const LinkConfig& c) {
  VerilatedContext ctx;
  V top(&ctx);
  RtlRun out;
  RtlFrame cur;
  size_t raw_n = 0;
  auto new_frame = [&] {
    cur.raw.assign(size_t(c.width) * c.height, 0);
    cur.row_ok.assign(size_t(c.height), 0);
    cur.rgb = cv::Mat(c.height, c.width, CV_16UC3, cv::Scalar::all(0));
    cur.rgb565 = cv::Mat(c.height, c.width, CV_16UC1, cv::Scalar(0));
    raw_n = 0;
  };
  new_frame();
  std::vector<RtlFrame> raw_done;  // frames whose raw stream is complete, awaiting RGB
  auto tick = [&] {
    top.clk = 0;
    top.eval();
    top.clk = 1;
    top.eval();
    ++out.cycles;
    if (top.raw_valid) {
      const size_t y = raw_n / size_t(c.width);
      cur.raw[raw_n] = uint16_t(top.raw_data);
      cur.row_ok[y] = top.raw_row_ok;
      ++raw_n;
    }
    if (top.rgb_valid) {
      auto& px = cur.rgb.at<cv::Vec3w>(top.rgb_y, top.rgb_x);
      px = cv::Vec3w(uint16_t(top.rgb_b), uint16_t(top.rgb_g), uint16_t(top.rgb_r));
      cur.rgb565.at<uint16_t>(top.rgb_y, top.rgb_x) = uint16_t(top.rgb565);
      if (top.rgb_y == c.height - 1 && top.rgb_x == c.width - 1) {
        EXPECT_EQ(raw_n, size_t(c.width) * c.height) << "RGB frame ended before its raw stream";
        out.frames.push_back(cur);
        new_frame();
      }
    }
  };
  top.rst = 1;
  top.chip_valid = 0;
  top.flush = 0;
  top.chip = 0;
  tick();
  tick();
  top.rst = 0;
  const size_t n = s.bytes.size() * 8;
  for (size_t i = 0; i < n; ++i) {
    top.chip_valid = 1;
    top.chip = (s.bytes[i >> 3] >> (7 - (i & 7))) & 1;
    tick();
  }
  top.chip_valid = 0;
  top.flush = 1;
  for (long guard = 0; !(top.done && !top.busy); ++guard) {
    tick();
    if (guard > 10L * c.width * c.height + 100000) {
      ADD_FAILURE() << "RTL did not finish after the stream";
      break;
    }
  }
  for (int k = 0; k < 4; ++k) tick();
  out.frames_count = long(top.frames);
  out.rows_ok = long(top.rows_ok);
  out.rows_damaged = long(top.rows_damaged);
  out.overruns = long(top.overruns);
  out.proto_err = top.proto_err;
  return out;
}

struct IspRun {
  std::vector<LinkFrame> frames;
  omma::isp::LinkSummary stats;
};

IspRun run_isp(const ChipStream& s, const LinkConfig& c) {
  IspRun r;
  r.stats = omma::isp::decode_link(s.bytes, c, [&](const LinkFrame& f) { r.frames.push_back(f); });
  return r;
}

// Compares everything; returns the number of differing pixels (raw + RGB) for the message.
void expect_same(const RtlRun& rtl, const IspRun& isp, const LinkConfig& c, const std::string& what) {
  SCOPED_TRACE(what);
  EXPECT_FALSE(rtl.proto_err);
  EXPECT_EQ(rtl.overruns, 0);
  EXPECT_EQ(rtl.frames_count, isp.stats.frames);
  EXPECT_EQ(rtl.rows_ok, isp.stats.rows_ok);
  EXPECT_EQ(rtl.rows_damaged, isp.stats.rows_damaged);
  ASSERT_EQ(rtl.frames.size(), isp.frames.size());
  for (size_t f = 0; f < isp.frames.size(); ++f) {
    const LinkFrame& e = isp.frames[f];
    const RtlFrame& g = rtl.frames[f];
    EXPECT_EQ(g.row_ok, e.row_ok) << "frame " << f;
    long raw_diff = 0;
    for (size_t i = 0; i < e.pixels.size(); ++i) raw_diff += g.raw[i] != e.pixels[i];
    EXPECT_EQ(raw_diff, 0) << "frame " << f << ": raw pixels differing";
    // isp: demosaic the decoded frame (damaged rows are 0, as handed on)
    cv::Mat raw(c.height, c.width, CV_16UC1, const_cast<uint16_t*>(e.pixels.data()));
    const cv::Mat rgb = omma::isp::demosaic(raw, omma::isp::Demosaic::kBilinear, c.bits);
    cv::Mat diff;
    cv::compare(rgb.reshape(1), g.rgb.reshape(1), diff, cv::CMP_NE);
    EXPECT_EQ(cv::countNonZero(diff), 0) << "frame " << f << ": demosaiced channel values differing";
    // RGB565 of §5.2: the 8 most significant bits of each channel, then 5/6/5
    cv::Mat rgb8(rgb.size(), CV_8UC3);
    for (int y = 0; y < rgb.rows; ++y)
      for (int x = 0; x < rgb.cols; ++x) {
        const cv::Vec3w p = rgb.at<cv::Vec3w>(y, x);
        rgb8.at<cv::Vec3b>(y, x) = cv::Vec3b(uint8_t(p[0] >> (c.bits - 8)), uint8_t(p[1] >> (c.bits - 8)),
                                             uint8_t(p[2] >> (c.bits - 8)));
      }
    cv::compare(omma::isp::pack_rgb565(rgb8), g.rgb565, diff, cv::CMP_NE);
    EXPECT_EQ(cv::countNonZero(diff), 0) << "frame " << f << ": RGB565 words differing";
  }
}

LinkFrame random_frame(const LinkConfig& c, uint32_t seed) {
  std::mt19937 rng(seed);
  LinkFrame f;
  f.width = c.width;
  f.height = c.height;
  f.pixels.resize(size_t(c.width) * c.height);
  for (auto& p : f.pixels) p = uint16_t(rng() % (1u << c.bits));
  return f;
}

// A photograph's crop, mosaicked RGGB and scaled to 10 bits (a natural image for the demosaic).
LinkFrame photo_frame(const LinkConfig& c, const std::string& name, int x0, int y0) {
  const cv::Mat img = cv::imread(std::string(OMMA_DATA_DIR) + "/" + name, cv::IMREAD_COLOR);
  if (img.empty()) return random_frame(c, 99);
  cv::Mat crop = img(cv::Rect(x0, y0, c.width, c.height)).clone(), crop16;
  crop.convertTo(crop16, CV_16UC3, 4.0);
  const cv::Mat m = omma::isp::mosaic_rggb(crop16);
  LinkFrame f;
  f.width = c.width;
  f.height = c.height;
  f.pixels.assign(m.ptr<uint16_t>(0), m.ptr<uint16_t>(0) + m.total());
  return f;
}

TEST(RtlFrontEnd, ThesisLinkCleanFramesMatchIsp) {
  const LinkConfig c = thesis_link();
  const ChipStream s =
      omma::isp::encode_link({photo_frame(c, "louvre.jpg", 1200, 700), random_frame(c, 1)}, c);
  const RtlRun rtl = run_rtl<Vfe_thesis>(s, c);
  const IspRun isp = run_isp(s, c);
  ASSERT_EQ(isp.stats.frames, 2);
  EXPECT_EQ(isp.stats.rows_damaged, 0);
  expect_same(rtl, isp, c, "clean");
  // one chip per cycle: the RTL keeps up with the line (the frames came out while chips arrived)
  EXPECT_LT(rtl.cycles, s.bytes.size() * 8 + 70000);
}

TEST(RtlFrontEnd, ThesisLinkWithBitFlipsAndLostSamplesMatchesIsp) {
  const LinkConfig c = thesis_link();
  const ChipStream clean = omma::isp::encode_link(
      {photo_frame(c, "lake.jpg", 900, 500), random_frame(c, 2), random_frame(c, 3)}, c);
  long damaged = 0;
  for (uint64_t seed : {11u, 12u}) {
    // ~7 flips and ~2 lost samples per frame: damaged rows, rows placed after a lost sample
    const ChipStream s = omma::isp::impair_link(clean, 5e-6, seed == 12 ? 1.5e-6 : 0.0, seed);
    const IspRun isp = run_isp(s, c);
    damaged += isp.stats.rows_damaged;
    expect_same(run_rtl<Vfe_thesis>(s, c), isp, c, "seed " + std::to_string(seed));
  }
  std::printf("thesis link with flips and lost samples: %ld damaged rows, all frames identical\n", damaged);
  EXPECT_GT(damaged, 5);  // the impairment did damage rows
}

TEST(RtlFrontEnd, SmallLinkRandomStreamsMatchIsp) {
  // Many short streams with heavy damage, truncated at random places (a capture that starts or
  // ends mid-frame), so that every path of the decoder runs: damaged rows, lost frame markers,
  // unsynchronised starts, resynchronisation, end of stream inside a row.
  const LinkConfig c = small_link();
  std::mt19937 rng(7);
  long frames = 0, damaged = 0, ok = 0;
  for (int trial = 0; trial < 60; ++trial) {
    std::vector<LinkFrame> fr;
    for (int k = 0; k < 4; ++k) fr.push_back(random_frame(c, rng()));
    ChipStream s = omma::isp::encode_link(fr, c);
    const double flip = (trial % 3) * 4e-4, drop = (trial % 4 == 3) ? 3e-4 : 0.0;
    s = omma::isp::impair_link(s, flip, drop, rng());
    if (trial % 2 == 1) {  // cut: start and end at random chips
      const size_t a = rng() % (s.chips / 3), b = s.chips - rng() % (s.chips / 3);
      ChipStream t;
      for (size_t i = a; i < b; ++i) t.push(s.chip(i));
      s = t;
    }
    const IspRun isp = run_isp(s, c);
    frames += isp.stats.frames;
    damaged += isp.stats.rows_damaged;
    ok += isp.stats.rows_ok;
    expect_same(run_rtl<Vfe_small>(s, c), isp, c, "trial " + std::to_string(trial));
    if (HasFailure()) break;
  }
  std::printf("small link: %ld frames, %ld intact rows, %ld damaged rows, all identical\n", frames, ok,
              damaged);
  EXPECT_GT(frames, 150);
  EXPECT_GT(damaged, 100);
  EXPECT_GT(ok, 1000);
}

}  // namespace
