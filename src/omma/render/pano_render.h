// Offline rendering of large panoramas (Giga-Eye, thesis ch. 7: 9000 x 2400 = 21.6 MP and
// 17700 x 4650 = 82.3 MP over 360 x 100 deg, which the thesis stitched offline with a commercial
// tool) from compiled maps, band by band.
//
// The output grid is cut into horizontal BANDS of `band_rows` rows. Each band has its own compiled
// map (MapOptions::window: the same taps as one map of the whole grid, mrf neighbours across band
// edges included), cached on disk like every map (compile_map_cached), and renders from ONE frame
// store holding every camera (FrameStore, row pairs: 6 bytes per camera pixel). A frame set is
// rendered band after band into a BandSink (an image in memory, or a file: io/pano_file.h), so memory
// holds: the store, the band maps (resident, or one at a time with `resident_maps = false`), and
// one band of output. PanoRenderer::memory() states it.
//
// Methods: the engine's (nn, linear, gaussian, mrf, mrf-spherical, sad: 8-bit fixed-point taps,
// render.h) and kOffline ("hq"): render::reference_render's double-precision blend of every tap
// (no dropped taps, no weight quantisation) per band, for a final master; about 100x slower.
//
// Depth (`depth = true`): near scenes seen by Giga-Eye's cameras 200 mm from its centre have
// parallax, and one stitching distance ghosts everything else. Each band is then rendered by a
// depth-adaptive map (depth_render.h: every tap moved to where its camera sees the pixel's surface
// point, eq. 5.21-5.26 on X = q + D w, contributors.h) from ONE inverse-depth map of the whole
// panorama per frame set, on a coarse grid (an integer factor f smaller than the panorama in both
// axes): estimated in set_frames from the frames by pano::DepthSweep (`sweep`; its coarse grid is
// the only whole-panorama state besides the store), or given by set_depth (a sphere, a true depth
// file). Memory: the store, the coarse depth, the band depth maps (about 54 bytes per panorama pixel
// resident, or one band's at a time with resident_maps = false, then compiled again for every
// frame set: not cached on disk), one output band.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/isp/isp.h"
#include "omma/pano/plane_sweep.h"
#include "omma/render/compiled_map.h"
#include "omma/render/depth_render.h"
#include "omma/render/frame_reader.h"
#include "omma/render/render.h"

