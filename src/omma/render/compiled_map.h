// Compiled panorama maps (thesis §5.3-5.4): for every output pixel of a grid, the taps that make it,
// with the bilinear sampling inside each camera folded into the blend weights, so that the renderer
// (render.h) only streams through the map and gathers camera pixels.
//
// Frame store. All camera frames of a rig live in ONE buffer (FrameStore) of "row pairs": camera c's
// frame row y is store row R = row0[c] + y, which holds, for every column x, the 6 bytes
//     B G R of pixel (x, y),  B G R of pixel (x, min(y + 1, H - 1)).
// So the whole 2x2 bilinear neighbourhood of (x, y) is the 12 contiguous bytes at byte
// R * stride_bytes + 6 x (x+1 follows x), one 16-byte load; the bottom edge is replicated by the
// pair itself. stride_bytes = 6 * stride_px (the widest
// camera); 64 bytes of padding at the end keep every 16-byte load inside the buffer.
//
// Map layout. The output is cut into tiles of kTileW x kTileH pixels, rendered tile by tile (the
// camera pixels a tile needs stay in the L1 cache), tiles in row-major order. Each tile row is a list
// of RUNS: consecutive pixels with the same number C of taps (sorted by camera) whose tap t lies
// within int16 of tap t of the run's first pixel. Per tap the map holds
//   delta[k]  int16   its neighbourhood's store offset minus the run's start offset for tap t
//                     (base[]), in units of 2 bytes (offsets are even). Relative to the run, not to
//                     the previous pixel: no chain of additions between pixels (measured 15-30 %
//                     faster than chained deltas)
//   weight[k] uint32  the four bilinear x blend weights of its neighbourhood, in 1/128, as bytes
//                     (w(x,y), w(x,y+1), w(x+1,y), w(x+1,y+1)) from the low byte up; the 4C weights
//                     of one output pixel sum to exactly 128, each is at most 127 (signed bytes:
//                     the VNNI kernel broadcasts them from memory into vpdpbusd)
// and per run: runs[] the byte pair (C, number of pixels), each tile row ended by the pair (0, 0),
// and base[] the offsets of the run's first pixel's C taps (units of 2 bytes).
// The output is (sum over taps and the 4 neighbours of w * value + 64) >> 7, exact integers.
// Per tile: lines[] the store's 64-byte cache lines its taps read (byte offsets), which the renderer
// prefetches while it renders the tile before (measured: the gather from the store, not arithmetic,
// dominated the previous row-by-row kernel).
// sad keeps per tap the bilinear weights only (summing to 128 per tap) and, in prior[k], its
// geometric prior (the mrf weight, eq. 4.18) in 1/256 minus one, summing to 256 per pixel.
// Bilinear sampling clamps to the image edge (BORDER_REPLICATE), pixel centres at integer + 0.5.
#pragma once

#include <algorithm>
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

