// Compiled panorama maps (thesis §5.3-5.4): for every output pixel of a grid, the taps that make it,
// with the bilinear sampling inside each camera folded into a compact fixed-point record, so that
// the renderer (render.h) only streams through the map and gathers camera pixels.
//
// Frame store. All camera frames of a rig live in ONE 8-bit BGR buffer (FrameStore): camera c
// occupies rows [row0[c], row0[c] + H_c) of an image `stride_px` pixels wide (the widest camera),
// plus one padding row and 16 padding bytes at the end, so that the 2x2 bilinear neighbourhood of
// any tap can be read without bounds checks.
//
// Map layout (structure of arrays, 5 bytes per tap + 1 byte per output pixel):
//   count[p]  uint8   number of taps of output pixel p (row-major), 0 = no camera sees it (black)
//   word[k]   uint32  bits 0..21  pixel index i = row * stride_px + col into the frame store of the
//                                 top-left pixel of the 2x2 bilinear neighbourhood
//                     bits 22..26 fx: horizontal bilinear fraction, in 1/32 pixel (0..31)
//                     bits 27..31 fy: vertical bilinear fraction, in 1/32 pixel (0..31)
//   weight[k] uint8   blend weight in 1/256 minus one (1..256 stored as 0..255); the weights of one
//                     output pixel sum to exactly 256
//   row_start[r]      index of the first tap of output row r (rows.size() = height + 1)
// The sample of a tap is ((32-fx)(32-fy) a + fx(32-fy) b + (32-fx)fy c + fx fy d) / 1024 for the
// neighbourhood a b / c d; the output is sum(weight * sample) / 256, rounded.
// Bilinear sampling clamps to the image edge (BORDER_REPLICATE), pixel centres at integer + 0.5.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/core/grid.h"
#include "omma/core/rig.h"
#include "omma/pano/method.h"
#include "omma/pano/weights.h"

namespace omma::engine {

// Geometry of the shared frame store of a rig (see the file comment).
struct StoreLayout {
  int stride_px = 0;             // pixels per store row (widest camera)
  int rows = 0;                  // total rows including the padding row
  std::vector<int> row0;         // first store row of each camera
  std::vector<cv::Size> size;    // each camera's frame size
  static StoreLayout for_rig(const Rig& rig);
  size_t bytes() const { return size_t(stride_px) * rows * 3 + 16; }
};

// One buffer holding the latest 8-bit BGR frame of every camera.
class FrameStore {
 public:
  FrameStore() = default;
  explicit FrameStore(StoreLayout layout);
  const StoreLayout& layout() const { return layout_; }
  // A view of camera c's frame (CV_8UC3, H x W); writing into it updates the store.
  cv::Mat camera(int c);
  cv::Mat camera(int c) const;
  // Copies `frame` (CV_8UC3 of the camera's size; 16-bit is scaled down) into camera c's place.
  // Throws std::invalid_argument naming the camera if the size or type is wrong.
  void set(int c, const cv::Mat& frame);
  const uint8_t* data() const { return buffer_.data(); }
  uint8_t* data() { return buffer_.data(); }

 private:
  StoreLayout layout_;
  std::vector<uint8_t> buffer_;
};

struct MapOptions {
  PanoGrid grid;
  pano::Method method = pano::Method::kLinear;
  pano::BlendParams params;
  // Cameras to use (rig order); empty = all. Inactive cameras get no taps; the weights are those
  // of the static method on the rig without them (renormalised among the others).
  std::vector<bool> active;
  // Pass static_taps only the cameras whose cone can reach each 16x16 tile (same taps, faster).
  bool cull = true;
  // Taps whose normalised weight is below this fraction are dropped and the others renormalised
  // (never the strongest tap; 0 = keep every tap whose 1/256-quantised weight is not 0; not applied
  // to sad, whose weights are per frame). The mrf family gives many faint taps: on the prototype
  // rig at 1080x1080, 20 % of its taps weigh 4/256 or less, and they cost as much to render as
  // strong ones. A dropped tap of weight w changes the output by at most w times the difference
  // between the cameras: with 1/32, less than half an 8-bit level where the cameras agree to 16
  // levels. Measured (mrf, prototype rig, vr180): taps per pixel 2.57 -> 1.83, bytes per pixel
  // 13.8 -> 10.2, PSNR against reference_render (which keeps every tap) 59.4 -> 59.2 dB on the
  // Louvre's views and 57.4 -> 53.6 dB on random-texture frames (cameras that disagree entirely).
  double min_weight = 1.0 / 32;
  bool IsValid(std::string* why = nullptr) const;
};

// The rig of the cameras that `active` selects (all if empty), and for each of its cameras the
// index of that camera in the full rig.
struct ActiveRig {
  Rig rig;
  std::vector<int> to_full;
};
ActiveRig active_cameras(const Rig& rig, const std::vector<bool>& active);


struct CompiledMap {
  int width = 0, height = 0;
  // kSad: the taps hold the geometric prior of eq. 4.18 (the mrf weights) and render() computes
  // the per-frame SAD weights (eq. 4.17-4.18) with its own kernel; any other method: final weights.
  pano::Method method = pano::Method::kLinear;
  float sad_epsilon = 1.0f / 255;
  StoreLayout layout;
  std::vector<uint8_t> count;
  std::vector<uint32_t> row_start;
  std::vector<uint32_t> word;
  std::vector<uint8_t> weight;

  size_t taps() const { return word.size(); }
  // Bytes of the map per output pixel (count + word + weight + row starts).
  double bytes_per_pixel() const;
  size_t bytes() const;
  // Camera index of the tap whose word is `w` (looked up from the store layout).
  int camera_of(uint32_t w) const;
};

inline constexpr int kFracBits = 5;
inline constexpr int kIndexBits = 22;

// Compiles the map with pano::static_taps for every output pixel (oneTBB parallel). For sad the
// map holds the mrf prior; the per-frame weights are computed by render().
CompiledMap compile_map(const Rig& rig, const MapOptions& opt);

// Hash (hex) of everything the map depends on: rig (as JSON), grid, method, params, active set
// and the map format version.
std::string map_key(const Rig& rig, const MapOptions& opt);

void save_map(const CompiledMap& map, const std::filesystem::path& path);  // atomic
// nullopt if the file is missing, truncated or of another format version.
std::optional<CompiledMap> load_map(const std::filesystem::path& path);

// Default cache folder: $OMMA_CACHE_DIR, else $XDG_CACHE_HOME/omma, else ~/.cache/omma, else
// /tmp/omma-cache.
std::filesystem::path default_cache_dir();

struct MapLoad {
  CompiledMap map;
  bool from_cache = false;
  double seconds = 0;  // time to compile or load
  std::filesystem::path file;
};
// Loads the map from `cache_dir`/omma-map-<key>.bin, or compiles and stores it there (atomically).
// An empty cache_dir disables the cache. A cache write failure is logged, not fatal.
MapLoad compile_map_cached(const Rig& rig, const MapOptions& opt,
                           const std::filesystem::path& cache_dir);

}  // namespace omma::engine
