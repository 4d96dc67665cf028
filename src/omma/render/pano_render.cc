#include "omma/render/pano_render.h"

#include <chrono>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "omma/core/io.h"
#include "omma/core/log.h"
#include "omma/core/progress.h"
#include "omma/core/valid.h"
#include "omma/isp/photometric.h"

namespace omma::render {

pano::PlaneSweepOptions giga_sweep_options() {
  pano::PlaneSweepOptions o;
  o.near_mm = 400;
  o.pitch_deg = 1.0;
  o.steps = 32;
  return o;
}

bool PanoRenderOptions::IsValid(std::string* why) const {
  if (grid.width < 1 || grid.height < 1 || grid.width > 1 << 20 || grid.height > 1 << 20)
    return invalid(why,
                   fmt::format("panorama size {}x{} must be 1..1048576 per side", grid.width, grid.height));
  if (band_rows < 1) return invalid(why, "band_rows must be >= 1");
  if (!(min_weight >= 0 && min_weight < 0.5)) return invalid(why, "min_weight must be in [0, 0.5)");
  if (!resident_maps && cache_dir.empty() && !depth)
    return invalid(why, "non-resident maps need a cache folder");
  if (depth && offline) return invalid(why, "the offline blend (hq) has no depth-adaptive bands");
  if (depth && method == pano::Method::kSad) return invalid(why, "depth-adaptive bands do not run sad");
  if (estimate_depth && !depth) return invalid(why, "estimate_depth needs depth");
  if (depth && !(reference_mm > 0 && std::isfinite(reference_mm)))
    return invalid(why, "reference_mm must be a positive distance");
  if (estimate_depth && !sweep.IsValid(why)) return false;
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
  if (opt_.depth) {
    if (opt_.estimate_depth) sweep_ = std::make_unique<pano::DepthSweep>(rig_, opt_.grid, opt_.sweep);
    depth_bands_.resize(n);
    if (opt_.resident_maps) {
      Progress progress("depth band maps", n, opt_.progress);
      for (int i = 0; i < n; ++i) {
        depth_bands_[i] = make_depth_band(i);
        const size_t bytes = size_t(depth_bands_[i]->bytes_per_pixel() * band(i).area());
        all_maps_ += bytes;
        largest_map_ = std::max(largest_map_, bytes);
        progress.step();
      }
    } else {  // compiled per frame set: band 0 (a full band) stands for the largest
      largest_map_ = size_t(make_depth_band(0)->bytes_per_pixel() * band(0).area());
    }
    maps_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return;
  }
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

std::unique_ptr<DepthRenderer> PanoRenderer::make_depth_band(int i) const {
  DepthRenderOptions o;
  o.map = band_options(i);
  o.estimate = false;
  o.reference_mm = opt_.reference_mm;
  o.threads = opt_.render.threads;
  return std::make_unique<DepthRenderer>(rig_, o);
}

void PanoRenderer::set_depth(const cv::Mat& depth_mm) {
  if (!opt_.depth)
    throw std::invalid_argument("render: set_depth needs depth-adaptive bands (options.depth)");
  if (depth_mm.type() != CV_32FC1 || depth_mm.empty() || opt_.grid.width % depth_mm.cols != 0 ||
      opt_.grid.height % depth_mm.rows != 0 ||
      opt_.grid.width / depth_mm.cols != opt_.grid.height / depth_mm.rows)
    throw std::invalid_argument(
        fmt::format("render: the depth map ({}x{}) must be CV_32FC1 of the panorama's size {}x{} or an "
                    "integer factor smaller",
                    depth_mm.cols, depth_mm.rows, opt_.grid.width, opt_.grid.height));
  cv::Mat inv(depth_mm.size(), CV_32FC1);
  for (int r = 0; r < depth_mm.rows; ++r)
    for (int c = 0; c < depth_mm.cols; ++c) {
      const float d = depth_mm.at<float>(r, c);
      if (!(d > 0))
        throw std::invalid_argument(fmt::format("render: depth {} at ({}, {}) is not > 0 mm", d, c, r));
      inv.at<float>(r, c) = std::isinf(d) ? 0.f : 1.f / d;
    }
  inverse_ = inv;
  confidence_ = cv::Mat();
}

PanoGrid PanoRenderer::coarsest_grid() const {
  const int g = std::gcd(opt_.grid.width, opt_.grid.height);
  return PanoGrid{opt_.grid.projection, opt_.grid.width / g, opt_.grid.height / g};
}

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
  if (sweep_) {
    const auto t0 = std::chrono::steady_clock::now();
    const pano::DepthEstimate e = sweep_->estimate(frames, {}, /*upsample=*/false);
    // The sweep's coarse grid is the panorama's size / its factor, rounded; the depth bands take a grid
    // an integer factor smaller exactly: the divisor of both sides nearest the sweep's factor, the
    // estimate resampled onto it (bilinear: both grids span the whole panorama).
    const PanoGrid& g = opt_.grid;
    const double want = double(g.width) / e.coarse_inverse.cols;
    int f = 1;
    for (int d = 1; d <= std::min(g.width, g.height); ++d)
      if (g.width % d == 0 && g.height % d == 0 && std::abs(d - want) < std::abs(f - want)) f = d;
    const cv::Size size(g.width / f, g.height / f);
    if (size == e.coarse_inverse.size()) {
      inverse_ = e.coarse_inverse;
      confidence_ = e.coarse_confidence;
    } else {
      cv::resize(e.coarse_inverse, inverse_, size, 0, 0, cv::INTER_LINEAR);
      cv::resize(e.coarse_confidence, confidence_, size, 0, 0, cv::INTER_LINEAR);
    }
    estimate_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
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
  } else if (opt_.depth) {
    if (inverse_.empty()) throw std::logic_error("render: no depth for the depth-adaptive bands (set_depth)");
    std::unique_ptr<DepthRenderer> scratch;
    DepthRenderer& dr = depth_bands_[i] ? *depth_bands_[i] : *(scratch = make_depth_band(i));
    dr.render(store_, {}, out, inverse_);
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