namespace omma::render {

inline constexpr int kTileW = 64, kTileH = 32;  // output tile (pixels)
inline constexpr size_t kStorePadding = 64;     // bytes after the last store row
inline constexpr int kMaxTaps = 8;              // taps per output pixel (the strongest are kept)
// Store offsets are 32-bit in units of 2 bytes: the frame store of a rig holds less than 8 GiB
// (with core/limits.h's kMaxCameras = 4096 cameras, the limits of the map format and the renderer).
inline constexpr size_t kMaxStoreBytes = size_t(8) << 30;

// Geometry of the shared frame store of a rig (see the file comment).
struct StoreLayout {
  int stride_px = 0;           // pixels per store row (widest camera)
  int rows = 0;                // total rows (sum of the camera heights)
  std::vector<int> row0;       // first store row of each camera
  std::vector<cv::Size> size;  // each camera's frame size
  static StoreLayout for_rig(const Rig& rig);
  size_t stride_bytes() const { return size_t(stride_px) * 6; }
  size_t bytes() const { return stride_bytes() * rows + kStorePadding; }
  // Byte offset of the 2x2 neighbourhood of pixel (x, y) of camera c.
  size_t offset(int c, int x, int y) const { return size_t(row0[c] + y) * stride_bytes() + size_t(x) * 6; }
  // Camera whose rows hold store byte `offset`.
  int camera_at(size_t offset) const;
  // 1..kMaxCameras cameras of valid frame sizes, each camera's rows right after the previous one's,
  // rows and stride as for_rig gives them, bytes() < kMaxStoreBytes.
  bool IsValid(std::string* why = nullptr) const;
};

// One buffer holding the latest frame of every camera, in the row-pair layout.
// Any frame FrameStore::set accepts (8/16-bit or float, gray, BGR or BGRA) as CV_8UC3 BGR (shared,
// not copied, when it already is). Throws std::invalid_argument on other depths or channel counts.
cv::Mat to_bgr8(const cv::Mat& frame);

class FrameStore {
 public:
  FrameStore() = default;
  explicit FrameStore(StoreLayout layout);
  const StoreLayout& layout() const { return layout_; }
  // A copy of camera c's frame (CV_8UC3, H x W) as it was last set.
  cv::Mat camera(int c) const;
  // Stores `frame` (CV_8UC3 of the camera's size; gray, BGRA, 16-bit and float are converted) as
  // camera c's. Throws std::invalid_argument naming the camera if the size or type is wrong.
  void set(int c, const cv::Mat& frame);
  const uint8_t* data() const { return buffer_.data(); }

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
  // (never the strongest tap; 0 = keep every tap whose 1/128-quantised weight is not 0; not
  // applied to sad, whose weights are per frame). The mrf family gives many faint taps, and a faint
  // tap costs as much to render as a strong one. A dropped tap of weight w changes the output by at
  // most w times the difference between the cameras. Measured (mrf, prototype rig, vr180 540x540;
  // PSNR against reference_render, which keeps every tap):
  //   min_weight  taps/pixel  Louvre views  random-texture frames (cameras disagree entirely)
  //   0           2.45        62.6 dB       59.0 dB
  //   1/32        1.83        62.5 dB       54.0 dB
  //   1/20        1.66        62.1 dB       51.3 dB   <- default: >= 50 dB even on random frames
  //   1/16        1.59        61.8 dB       49.8 dB
  //   1/8         1.38        60.4 dB       44.6 dB
  // At 1080x1080 on 2 threads, 1/20 renders about 10 % faster than 1/32 (same run, interleaved).
  double min_weight = 1.0 / 20;
  // Part of the grid the map covers (grid pixels); empty = the whole grid. The map is then
  // window.width x window.height and its pixel (c, r) is grid pixel (window.x + c, window.y + r), with
  // the same taps as in the whole grid's map (mrf neighbours outside the window included): a
  // panorama too large for one map is rendered block by block (pano_render.h).
  cv::Rect window;
  bool IsValid(std::string* why = nullptr) const;
};

// The rig of the cameras that `active` selects (all if empty), and for each of its cameras the
// index of that camera in the full rig.
struct ActiveRig {
  Rig rig;
  std::vector<int> to_full;
};
ActiveRig active_cameras(const Rig& rig, const std::vector<bool>& active);

// One tap of an output pixel, decoded (CompiledMap::visit).
struct MapTap {
  size_t offset;  // store byte offset of the 2x2 neighbourhood
  uint8_t w[4];   // weights of (x,y), (x,y+1), (x+1,y), (x+1,y+1), 1/128
  int prior;      // sad: the prior weight in 1/256 (1..256); other methods: 0
  int weight() const { return w[0] + w[1] + w[2] + w[3]; }
};

struct CompiledMap {
  int width = 0, height = 0;
  // kSad: the taps hold the bilinear weights and `prior` the geometric prior of eq. 4.18 (the mrf
  // weights); render() computes the per-frame SAD weights (eq. 4.17-4.18) with its own kernel.
  pano::Method method = pano::Method::kLinear;
  float sad_epsilon = 1.0f / 255;
  StoreLayout layout;
  std::vector<uint32_t> tile_run, tile_tap, tile_base, tile_line;  // per tile + 1: first entry of it
  std::vector<uint8_t> runs;
  std::vector<uint32_t> base;
  std::vector<int16_t> delta;
  std::vector<uint32_t> weight;
  std::vector<uint8_t> prior;  // sad only
  std::vector<uint32_t> lines;

