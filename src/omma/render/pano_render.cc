#include "omma/render/pano_render.h"

#include <chrono>
#include <stdexcept>

#include <fmt/format.h>

#include "omma/core/io.h"
#include "omma/core/log.h"
#include "omma/core/progress.h"
#include "omma/core/valid.h"
#include "omma/isp/photometric.h"

namespace omma::render {

bool PanoRenderOptions::IsValid(std::string* why) const {
  if (grid.width < 1 || grid.height < 1 || grid.width > 1 << 20 || grid.height > 1 << 20)
    return invalid(why,
                   fmt::format("panorama size {}x{} must be 1..1048576 per side", grid.width, grid.height));
  if (band_rows < 1) return invalid(why, "band_rows must be >= 1");
  if (!(min_weight >= 0 && min_weight < 0.5)) return invalid(why, "min_weight must be in [0, 0.5)");
  if (!resident_maps && cache_dir.empty()) return invalid(why, "non-resident maps need a cache folder");
  return true;
}

PanoRenderer::PanoRenderer(const Rig& rig, const PanoRenderOptions& options) : rig_(rig), opt_(options) {
  if (std::string why; !opt_.IsValid(&why)) throw std::invalid_argument("render: " + why);
  rig_.validate();
  if (const std::string problem = opt_.resident_maps ? "" : cache_dir_problem(opt_.cache_dir);
      !problem.empty())
    throw std::invalid_argument("render: maps kept out of memory need a map cache only you can write: " +
                                problem);
  store_ = FrameStore(StoreLayout::for_rig(rig_));
  if (opt_.offline) return;  // the offline blend needs no maps
  const auto t0 = std::chrono::steady_clock::now();
  const int n = bands();
  maps_.resize(n);
  map_files_.resize(n);
  Progress progress("band maps", n, opt_.progress);
  for (int i = 0; i < n; ++i) {
    MapLoad ml = compile_map_cached(rig_, band_options(i), opt_.cache_dir);
    maps_from_cache_ += ml.from_cache;
    map_files_[i] = ml.file;
    const size_t bytes = ml.map.bytes();
    largest_map_ = std::max(largest_map_, bytes);
    all_maps_ += bytes;
    if (opt_.resident_maps) maps_[i] = std::make_unique<CompiledMap>(std::move(ml.map));
    progress.step();
  }
  maps_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

PanoRenderer::~PanoRenderer() = default;

MapOptions PanoRenderer::band_options(int i) const {
  MapOptions mo;
  mo.grid = opt_.grid;
  mo.method = opt_.method;
  mo.params = opt_.params;
  mo.min_weight = opt_.min_weight;
  mo.window = band(i);
  return mo;
}

int PanoRenderer::bands() const { return (opt_.grid.height + opt_.band_rows - 1) / opt_.band_rows; }

cv::Rect PanoRenderer::band(int i) const {
  const int r0 = i * opt_.band_rows;
  return {0, r0, opt_.grid.width, std::min(opt_.band_rows, opt_.grid.height - r0)};
}

void PanoRenderer::set_frames(const std::vector<cv::Mat>& frames) {
  if (frames.size() != rig_.cameras.size())
    throw std::invalid_argument(
        fmt::format("render: {} frames for a rig of {} cameras", frames.size(), rig_.cameras.size()));
  for (size_t c = 0; c < frames.size(); ++c) store_.set(static_cast<int>(c), frames[c]);
  if (opt_.offline) {
    frames_.resize(frames.size());
    for (size_t c = 0; c < frames.size(); ++c) frames_[c] = store_.camera(static_cast<int>(c));
  }
}

const CompiledMap& PanoRenderer::band_map(int i, std::unique_ptr<CompiledMap>& scratch) const {
  if (maps_[i]) return *maps_[i];
  std::string why;
  auto m = load_map(map_files_[i], rig_, band_options(i), &why);
  if (!m)
    throw std::runtime_error("render: the cached map '" + map_files_[i].string() +
                             "' cannot be used: " + why);
  scratch = std::make_unique<CompiledMap>(std::move(*m));
  return *scratch;
}

void PanoRenderer::render_band(int i, cv::Mat& out) {
  const cv::Rect b = band(i);
  if (opt_.offline) {
    MapOptions mo;
    mo.grid = opt_.grid;
    mo.method = opt_.method;
    mo.params = opt_.params;
    mo.window = b;
    out = reference_render(rig_, mo, frames_);
  } else {
    std::unique_ptr<CompiledMap> scratch;
    render::render(band_map(i, scratch), store_, out, opt_.render);
  }
}

void PanoRenderer::render(const BandSink& sink) {
  cv::Mat out;
  for (int i = 0; i < bands(); ++i) {
    render_band(i, out);
    sink(band(i).y, out);
  }
}

cv::Mat PanoRenderer::render_image() {
  cv::Mat img(opt_.grid.height, opt_.grid.width, CV_8UC3);
  render([&](int row0, const cv::Mat& band) { band.copyTo(img.rowRange(row0, row0 + band.rows)); });
  return img;
}

PanoRenderMemory PanoRenderer::memory() const {
  PanoRenderMemory m;
  m.store_bytes = store_.layout().bytes();
  m.maps_bytes = opt_.resident_maps ? all_maps_ : largest_map_;
  m.band_bytes = size_t(opt_.grid.width) * std::min(opt_.band_rows, opt_.grid.height) * 3;
  return m;
}

std::vector<cv::Mat> develop_frame_set(const FrameSetReader& recording, int64_t set, isp::IspOptions iso,
                                       FrameSetTimes* times, const std::vector<cv::Mat>& gains) {
  using clock = std::chrono::steady_clock;
  auto t0 = clock::now();
  std::vector<cv::Mat> raws = recording.read_frame_set(set);
  auto t1 = clock::now();
  iso.bits = recording.bits();
  std::vector<cv::Mat> frames = isp::develop_with_model(raws, iso, gains);
  const Rig& rig = recording.rig();
  for (size_t c = 0; c < raws.size(); ++c)
    if (frames[c].empty())
      frames[c] = cv::Mat::zeros(rig.cameras[c].in.height, rig.cameras[c].in.width, CV_8UC3);
  if (times) {
    times->read = std::chrono::duration<double>(t1 - t0).count();
    times->develop = std::chrono::duration<double>(clock::now() - t1).count();
  }
  return frames;
}

}  // namespace omma::render