namespace omma::render {

// The sweep for Giga-Eye-scale rigs and near scenes (the depth of `omma render --depth estimate`):
// candidates from 400 mm (twice Giga-Eye's 200 mm radius) to infinity, 32 of them, on a grid of 1 deg
// (pano::PlaneSweepOptions documents every field; measured in docs/results/near_scene.md).
pano::PlaneSweepOptions giga_sweep_options();

struct PanoRenderOptions {
  PanoGrid grid{Projection::kEquirect100, 9000, 2400};
  pano::Method method = pano::Method::kMrf;
  bool offline = false;  // the high-quality offline blend (see the file comment)
  pano::BlendParams params;
  double min_weight = 1.0 / 20;  // MapOptions::min_weight (engine methods)
  int band_rows = 256;           // rows per band map (a multiple of kTileH is best)
  bool resident_maps = true;     // keep every band map in memory (else load each from the cache)
  std::filesystem::path cache_dir = default_cache_dir();  // empty: no cache (resident only)
  RenderOptions render;
  bool progress = true;  // progress bar on stderr while compiling maps
  // Depth-adaptive bands (see the file comment; not with offline). estimate_depth: set_frames
  // estimates the depth with `sweep` (else set_depth must be called before rendering).
  bool depth = false;
  bool estimate_depth = false;
  pano::PlaneSweepOptions sweep = giga_sweep_options();
  double reference_mm = 2000;  // the sphere the depth maps' static weights are computed on, mm
  bool IsValid(std::string* why = nullptr) const;
};

// Receives the bands of one panorama, top to bottom: (first row, band CV_8UC3).
using BandSink = std::function<void(int row0, const cv::Mat& band)>;

struct PanoRenderMemory {
  size_t store_bytes = 0;  // the frame store
  size_t maps_bytes = 0;   // all band maps (resident) or the largest one
  size_t band_bytes = 0;   // one output band
  size_t total() const { return store_bytes + maps_bytes + band_bytes; }
};

class PanoRenderer {
 public:
  // Compiles (or loads from the cache) the band maps. Throws std::invalid_argument on bad options.
  PanoRenderer(const Rig& rig, const PanoRenderOptions& options);
  ~PanoRenderer();
  const PanoRenderOptions& options() const { return opt_; }
  int bands() const;
  cv::Rect band(int i) const;  // rows of band i (the full width)
  // Sets the developed frames (CV_8UC3 or anything FrameStore::set converts; rig order; one per
  // camera) into the store. Throws std::invalid_argument naming a camera of the wrong size.
  void set_frames(const std::vector<cv::Mat>& frames);
  // Depth bands: the surface of the frames set next (or last): a depth map of the whole panorama, mm
  // from q (+inf = infinity; CV_32FC1), at the panorama's size or a coarse grid an integer factor
  // smaller in both axes (DepthSweep's convention: coarse pixel (c, r) looks at the centre of the
  // panorama's f x f block). Throws std::invalid_argument without `depth`, or for another size.
  void set_depth(const cv::Mat& depth_mm);
  // The coarsest grid set_depth takes: the panorama's size divided by the greatest common divisor of
  // its sides (15 x 4 for 9000 x 2400). A sphere around the rig centre, seen from it, is one distance:
  // set_depth(pano::sphere_depth(rig, coarsest_grid(), R)).
  PanoGrid coarsest_grid() const;
  // The inverse depth (1/mm, coarse grid) the next render uses; its confidence when estimated (else
  // empty); the estimate's time (s) for the frames last set.
  const cv::Mat& coarse_inverse() const { return inverse_; }
  const cv::Mat& coarse_confidence() const { return confidence_; }
  double estimate_seconds() const { return estimate_seconds_; }
  // Renders the frames last set, band by band, into `sink`.
  void render(const BandSink& sink);
  // Renders band i only (rows band(i)) into `out` (CV_8UC3): the unit a distributed renderer splits
  // one panorama into (apps/split_render.h).
  void render_band(int i, cv::Mat& out);
  // The whole panorama in memory (small grids, tests).
  cv::Mat render_image();
  PanoRenderMemory memory() const;
  double maps_seconds() const { return maps_seconds_; }  // compile or load time of the maps
  int maps_from_cache() const { return maps_from_cache_; }

 private:
  const CompiledMap& band_map(int i, std::unique_ptr<CompiledMap>& scratch) const;
  std::unique_ptr<DepthRenderer> make_depth_band(int i) const;
  Rig rig_;
  PanoRenderOptions opt_;
  FrameStore store_;
  std::vector<cv::Mat> frames_;          // offline: the developed frames
  MapOptions band_options(int i) const;  // the map of band i: the panorama's grid, band(i) as window
  std::vector<std::unique_ptr<CompiledMap>> maps_;
  std::vector<std::filesystem::path> map_files_;
  size_t largest_map_ = 0, all_maps_ = 0;
  double maps_seconds_ = 0;
  int maps_from_cache_ = 0;
  // Depth bands.
  std::vector<std::unique_ptr<DepthRenderer>> depth_bands_;
  std::unique_ptr<pano::DepthSweep> sweep_;
  cv::Mat inverse_, confidence_;
  double estimate_seconds_ = 0;
};

// Times of one frame set's way from a reader to a file (seconds): io::render_frame_set.
struct FrameSetTimes {
  double read = 0, develop = 0, render = 0, write = 0;
};

// Frame set `set` of `reader` read and developed (ISP: demosaic, white balance; iso.bits is taken
// from the reader): one CV_8UC3 frame per camera, black where the set lacks the camera (its weights
// are not renormalised: the gap shows); times->read and ->develop filled when given. `gains`: the
// rig's photometric model as flat-gain maps (isp::flat_gains_from_rig, computed once per rig):
// cameras with a model are developed with it instead of the white balance; empty: none.
std::vector<cv::Mat> develop_frame_set(const FrameSetReader& reader, int64_t set, isp::IspOptions iso,
                                       FrameSetTimes* times = nullptr,
                                       const std::vector<cv::Mat>& gains = {});

}  // namespace omma::render
