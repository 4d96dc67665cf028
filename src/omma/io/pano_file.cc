#include "omma/io/pano_file.h"

#include <chrono>

#include <fmt/format.h>

#include "omma/core/io.h"
#include "omma/io/metadata.h"
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
  if (ext == ".tif" || ext == ".tiff" || ext == ".btf") {
    BigTiffWriter w(path, g.width, g.height, false, 16, panorama_xmp(g));  // with the 360-degree XMP
    renderer.render(timed([&](int, const cv::Mat& band) { w.write_rows(band); }));
    w.finish();
  } else {
    check_image_format(path, g.width, g.height);
    cv::Mat img(g.height, g.width, CV_8UC3);
    renderer.render(
        timed([&](int row0, const cv::Mat& band) { band.copyTo(img.rowRange(row0, row0 + band.rows)); }));
    write_panorama(path, img, g);  // JPEG/PNG with the 360-degree XMP
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

std::filesystem::path frame_set_path(const std::string& pattern, int64_t set, bool many) {
  const std::string key = "{set}";
  const auto at = pattern.find(key);
  if (at != std::string::npos)
    return pattern.substr(0, at) + fmt::format("{:05d}", set) + pattern.substr(at + key.size());
  if (!many) return pattern;
  std::filesystem::path p = pattern;
  return p.replace_filename(p.stem().string() + fmt::format("_{:05d}", set) + p.extension().string());
}

}  // namespace omma::io
