#include "omma/render/compiled_map.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <tbb/parallel_for.h>

#include "omma/core/io.h"
#include "omma/core/limits.h"
#include "omma/core/log.h"
#include "omma/core/valid.h"

namespace omma::render {
namespace {

uint64_t fnv1a(const std::string& s) {
  uint64_t h = 1469598103934665603ull;
  for (unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

// Rounds n non-negative reals that sum to `total` to integers of at most `cap` that sum to exactly
// `total` (largest remainder first).
void quantise(const double* x, int n, int total, int cap, int* q) {
  double rem[4 * kMaxTaps];
  int sum = 0;
  for (int i = 0; i < n; ++i) {
    q[i] = std::min(cap, static_cast<int>(std::floor(x[i])));
    rem[i] = x[i] - q[i];
    sum += q[i];
  }
  while (sum < total) {
    int best = -1;
    for (int i = 0; i < n; ++i)
      if (q[i] < cap && (best < 0 || rem[i] > rem[best])) best = i;
    if (best < 0) break;  // n * cap < total: cannot happen for the callers
    q[best] += 1;
    rem[best] -= 1;
    ++sum;
  }
}

// Bilinear neighbourhood along one axis with replicated edges (centres at integer + 0.5): the
// first pixel i0 and the weight f of pixel i0 + 1.
void bilinear_axis(double p, int n, int& i0, double& f) {
  const double s = p - 0.5;
  const double fl = std::floor(s);
  i0 = static_cast<int>(fl);
  f = s - fl;
  if (i0 < 0) i0 = 0, f = 0;
  if (i0 >= n - 1) i0 = n - 1, f = 0;
}

// The taps of one output pixel, sorted by camera.
struct PixelTaps {
  uint8_t n = 0;
  uint32_t off2[kMaxTaps];    // store offset / 2 of the neighbourhood
  uint32_t weight[kMaxTaps];  // 4 weight bytes
  uint8_t prior[kMaxTaps];    // sad: prior in 1/256 minus one
};

// One tile's share of the map arrays, assembled independently, then concatenated.
struct TileData {
  std::vector<uint8_t> runs;
  std::vector<uint32_t> base, weight, lines;
  std::vector<int16_t> delta;
  std::vector<uint8_t> prior;
};

// Runs of one tile row (see compiled_map.h): a run continues while the tap count stays the same,
// it is shorter than 255 pixels and every tap's offset stays within int16 of the run's start.
void encode_tile_row(const PixelTaps* px, int w, bool sad, TileData& d) {
  for (int i = 0; i < w;) {
    const int n = px[i].n;
    int j = i + 1;
    auto fits = [&](int p) {
      if (px[p].n != n) return false;
      for (int t = 0; t < n; ++t) {
        const int64_t dd = int64_t(px[p].off2[t]) - int64_t(px[i].off2[t]);
        if (dd < INT16_MIN || dd > INT16_MAX) return false;
      }
      return true;
    };
    while (j < w && j - i < 255 && fits(j)) ++j;
    d.runs.push_back(static_cast<uint8_t>(n));
    d.runs.push_back(static_cast<uint8_t>(j - i));
    for (int t = 0; t < n; ++t) d.base.push_back(px[i].off2[t]);
    for (int p = i; p < j; ++p)
      for (int t = 0; t < n; ++t) {
        d.delta.push_back(static_cast<int16_t>(int64_t(px[p].off2[t]) - int64_t(px[i].off2[t])));
        d.weight.push_back(px[p].weight[t]);
        if (sad) d.prior.push_back(px[p].prior[t]);
      }
    i = j;
  }
  d.runs.push_back(0);
  d.runs.push_back(0);
}

}  // namespace

StoreLayout StoreLayout::for_rig(const Rig& rig) {
  StoreLayout l;
  int rows = 0;
  for (const auto& c : rig.cameras) {
    l.stride_px = std::max(l.stride_px, c.in.width);
    l.row0.push_back(rows);
    l.size.emplace_back(c.in.width, c.in.height);
    rows += c.in.height;
  }
  l.rows = rows;
  // Offsets are stored in units of 2 bytes in 32 bits.
  if (double(l.stride_bytes()) * l.rows + kStorePadding >= double(kMaxStoreBytes))
    throw std::invalid_argument("rig too large for the compiled map format: " + std::to_string(l.stride_px) +
                                " x " + std::to_string(l.rows) + " store pixels (limit 8 GB of frame store)");
  return l;
}

int StoreLayout::camera_at(size_t offset) const {
  const int row = static_cast<int>(offset / stride_bytes());
  const auto it = std::upper_bound(row0.begin(), row0.end(), row);
  return int(it - row0.begin()) - 1;
}

FrameStore::FrameStore(StoreLayout layout) : layout_(std::move(layout)) {
  buffer_.assign(layout_.bytes(), 0);
}

cv::Mat FrameStore::camera(int c) const {
  if (c < 0 || c >= static_cast<int>(layout_.size.size()))
    throw std::invalid_argument("frame store: no camera index " + std::to_string(c));
  const cv::Size s = layout_.size[c];
  cv::Mat out(s, CV_8UC3);
  for (int y = 0; y < s.height; ++y) {
    const uint8_t* src = buffer_.data() + layout_.offset(c, 0, y);
    uint8_t* dst = out.ptr<uint8_t>(y);
    for (int x = 0; x < s.width; ++x)
      for (int ch = 0; ch < 3; ++ch) dst[3 * x + ch] = src[6 * x + ch];
  }
  return out;
}

cv::Mat to_bgr8(const cv::Mat& frame) {
  cv::Mat src = frame;
  if (src.depth() == CV_16U)
    src.convertTo(src, CV_8U, 1.0 / 257.0);
  else if (src.depth() == CV_32F)
    src.convertTo(src, CV_8U, 255.0);
  else if (src.depth() != CV_8U)
    throw std::invalid_argument("unsupported frame depth");
  if (src.channels() == 1)
    cv::cvtColor(src, src, cv::COLOR_GRAY2BGR);
  else if (src.channels() == 4)
    cv::cvtColor(src, src, cv::COLOR_BGRA2BGR);
  else if (src.channels() != 3)
    throw std::invalid_argument("unsupported channel count");
  return src;
}

void FrameStore::set(int c, const cv::Mat& frame) {
  if (c < 0 || c >= static_cast<int>(layout_.size.size()))
    throw std::invalid_argument("frame store: no camera index " + std::to_string(c));
  if (frame.size() != layout_.size[c])
    throw std::invalid_argument("camera index " + std::to_string(c) + ": frame is " +
                                std::to_string(frame.cols) + "x" + std::to_string(frame.rows) +
                                ", the rig says " + std::to_string(layout_.size[c].width) + "x" +
                                std::to_string(layout_.size[c].height));
  cv::Mat src;
  try {
    src = to_bgr8(frame);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("camera index " + std::to_string(c) + ": " + e.what());
  }
  // Row pairs: 3 bytes of row y then 3 bytes of row y + 1 per pixel. Each pixel is one
  // 8-byte store of which the next pixel overwrites the last two bytes; the row's last pixel is
  // written byte by byte so that nothing outside the row is touched.
  const int W = src.cols, H = src.rows;
  for (int y = 0; y < H; ++y) {
    const uint8_t* r0 = src.ptr<uint8_t>(y);
    const uint8_t* r1 = src.ptr<uint8_t>(std::min(y + 1, H - 1));
    uint8_t* d = buffer_.data() + layout_.offset(c, 0, y);
    int x = 0;
    for (; x + 2 <= W; ++x) {  // 4-byte loads stay inside the row while a next pixel follows
      uint32_t a, b;
      std::memcpy(&a, r0 + 3 * x, 4);
      std::memcpy(&b, r1 + 3 * x, 4);
      const uint64_t v = (uint64_t(a) & 0xFFFFFF) | ((uint64_t(b) & 0xFFFFFF) << 24);
      std::memcpy(d + 6 * x, &v, 8);
    }
    for (; x < W; ++x)
      for (int ch = 0; ch < 3; ++ch) {
        d[6 * x + ch] = r0[3 * x + ch];
        d[6 * x + 3 + ch] = r1[3 * x + ch];
      }
  }
}

size_t CompiledMap::bytes() const {
  return (tile_run.size() + tile_tap.size() + tile_base.size() + tile_line.size()) * 4 + runs.size() +
         base.size() * 4 + delta.size() * 2 + weight.size() * 4 + prior.size() + lines.size() * 4;
}

size_t CompiledMap::store_bytes_read() const {
  std::vector<uint32_t> all = lines;
  std::sort(all.begin(), all.end());
  return size_t(std::unique(all.begin(), all.end()) - all.begin()) * 64;
}

double CompiledMap::bytes_per_pixel() const {
  const double px = double(width) * height;
  return px > 0 ? double(bytes()) / px : 0;
}

ActiveRig active_cameras(const Rig& rig, const std::vector<bool>& active) {
  ActiveRig a;
  a.rig = rig;
  a.rig.cameras.clear();
  for (size_t i = 0; i < rig.cameras.size(); ++i)
    if (active.empty() || active[i]) {
      a.rig.cameras.push_back(rig.cameras[i]);
      a.to_full.push_back(static_cast<int>(i));
    }
  return a;
}

bool MapOptions::IsValid(std::string* why) const {
  try {
    // A map of the whole panorama is an image; a band map (window) may belong to a larger
    // panorama rendered band by band (core/limits.h).
    if (window.empty()) {
      check_image_size(grid.width, grid.height, "panorama size");
    } else {
      check_banded_size(grid.width, grid.height, "panorama size");
      // A band spans the panorama's width (up to kMaxBandedSide) but holds at most an image's pixels.
      check_banded_size(window.width, window.height, "map window");
      if (int64_t(window.width) * window.height > kMaxImagePixels)
        return invalid(why, fmt::format("map window {}x{} holds more than {} pixels", window.width,
                                        window.height, kMaxImagePixels));
    }
  } catch (const std::invalid_argument& e) {
    return invalid(why, e.what());
  }
  if (!window.empty() && (window.x < 0 || window.y < 0 || window.x + window.width > grid.width ||
                          window.y + window.height > grid.height))
    return invalid(why, "the map's window must lie inside the panorama");
  if (!(min_weight >= 0 && min_weight < 0.5)) return invalid(why, "min_weight must be in [0, 0.5)");
  return true;
}

namespace {

// The taps of a map's output pixels, block by block (eq. 2.3 contributors, the method's weights,
// then the 8-bit fixed-point taps of compiled_map.h).
class TapCompiler {
 public:
  TapCompiler(const Rig& rig, const MapOptions& opt, const cv::Rect& win, const StoreLayout& layout)
      : opt_(opt),
        wx_(win.x),
        wy_(win.y),
        W_(win.width),
        H_(win.height),
        layout_(layout),
        sad_(opt.method == pano::Method::kSad),
        needs_nb_(pano::uses_neighbours(opt.method)),
        spherical_(opt.method == pano::Method::kMrfSpherical) {
    ActiveRig active = active_cameras(rig, opt.active);
    sub_ = std::move(active.rig);
    to_full_ = std::move(active.to_full);
    cam_half_.resize(sub_.cameras.size());
    for (size_t c = 0; c < sub_.cameras.size(); ++c) cam_half_[c] = sub_.cameras[c].in.aov / 2;
  }

  // The taps of the output pixels [c0, c1) x [r0, r1) (at most 16 x 16) into `px` (kTileW pixels per
  // row, starting at pixel (pc, pr)).
  void compute(int c0, int r0, int c1, int r1, PixelTaps* px, int pc, int pr) const {
    Block b = block(c0, r0, c1, r1);
    for (int row = r0; row < r1; ++row)
      for (int col = c0; col < c1; ++col) {
        PixelTaps& out = px[size_t(row - pr) * kTileW + (col - pc)];
        if (b.rig.cameras.empty()) continue;
        std::vector<pano::Tap> taps = weighted_taps(b, col, row);
        if (!taps.empty()) encode(b, taps, out);
      }
  }

 private:
  // Per node: its contributors and, for the mrf family, their potentials (eq. 4.8), each computed
  // once although every node is visited as the centre and as 4 neighbours.
  struct Node {
    std::vector<pano::Contributor> cs;
    std::vector<double> phi;
  };
  // One block: the rig of the cameras that can reach it, and its nodes with a one-pixel border.
  struct Block {
    Rig rig;
    std::vector<int> to_full;  // block camera -> rig camera
    int bx0, by0, bx1, by1;
    std::vector<Node> found;
    std::vector<uint8_t> done;
    std::array<Node, 4> outside;
  };

  Vec3 grid_dir(double x, double y) const { return opt_.grid.direction(x + wx_, y + wy_); }

  // The rig of the cameras whose cone of view (eq. 2.3) can reach the block's pixels (with a margin
  // for the 4-neighbourhood of mrf): the taps are the same as with the full rig, at a fraction of the
  // cost.
  Block block(int c0, int r0, int c1, int r1) const {
    Block b;
    if (opt_.cull) {
      b.rig.name = sub_.name;
      b.rig.dome = sub_.dome;
      const Vec3 wc = grid_dir(0.5 * (c0 + c1), 0.5 * (r0 + r1));
      double radius = 0;
      for (double fy : {0.0, 0.5, 1.0})
        for (double fx : {0.0, 0.5, 1.0}) {
          const double x =
              std::clamp(c0 - 2 + fx * (c1 - c0 + 4), -double(wx_), double(opt_.grid.width - wx_));
          const double y =
              std::clamp(r0 - 2 + fy * (r1 - r0 + 4), -double(wy_), double(opt_.grid.height - wy_));
          radius = std::max(radius, angle_between(wc, grid_dir(x, y)));
        }
      radius += deg2rad(2.0);
      for (size_t c = 0; c < sub_.cameras.size(); ++c)
        if (angle_between(wc, sub_.cameras[c].frame.t) <= cam_half_[c] + radius) {
          b.rig.cameras.push_back(sub_.cameras[c]);
          b.to_full.push_back(to_full_[c]);
        }
    } else {
      b.rig = sub_;
      b.to_full = to_full_;
    }
    // Contributors (eq. 2.3) of the block and a one-pixel border, found once and shared by the
    // 4-neighbourhoods of mrf, mrf-spherical and sad.
    b.bx0 = std::max(0, c0 - 1);
    b.by0 = std::max(0, r0 - 1);
    b.bx1 = std::min(W_, c1 + 1);
    b.by1 = std::min(H_, r1 + 1);
    b.found.resize(size_t(b.bx1 - b.bx0) * (b.by1 - b.by0));
    b.done.assign(b.found.size(), 0);
    return b;
  }

  void fill(const Block& b, Node& n, int col, int row) const {
    n.cs =
        pano::find_contributors(b.rig, opt_.grid.pixel_direction(col + wx_, row + wy_), opt_.params.search);
    if (needs_nb_) n.phi = pano::node_potentials(n.cs, spherical_);
  }
  const Node& node(Block& b, int col, int row, int slot) const {
    if (col >= b.bx0 && col < b.bx1 && row >= b.by0 && row < b.by1) {
      const size_t i = size_t(row - b.by0) * (b.bx1 - b.bx0) + (col - b.bx0);
      if (!b.done[i]) {
        fill(b, b.found[i], col, row);
        b.done[i] = 1;
      }
      return b.found[i];
    }
    fill(b, b.outside[slot], col, row);  // equirect wrap-around neighbours
    return b.outside[slot];
  }

  // The weights of pixel (col, row) exactly as static_taps computes them (pano::method_weights):
  // at most kMaxTaps (the strongest), the faint ones dropped (MapOptions::min_weight), sorted by
  // camera so that tap t of neighbouring pixels usually comes from the same camera (the runs of the
  // map, compiled_map.h). Cameras are the block's.
  std::vector<pano::Tap> weighted_taps(Block& b, int col, int row) const {
    const Node& u = node(b, col, row, 0);
    const std::vector<pano::Contributor>& cs = u.cs;
    if (cs.empty()) return {};
    std::vector<double> mw;
    if (needs_nb_) {  // = pano::method_weights, with the cached potentials
      std::array<pano::MrfNode, 4> nb;
      const auto nbs = pano::grid_neighbours(opt_.grid, col + wx_, row + wy_);
      for (int k = 0; k < 4; ++k)
        if (nbs[k][0] >= 0) {
          const Node& v = node(b, nbs[k][0] - wx_, nbs[k][1] - wy_, k);
          nb[k] = {&v.cs, &v.phi};
        }
      mw = pano::mrf_posterior(cs, u.phi, nb);
    } else {
      mw = pano::method_weights(b.rig, opt_.method, cs, {nullptr, nullptr, nullptr, nullptr}, opt_.params);
    }
    std::vector<pano::Tap> taps;
    for (size_t i = 0; i < cs.size(); ++i)
      if (mw[i] > 0) taps.push_back({cs[i].camera, cs[i].px, mw[i]});
    if (taps.size() > size_t(kMaxTaps)) {  // keep the strongest (never happens with real rigs)
      std::partial_sort(taps.begin(), taps.begin() + kMaxTaps, taps.end(),
                        [](auto& a, auto& b) { return a.weight > b.weight; });
      taps.resize(kMaxTaps);
    }
    double total = 0;
    for (const auto& t : taps) total += t.weight;
    if (opt_.min_weight > 0 && !sad_ && total > 0) {  // drop the faint taps, never the strongest
      const double strongest = std::max_element(taps.begin(), taps.end(), [](auto& a, auto& b) {
                                 return a.weight < b.weight;
                               })->weight;
      std::erase_if(taps, [&](const pano::Tap& t) {
        return t.weight < opt_.min_weight * total && t.weight < strongest;
      });
    }
    std::sort(taps.begin(), taps.end(), [&](auto& a, auto& b) { return a.camera < b.camera; });
    return taps;
  }

  // The fixed-point taps of one pixel: the tap weights in 1/128 (summing to 128), then per tap the
  // 2x2 neighbourhood and its four bilinear weights times the tap's weight, rounded to integers that
  // sum to it (each at most 127, the kernels' signed bytes: a lone tap exactly on a pixel centre
  // gives 127 + 1 to its neighbour below). sad keeps the bilinear weights alone (128 per tap) and
  // its prior, the tap weights, in 1/256.
  void encode(const Block& b, const std::vector<pano::Tap>& taps, PixelTaps& out) const {
    double w[kMaxTaps], e[4 * kMaxTaps];
    int q[kMaxTaps], qe[4 * kMaxTaps];
    const int n = static_cast<int>(taps.size());
    double sum = 0;
    for (int k = 0; k < n; ++k) sum += (w[k] = taps[k].weight);
    if (sum <= 0) return;
    for (int k = 0; k < n; ++k) w[k] /= sum;
    double pw[kMaxTaps];
    for (int k = 0; k < n; ++k) pw[k] = w[k] * (sad_ ? 256.0 : 128.0);
    quantise(pw, n, sad_ ? 256 : 128, 256, q);
    uint32_t off2[kMaxTaps];
    for (int k = 0; k < n; ++k) {
      const int cam = b.to_full[taps[k].camera];
      int x0, y0;
      double fx, fy;
      bilinear_axis(taps[k].px.x(), layout_.size[cam].width, x0, fx);
      bilinear_axis(taps[k].px.y(), layout_.size[cam].height, y0, fy);
      off2[k] = static_cast<uint32_t>(layout_.offset(cam, x0, y0) / 2);
      const int total = sad_ ? 128 : q[k];
      const double bw[4] = {(1 - fx) * (1 - fy), (1 - fx) * fy, fx * (1 - fy), fx * fy};
      for (int j = 0; j < 4; ++j) e[4 * k + j] = bw[j] * total;
      quantise(e + 4 * k, 4, total, 127, qe + 4 * k);
    }
    for (int k = 0; k < n; ++k) {
      const int* qk = qe + 4 * k;
      if (q[k] == 0) continue;
      out.off2[out.n] = off2[k];
      out.weight[out.n] =
          uint32_t(qk[0]) | uint32_t(qk[1]) << 8 | uint32_t(qk[2]) << 16 | uint32_t(qk[3]) << 24;
      out.prior[out.n] = sad_ ? static_cast<uint8_t>(q[k] - 1) : 0;
      ++out.n;
    }
  }

  const MapOptions& opt_;
  const int wx_, wy_, W_, H_;
  const StoreLayout& layout_;
  const bool sad_, needs_nb_, spherical_;
  Rig sub_;                   // the rig of the active cameras
  std::vector<int> to_full_;  // its camera index -> rig camera index
  std::vector<double> cam_half_;
};

// Tile t of `map` (kTileW x kTileH): computed in blocks of 16 x 16 pixels and encoded, with the
// store's cache lines it reads (16 bytes per tap) for the renderer's prefetch.
TileData compile_tile(const CompiledMap& map, const TapCompiler& taps, int t) {
  const int c0 = (t % map.tiles_x()) * kTileW, r0 = (t / map.tiles_x()) * kTileH;
  const int c1 = std::min(map.width, c0 + kTileW), r1 = std::min(map.height, r0 + kTileH);
  std::vector<PixelTaps> px(size_t(kTileW) * kTileH);
  constexpr int kBlock = 16;
  for (int br = r0; br < r1; br += kBlock)
    for (int bc = c0; bc < c1; bc += kBlock)
      taps.compute(bc, br, std::min(c1, bc + kBlock), std::min(r1, br + kBlock), px.data(), c0, r0);
  const bool sad = map.method == pano::Method::kSad;
  TileData d;
  for (int row = r0; row < r1; ++row) encode_tile_row(&px[size_t(row - r0) * kTileW], c1 - c0, sad, d);
  for (int row = r0; row < r1; ++row)
    for (int col = c0; col < c1; ++col) {
      const PixelTaps& p = px[size_t(row - r0) * kTileW + (col - c0)];
      for (int k = 0; k < p.n; ++k)
        for (size_t b : {size_t(p.off2[k]) * 2, size_t(p.off2[k]) * 2 + 15})
          d.lines.push_back(uint32_t(b / 64 * 64));
    }
  std::sort(d.lines.begin(), d.lines.end());
  d.lines.erase(std::unique(d.lines.begin(), d.lines.end()), d.lines.end());
  return d;
}

// The tiles, encoded independently, concatenated into the map's arrays.
void concatenate_tiles(const std::vector<TileData>& td, CompiledMap& map) {
  const int ntiles = static_cast<int>(td.size());
  const bool sad = map.method == pano::Method::kSad;
  map.tile_run.assign(ntiles + 1, 0);
  map.tile_tap.assign(ntiles + 1, 0);
  map.tile_base.assign(ntiles + 1, 0);
  map.tile_line.assign(ntiles + 1, 0);
  for (int t = 0; t < ntiles; ++t) {
    map.tile_run[t + 1] = map.tile_run[t] + uint32_t(td[t].runs.size());
    map.tile_tap[t + 1] = map.tile_tap[t] + uint32_t(td[t].weight.size());
    map.tile_base[t + 1] = map.tile_base[t] + uint32_t(td[t].base.size());
    map.tile_line[t + 1] = map.tile_line[t] + uint32_t(td[t].lines.size());
  }
  map.runs.resize(map.tile_run.back());
  map.weight.resize(map.tile_tap.back());
  map.delta.resize(map.tile_tap.back());
  if (sad) map.prior.resize(map.tile_tap.back());
  map.base.resize(map.tile_base.back());
  map.lines.resize(map.tile_line.back());
  tbb::parallel_for(0, ntiles, [&](int t) {
    const TileData& d = td[t];
    std::copy(d.runs.begin(), d.runs.end(), map.runs.begin() + map.tile_run[t]);
    std::copy(d.weight.begin(), d.weight.end(), map.weight.begin() + map.tile_tap[t]);
    std::copy(d.delta.begin(), d.delta.end(), map.delta.begin() + map.tile_tap[t]);
    if (sad) std::copy(d.prior.begin(), d.prior.end(), map.prior.begin() + map.tile_tap[t]);
    std::copy(d.base.begin(), d.base.end(), map.base.begin() + map.tile_base[t]);
    std::copy(d.lines.begin(), d.lines.end(), map.lines.begin() + map.tile_line[t]);
  });
}

}  // namespace

CompiledMap compile_map(const Rig& rig, const MapOptions& opt) {
  if (std::string why; !opt.IsValid(&why)) throw std::invalid_argument("compile_map: " + why);
  if (!opt.active.empty() && opt.active.size() != rig.cameras.size())
    throw std::invalid_argument("compile_map: active set has " + std::to_string(opt.active.size()) +
                                " entries for " + std::to_string(rig.cameras.size()) + " cameras");
  CompiledMap map;
  // The window of the grid this map covers (map pixel (c, r) = grid pixel (wx + c, wy + r)).
  const cv::Rect win = opt.window.empty() ? cv::Rect(0, 0, opt.grid.width, opt.grid.height) : opt.window;
  map.width = win.width;
  map.height = win.height;
  map.method = opt.method;
  map.sad_epsilon = static_cast<float>(opt.params.sad_epsilon);
  map.layout = StoreLayout::for_rig(rig);
  const TapCompiler taps(rig, opt, win, map.layout);
  std::vector<TileData> td(map.tiles());
  tbb::parallel_for(0, map.tiles(), [&](int t) { td[t] = compile_tile(map, taps, t); });
  concatenate_tiles(td, map);
  return map;
}

std::string map_key(const Rig& rig, const MapOptions& opt) {
  nlohmann::json j;
  j["rig"] = rig_to_json(rig);
  j["projection"] = to_string(opt.grid.projection);
  j["size"] = {opt.grid.width, opt.grid.height};
  if (!opt.window.empty()) j["window"] = {opt.window.x, opt.window.y, opt.window.width, opt.window.height};
  j["method"] = pano::to_string(opt.method);
  j["q"] = {opt.params.search.q.x(), opt.params.search.q.y(), opt.params.search.q.z()};
  j["min_r"] = opt.params.search.min_r_mm;
  j["sigma"] = opt.params.gaussian_sigma_rel;
  j["sad_eps"] = opt.params.sad_epsilon;
  if (opt.min_weight > 0) j["min_weight"] = opt.min_weight;
  std::string active;
  for (bool a : opt.active) active += a ? '1' : '0';
  j["active"] = active;
  j["format"] = kMapFormatVersion;
  j["grid_convention"] = kGridConvention;  // no map of the mirrored grids is ever reused
  char buf[32];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(fnv1a(j.dump())));
  return buf;
}

std::optional<CompiledMap> parse_map_for(const uint8_t* data, size_t n, const Rig& rig, const MapOptions& opt,
                                         std::string* why) {
  auto fail = [&](const std::string& m) -> std::optional<CompiledMap> {
    if (why) *why = m;
    return std::nullopt;
  };
  std::string key;
  std::optional<CompiledMap> m = parse_map(data, n, &key, why);
  if (!m) return m;
  // The header against the rig and the options (the file name says the key, the file may not).
  if (key != map_key(rig, opt)) return fail("written for another rig or other options (key " + key + ")");
  const int want_w = opt.window.empty() ? opt.grid.width : opt.window.width;  // a band map: its window
  const int want_h = opt.window.empty() ? opt.grid.height : opt.window.height;
  if (m->width != want_w || m->height != want_h || m->method != opt.method ||
      m->sad_epsilon != static_cast<float>(opt.params.sad_epsilon))
    return fail("size, method or sad epsilon differ from the options");
  const StoreLayout want = StoreLayout::for_rig(rig);
  if (m->layout.stride_px != want.stride_px || m->layout.rows != want.rows || m->layout.row0 != want.row0 ||
      m->layout.size != want.size)
    return fail("frame store layout differs from the rig's cameras");
  return m;
}

std::optional<CompiledMap> load_map(const std::filesystem::path& path, const Rig& rig, const MapOptions& opt,
                                    std::string* why) {
  std::vector<uint8_t> bytes;
  try {
    bytes = read_file(path, kMaxDataFileBytes, "map file");
  } catch (const IoError& e) {
    if (why) *why = e.what();
    return std::nullopt;
  }
  return parse_map_for(bytes.data(), bytes.size(), rig, opt, why);
}

std::filesystem::path default_cache_dir() {
  if (const char* d = std::getenv("OMMA_CACHE_DIR"); d && *d) return d;
  if (const char* d = std::getenv("XDG_CACHE_HOME"); d && *d) return std::filesystem::path(d) / "omma";
  if (const char* d = std::getenv("HOME"); d && *d) return std::filesystem::path(d) / ".cache" / "omma";
  return fmt::format("/tmp/omma-cache-{}", ::getuid());
}

namespace {

// Who owns `st` and who else may write it: "" if only the user running omma may.
std::string owner_problem(const struct stat& st, const std::string& what) {
  if (st.st_uid != ::getuid())
    return fmt::format("{} belongs to user {}, not to you (user {})", what, st.st_uid, ::getuid());
  if (st.st_mode & (S_IWGRP | S_IWOTH))
    return fmt::format("{} may be written by others (mode {:o}; chmod go-w it)", what, st.st_mode & 07777);
  return "";
}

// A cached map file: a regular file (not a link) of the user, written by no one else.
std::string cache_file_problem(const std::filesystem::path& file) {
  struct stat st {};
  if (::lstat(file.c_str(), &st) != 0) return "";  // missing: compiled and written
  if (!S_ISREG(st.st_mode)) return "map cache file " + file.string() + " is not a regular file";
  return owner_problem(st, "map cache file " + file.string());
}

}  // namespace

std::string cache_dir_problem(const std::filesystem::path& dir) {
  struct stat st {};
  if (::lstat(dir.c_str(), &st) != 0) return "";  // missing: created with mode 0700
  if (S_ISLNK(st.st_mode) && ::stat(dir.c_str(), &st) != 0)
    return "map cache folder " + dir.string() + " is a dangling link";
  if (!S_ISDIR(st.st_mode)) return "map cache folder " + dir.string() + " is not a folder";
  return owner_problem(st, "map cache folder " + dir.string());
}

MapLoad compile_map_cached(const Rig& rig, const MapOptions& opt, const std::filesystem::path& cache_dir) {
  const auto t0 = std::chrono::steady_clock::now();
  MapLoad out;
  std::string key;
  std::filesystem::path dir = cache_dir;
  if (const std::string problem = dir.empty() ? "" : cache_dir_problem(dir); !problem.empty()) {
    spdlog::warn("map cache not used: {}", problem);
    dir.clear();
  }
  if (!dir.empty()) {
    key = map_key(rig, opt);
    out.file = dir / ("omma-map-" + key + ".bin");
    std::string why;
    if (const std::string problem = cache_file_problem(out.file); !problem.empty()) {
      spdlog::warn("map cache file not used: {}: compiling the map again", problem);
    } else if (auto m = load_map(out.file, rig, opt, &why)) {
      out.map = std::move(*m);
      out.from_cache = true;
    } else if (std::error_code ec; std::filesystem::exists(out.file, ec)) {
      spdlog::warn("map cache file {} not used ({}): compiling the map again", out.file.string(), why);
    }
  }
  if (!out.from_cache) {
    out.map = compile_map(rig, opt);
    if (!dir.empty()) {
      try {
        if (!std::filesystem::exists(dir)) {
          std::filesystem::create_directories(dir);
          std::filesystem::permissions(dir, std::filesystem::perms::owner_all);  // 0700
        }
        save_map(out.map, out.file, key);
        std::filesystem::permissions(
            out.file, std::filesystem::perms::owner_read | std::filesystem::perms::owner_write);
      } catch (const std::exception& e) {
        spdlog::warn("map cache not written ({})", e.what());
      }
    }
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace omma::render
