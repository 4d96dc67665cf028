// The whole chip (system_top) from its 24 serial camera links to the panorama: raw Bayer frames of a
// far-field photograph seen by the 24-camera prototype (here with 40 x 40 sensors, so that the links
// carry a frame in 60,000 chips), encoded by isp::encode_link and partly damaged by bit flips, go
// into the 24 front ends one chip per cycle; the front ends write RGB565 into the frame memories,
// the pipeline makes the panorama. The model side: isp::decode_link and isp::demosaic of the same
// streams give the frames (8 most significant bits of the 10-bit RGB) that hw::Pipeline renders.
// 0 differing pixels.
#include <cstdio>
#include <random>

#include <gtest/gtest.h>

#include "omma/isp/demosaic.h"
#include "pano_chip.h"

namespace omma::hw::rtl {
namespace {

Rig small_sensor_rig() {
  Rig rig = rig24();
  for (RigCamera& c : rig.cameras) {
    const double s = 40.0 / c.in.width;
    c.in.width = c.in.height = 40;  // hw/rtl/CMakeLists.txt: system_top -GCAM_W=40 -GCAM_H=40
    c.in.fu *= s;
    c.in.fv *= s;
    c.in.cu *= s;
    c.in.cv *= s;
  }
  return rig;
}

TEST(RtlSystem, SerialLinksToPanoramaMatchIspAndModelBitForBit) {
  const Rig rig = small_sensor_rig();
  isp::LinkConfig link;
  link.width = link.height = 40;
  // raw frames: the Louvre seen by each camera, mosaicked RGGB, 10 bits (8-bit render << 2 plus
  // random low bits)
  const cv::Mat tex = testing::photo_texture(std::string(OMMA_DATA_DIR) + "/louvre.jpg", 720);
  std::mt19937 rng(5);
  std::vector<isp::ChipStream> streams;
  std::vector<cv::Mat> frames;  // what the model sees
  long damaged = 0;
  for (const cv::Mat& f : testing::render_frames(rig, tex)) {
    cv::Mat bgr16;
    to_u8(f).convertTo(bgr16, CV_16UC3, 4.0);
    const cv::Mat raw = isp::mosaic_rggb(bgr16);
    isp::LinkFrame lf;
    lf.width = lf.height = 40;
    lf.pixels.assign(raw.ptr<uint16_t>(0), raw.ptr<uint16_t>(0) + raw.total());
    for (auto& p : lf.pixels) p = uint16_t(p | (rng() & 3));
    isp::ChipStream s = isp::encode_link({lf}, link);
    if (streams.size() % 6 == 5) s = isp::impair_link(s, 3e-4, 0, rng());  // four damaged links
    // the model's frame: the decoder's output (damaged rows 0), demosaiced, 8 MSBs
    isp::LinkFrame dec;
    const isp::LinkSummary st = isp::decode_link(s.bytes, link, [&](const isp::LinkFrame& d) { dec = d; });
    ASSERT_EQ(st.frames, 1);
    damaged += st.rows_damaged;
    const cv::Mat rgb10 =
        isp::demosaic(cv::Mat(40, 40, CV_16UC1, dec.pixels.data()), isp::Demosaic::kBilinear, 10);
    cv::Mat bgr8(40, 40, CV_8UC3);
    for (int y = 0; y < 40; ++y)
      for (int x = 0; x < 40; ++x) {
        const cv::Vec3w p = rgb10.at<cv::Vec3w>(y, x);
        bgr8.at<cv::Vec3b>(y, x) = cv::Vec3b(uint8_t(p[0] >> 2), uint8_t(p[1] >> 2), uint8_t(p[2] >> 2));
      }
    frames.push_back(bgr8);
    streams.push_back(s);
  }
  size_t longest = 0;
  for (const auto& s : streams) longest = std::max(longest, s.bytes.size());
  for (auto& s : streams) s.bytes.resize(longest, 0);  // idle line after a shorter (impaired) stream
  EXPECT_GT(damaged, 0);

  const HwConfig cfg;
  const PanoGrid grid{Projection::kVr180, 64, 64};
  Pipeline model(cfg, rig, grid);
  model.load_frames(frames);
  const PipelineSummary ref = model.render(pano::Method::kLinear, false);

  Chip chip;
  chip.feed_links(streams);
  EXPECT_EQ(chip.top().cam_frames, 1u);
  chip.configure(exported_streams(rig, ExportOptions{cfg, grid, pano::Method::kLinear, false, {}}));
  ASSERT_FALSE(chip.top().cfg_err);
  const Chip::Run run = chip.run(grid.width, grid.height);
  EXPECT_EQ(run.pixels, uint64_t(grid.width) * grid.height);
  const int diff = differing_pixels(run.pano, ref.pano);
  std::printf(
      "system: 24 links (%ld damaged rows) -> front ends -> frame memories -> %dx%d linear panorama: "
      "%d differing pixels\n",
      damaged, grid.width, grid.height, diff);
  EXPECT_EQ(diff, 0);
  EXPECT_GT(cv::countNonZero(run.pano.reshape(1)), int(run.pano.total()));
}

}  // namespace
}  // namespace omma::hw::rtl