  int tiles_x() const { return (width + kTileW - 1) / kTileW; }
  int tiles_y() const { return (height + kTileH - 1) / kTileH; }
  int tiles() const { return tiles_x() * tiles_y(); }
  size_t taps() const { return weight.size(); }
  // Bytes of the frame store that a render reads: its distinct 64-byte lines.
  size_t store_bytes_read() const;
  // Bytes of the map per output pixel (everything the renderer reads except the frames).
  double bytes_per_pixel() const;
  size_t bytes() const;
  // Calls f(col, row, n, taps) for every output pixel (tile by tile), taps[0..n) decoded.
  template <class F>
  void visit(F&& f) const;
  // Everything the renderers rely on without checking, over the whole map (a loaded file is
  // untrusted input): size, method and the store layout (StoreLayout::IsValid); the tile indexes
  // against the arrays; every tile row's runs (at most kMaxTaps taps, exactly the row's width);
  // every tap inside the frame store; every weight byte at most 127 and each pixel's weights
  // summing to 128 (sad: 128 per tap, priors summing to 256); prefetch lines inside the store.
  // Linear in the size of the map (a few ms at 1080 x 1080); called when a map is loaded, never
  // while rendering.
  bool IsValid(std::string* why = nullptr) const;
};

// Compiles the map with the per-direction weights of pano (pano::find_contributors, method_weights,
// mrf_posterior) for every output pixel (oneTBB parallel). For sad the map holds the mrf prior; the
// per-frame weights are computed by render().
CompiledMap compile_map(const Rig& rig, const MapOptions& opt);

// Hash (hex) of everything the map depends on: rig (as JSON), grid, method, params, active set
// and the map format version.
std::string map_key(const Rig& rig, const MapOptions& opt);

// Map files (map_file.cc), format version kMapFormatVersion, native byte order:
//   u32 magic, u32 version, char key[16] (map_key), i32 width, height, method, f32 sad_epsilon,
//   i32 stride_px, rows, cameras, cameras x (i32 row0, width, height), then the arrays tile_run,
//   tile_tap, tile_base, tile_line, runs, base, delta, weight, prior, lines (each u64 count and the
//   elements), u32 magic, u32 CRC-32 (core/checksum.h) of every byte before it.
// 3: tiles, runs, row pairs; 4: 1/128; 5: key, CRC-32; 6: the unmirrored grids (core/conventions.h
// kGridConvention 2: a version-5 file maps the mirrored panorama and is refused).
inline constexpr uint32_t kMapFormatVersion = 6;
inline constexpr size_t kMapKeyBytes = 16;
std::vector<uint8_t> map_file_bytes(const CompiledMap& map, const std::string& key);
void save_map(const CompiledMap& map, const std::filesystem::path& path, const std::string& key);  // atomic
// Parses the bytes of a map file as untrusted input: the checksum over the whole file, every read
// against the bytes left (an array's length before it is allocated), the header's bounds and
// CompiledMap::IsValid. Never reads outside [data, data + n). nullopt and *why if anything fails;
// *key gets the key the file was written with.
std::optional<CompiledMap> parse_map(const uint8_t* data, size_t n, std::string* key = nullptr,
                                     std::string* why = nullptr);
// parse_map, then the header against what the map must be for `rig` and `opt`: key, size, method,
// sad epsilon and the store layout of every camera.
std::optional<CompiledMap> parse_map_for(const uint8_t* data, size_t n, const Rig& rig, const MapOptions& opt,
                                         std::string* why = nullptr);
// Reads `path` (a regular file of at most kMaxDataFileBytes) and parse_map_for()s it. nullopt and
// *why if the file is missing, unreadable or any check fails.
std::optional<CompiledMap> load_map(const std::filesystem::path& path, const Rig& rig, const MapOptions& opt,
                                    std::string* why = nullptr);

// Default cache folder: $OMMA_CACHE_DIR, else $XDG_CACHE_HOME/omma, else ~/.cache/omma, else
// /tmp/omma-cache-UID (the user's own folder in /tmp, never one shared between users).
std::filesystem::path default_cache_dir();

// The cache's trust model. A cached map decides every output pixel, and its name is a public hash of
// the rig and the options while its checksums can be recomputed by anyone: a map file is trusted
// only because nobody but the user could have put it there. So, as ssh checks ~/.ssh, the cache is
// used only if its folder belongs to the user running omma and no one else may write it (mode
// without group/other write), and a map file only if it is a regular file (not a link) of that user
// not writable by others. cache_dir_problem says why a folder fails ("" if it may be used; a missing
// folder may be: it is created with mode 0700); compile_map_cached then warns and compiles without
// the cache.
std::string cache_dir_problem(const std::filesystem::path& dir);

struct MapLoad {
  CompiledMap map;
  bool from_cache = false;
  double seconds = 0;  // time to compile or load
  std::filesystem::path file;
};
// Loads the map from `cache_dir`/omma-map-<key>.bin, or compiles and stores it there (atomically).
// A cached file that fails load_map (damaged, truncated, written for other options) is never used:
// a warning names the reason, and the map is compiled and the file replaced.
// An empty cache_dir disables the cache, and so does one that fails cache_dir_problem (with a
// warning). A cache write failure is logged, not fatal.
MapLoad compile_map_cached(const Rig& rig, const MapOptions& opt, const std::filesystem::path& cache_dir);

// ---------------------------------------------------------------------------------------------
template <class F>
void CompiledMap::visit(F&& f) const {
  MapTap taps[kMaxTaps];
  for (int t = 0; t < tiles(); ++t) {
    const int c0 = (t % tiles_x()) * kTileW, r0 = (t / tiles_x()) * kTileH;
    const int r1 = std::min(height, r0 + kTileH);
    const uint8_t* run = runs.data() + tile_run[t];
    size_t k = tile_tap[t], b = tile_base[t];
    for (int row = r0; row < r1; ++row, run += 2) {
      for (int col = c0; run[1] != 0; run += 2) {
        const int n = run[0];
        for (int p = 0; p < run[1]; ++p, ++col) {
          for (int i = 0; i < n; ++i, ++k) {
            const uint32_t w = weight[k];
            taps[i] = {size_t(int64_t(base[b + i]) + delta[k]) * 2,
                       {uint8_t(w), uint8_t(w >> 8), uint8_t(w >> 16), uint8_t(w >> 24)},
                       prior.empty() ? 0 : prior[k] + 1};
          }
          f(col, row, n, static_cast<const MapTap*>(taps));
        }
        b += n;
      }
    }
  }
}

}  // namespace omma::render
