#include "omma/io/pano_file.h"

#include <chrono>

#include <fmt/format.h>

#include "omma/core/io.h"
#include "omma/io/tiff_writer.h"

namespace omma::io {

double render_to_file(render::PanoRenderer& renderer, const std::filesystem::path& path) {
  const PanoGrid& g = renderer.options().grid;
  const std::string ext = lower_extension(path);
  double seconds = 0;
  auto timed = [&](const render::BandSink& sink) {
    return [&seconds, sink, t = std::chrono::steady_clock::now()](int row0, const cv::Mat& band) mutable {
      seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
      sink(row0, band);
      t = std::chrono::steady_clock::now();
    };
  };
  if (ext == ".tif" || ext == ".tiff") {
    BigTiffWriter w(path, g.width, g.height);
    renderer.render(timed([&](int, const cv::Mat& band) { w.write_rows(band); }));
    w.finish();
  } else {
    check_image_format(path, g.width, g.height);
    cv::Mat img(g.height, g.width, CV_8UC3);
    renderer.render(
        timed([&](int row0, const cv::Mat& band) { band.copyTo(img.rowRange(row0, row0 + band.rows)); }));
    write_image(path, img);
  }
  return seconds;
}

render::FrameSetTimes render_frame_set(const render::FrameSetReader& recording, int64_t set,
                                       render::PanoRenderer& renderer, isp::IspOptions iso,
                                       const std::filesystem::path& path) {
  using clock = std::chrono::steady_clock;
  render::FrameSetTimes t;
  std::vector<cv::Mat> frames = render::develop_frame_set(recording, set, iso, &t);
  auto t2 = clock::now();
  renderer.set_frames(frames);
  t.render = render_to_file(renderer, path);
  t.write = std::chrono::duration<double>(clock::now() - t2).count() - t.render;
  return t;
}

}  // namespace omma::io
