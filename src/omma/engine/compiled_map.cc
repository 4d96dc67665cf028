#include "omma/engine/compiled_map.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <tbb/parallel_for.h>

#include "omma/core/io.h"
#include "omma/core/log.h"

namespace omma::engine {
namespace {

constexpr uint32_t kMagic = 0x4d4d4f31;  // "1OMM"
constexpr uint32_t kFormatVersion = 2;

uint64_t fnv1a(const std::string& s) {
  uint64_t h = 1469598103934665603ull;
  for (unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

// Quantises n <= 8 weights (sum 1) to integers in 1/256 that sum to exactly 256 (largest
// remainder first); taps that get 0 are dropped by the caller.
void quantise_weights(const double* w, int n, int* q) {
  double rem[8];
  int sum = 0;
  for (int i = 0; i < n; ++i) {
    const double x = w[i] * 256.0;
    q[i] = static_cast<int>(std::floor(x));
    rem[i] = x - q[i];
    sum += q[i];
  }
  while (sum < 256) {
    int best = 0;
    for (int i = 1; i < n; ++i)
      if (rem[i] > rem[best]) best = i;
    q[best] += 1;
    rem[best] = -1;
    ++sum;
  }
}

struct PixelTaps {
  uint8_t n = 0;
  uint32_t word[8];
  uint8_t weight[8];
};

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
  l.rows = rows + 1;  // padding row: the y+1 neighbour of a tap with fy = 0 in the last row
  if (double(l.stride_px) * l.rows >= double(1u << kIndexBits))
    throw std::invalid_argument("rig too large for the compiled map format: " +
                                std::to_string(l.stride_px) + " x " + std::to_string(l.rows) +
                                " store pixels (limit 4194304)");
  return l;
}

FrameStore::FrameStore(StoreLayout layout) : layout_(std::move(layout)) {
  buffer_.assign(layout_.bytes(), 0);
}

cv::Mat FrameStore::camera(int c) {
  return cv::Mat(layout_.size[c], CV_8UC3, buffer_.data() + size_t(layout_.row0[c]) * layout_.stride_px * 3,
                 size_t(layout_.stride_px) * 3);
}
cv::Mat FrameStore::camera(int c) const { return const_cast<FrameStore*>(this)->camera(c); }

void FrameStore::set(int c, const cv::Mat& frame) {
  if (c < 0 || c >= static_cast<int>(layout_.size.size()))
    throw std::invalid_argument("frame store: no camera index " + std::to_string(c));
  if (frame.size() != layout_.size[c])
    throw std::invalid_argument("camera index " + std::to_string(c) + ": frame is " +
                                std::to_string(frame.cols) + "x" + std::to_string(frame.rows) +
                                ", the rig says " + std::to_string(layout_.size[c].width) + "x" +
                                std::to_string(layout_.size[c].height));
  cv::Mat dst = camera(c);
  cv::Mat src = frame;
  if (src.depth() == CV_16U) src.convertTo(src, CV_8U, 1.0 / 257.0);
  else if (src.depth() == CV_32F) src.convertTo(src, CV_8U, 255.0);
  else if (src.depth() != CV_8U)
    throw std::invalid_argument("camera index " + std::to_string(c) + ": unsupported frame depth");
  if (src.channels() == 1) cv::cvtColor(src, dst, cv::COLOR_GRAY2BGR);
  else if (src.channels() == 4) cv::cvtColor(src, dst, cv::COLOR_BGRA2BGR);
  else if (src.channels() == 3) src.copyTo(dst);
  else throw std::invalid_argument("camera index " + std::to_string(c) + ": unsupported channel count");
}

double CompiledMap::bytes_per_pixel() const {
  const double px = double(width) * height;
  return px > 0 ? double(bytes()) / px : 0;
}

size_t CompiledMap::bytes() const {
  return count.size() + word.size() * 4 + weight.size() + row_start.size() * 4;
}

int CompiledMap::camera_of(uint32_t w) const {
  const int row = int((w & ((1u << kIndexBits) - 1)) / uint32_t(layout.stride_px));
  const auto it = std::upper_bound(layout.row0.begin(), layout.row0.end(), row);
  return int(it - layout.row0.begin()) - 1;
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
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (grid.width <= 0 || grid.height <= 0) return fail("panorama size must be positive");
  if (!(min_weight >= 0 && min_weight < 0.5)) return fail("min_weight must be in [0, 0.5)");
  return true;
}

CompiledMap compile_map(const Rig& rig, const MapOptions& opt) {
  if (std::string why; !opt.IsValid(&why)) throw std::invalid_argument("compile_map: " + why);
  if (!opt.active.empty() && opt.active.size() != rig.cameras.size())
    throw std::invalid_argument("compile_map: active set has " + std::to_string(opt.active.size()) +
                                " entries for " + std::to_string(rig.cameras.size()) + " cameras");
  CompiledMap map;
  map.width = opt.grid.width;
  map.height = opt.grid.height;
  map.method = opt.method;
  map.sad_epsilon = static_cast<float>(opt.params.sad_epsilon);
  map.layout = StoreLayout::for_rig(rig);
  // The rig of the active cameras, and its camera index -> rig camera index.
  const auto [sub, to_full] = active_cameras(rig, opt.active);
  const int W = map.width, H = map.height;
  std::vector<PixelTaps> px(size_t(W) * H);
  const StoreLayout& L = map.layout;
  // Tiles of kTile x kTile output pixels; each tile calls static_taps with the rig of the cameras
  // whose cone of view (eq. 2.3) can reach the tile (with a margin for the 4-neighbourhood of mrf):
  // the taps are the same as with the full rig, at a fraction of the cost.
  constexpr int kTile = 16;
  const int tiles_x = (W + kTile - 1) / kTile, tiles_y = (H + kTile - 1) / kTile;
  std::vector<double> cam_half(sub.cameras.size());
  for (size_t c = 0; c < sub.cameras.size(); ++c) cam_half[c] = sub.cameras[c].in.aov / 2;
  tbb::parallel_for(0, tiles_x * tiles_y, [&](int tile) {
    const int tx = tile % tiles_x, ty = tile / tiles_x;
    const int c0 = tx * kTile, r0 = ty * kTile, c1 = std::min(W, c0 + kTile), r1 = std::min(H, r0 + kTile);
    Rig tile_rig;
    std::vector<int> tile_to_full;
    if (opt.cull) {
      tile_rig.name = sub.name;
      tile_rig.dome = sub.dome;
      const Vec3 wc = opt.grid.direction(0.5 * (c0 + c1), 0.5 * (r0 + r1));
      double radius = 0;
      for (double fy : {0.0, 0.5, 1.0})
        for (double fx : {0.0, 0.5, 1.0}) {
          const double x = std::clamp(c0 - 2 + fx * (c1 - c0 + 4), 0.0, double(W));
          const double y = std::clamp(r0 - 2 + fy * (r1 - r0 + 4), 0.0, double(H));
          radius = std::max(radius, angle_between(wc, opt.grid.direction(x, y)));
        }
      radius += deg2rad(2.0);
      for (size_t c = 0; c < sub.cameras.size(); ++c)
        if (angle_between(wc, sub.cameras[c].frame.t) <= cam_half[c] + radius) {
          tile_rig.cameras.push_back(sub.cameras[c]);
          tile_to_full.push_back(to_full[c]);
        }
    } else {
      tile_rig = sub;
      tile_to_full = to_full;
    }
    double w[8];
    int q[8];
    // Contributors (eq. 2.3) of the tile and a one-pixel border, found once and shared by the
    // 4-neighbourhoods of mrf, mrf-spherical and sad; then the weights exactly as static_taps
    // computes them (pano::method_weights).
    const bool needs_nb = pano::uses_neighbours(opt.method);
    const bool prune = opt.min_weight > 0 && opt.method != pano::Method::kSad;
    const int bx0 = std::max(0, c0 - 1), by0 = std::max(0, r0 - 1);
    const int bx1 = std::min(W, c1 + 1), by1 = std::min(H, r1 + 1), bw = bx1 - bx0;
    // Per node: its contributors and, for the mrf family, their potentials (eq. 4.8), each
    // computed once although every node is visited as the centre and as 4 neighbours.
    struct Node {
      std::vector<pano::Contributor> cs;
      std::vector<double> phi;
    };
    const bool spherical = opt.method == pano::Method::kMrfSpherical;
    std::vector<Node> found(size_t(bw) * (by1 - by0));
    std::vector<uint8_t> done(found.size(), 0);
    std::array<Node, 4> outside;
    auto fill = [&](Node& n, int col, int row) {
      n.cs = pano::find_contributors(tile_rig, opt.grid.pixel_direction(col, row), opt.params.search);
      if (needs_nb) n.phi = pano::node_potentials(n.cs, spherical);
    };
    auto node = [&](int col, int row, int slot) -> const Node& {
      if (col >= bx0 && col < bx1 && row >= by0 && row < by1) {
        const size_t i = size_t(row - by0) * bw + (col - bx0);
        if (!done[i]) {
          fill(found[i], col, row);
          done[i] = 1;
        }
        return found[i];
      }
      fill(outside[slot], col, row);  // equirect wrap-around neighbours
      return outside[slot];
    };
    for (int row = r0; row < r1; ++row)
      for (int col = c0; col < c1; ++col) {
        PixelTaps& out = px[size_t(row) * W + col];
        if (tile_rig.cameras.empty()) continue;
        const Node& u = node(col, row, 0);
        const std::vector<pano::Contributor>& cs = u.cs;
        if (cs.empty()) continue;
        std::vector<double> mw;
        if (needs_nb) {  // = pano::method_weights, with the cached potentials
          std::array<pano::MrfNode, 4> nb;
          const auto nbs = pano::grid_neighbours(opt.grid, col, row);
          for (int k = 0; k < 4; ++k)
            if (nbs[k][0] >= 0) {
              const Node& v = node(nbs[k][0], nbs[k][1], k);
              nb[k] = {&v.cs, &v.phi};
            }
          mw = pano::mrf_posterior(cs, u.phi, nb);
        } else {
          mw = pano::method_weights(tile_rig, opt.method, cs, {nullptr, nullptr, nullptr, nullptr}, opt.params);
        }
        std::vector<pano::Tap> taps;
        for (size_t i = 0; i < cs.size(); ++i)
          if (mw[i] > 0) taps.push_back({cs[i].camera, cs[i].px, mw[i]});
        if (taps.size() > 8) {  // keep the 8 strongest (never happens with real rigs)
          std::partial_sort(taps.begin(), taps.begin() + 8, taps.end(),
                            [](auto& a, auto& b) { return a.weight > b.weight; });
          taps.resize(8);
        }
        double total = 0;
        for (const auto& t : taps) total += t.weight;
        if (prune && total > 0) {  // drop the faint taps (MapOptions::min_weight), never the strongest
          const double strongest =
              std::max_element(taps.begin(), taps.end(), [](auto& a, auto& b) { return a.weight < b.weight; })->weight;
          std::erase_if(taps, [&](const pano::Tap& t) {
            return t.weight < opt.min_weight * total && t.weight < strongest;
          });
        }
        const int n = static_cast<int>(taps.size());
        double sum = 0;
        for (int k = 0; k < n; ++k) sum += (w[k] = taps[k].weight);
        if (sum <= 0) continue;
        for (int k = 0; k < n; ++k) w[k] /= sum;
        quantise_weights(w, n, q);
        for (int k = 0; k < n; ++k) {
          if (q[k] == 0) continue;
          const int cam = tile_to_full[taps[k].camera];
          const int cw = L.size[cam].width, ch = L.size[cam].height;
          // Bilinear neighbourhood with replicated edges (centres at integer + 0.5).
          auto axis = [](double p, int n, int& i0, int& f) {
            const double s = p - 0.5;
            double fl = std::floor(s);
            i0 = static_cast<int>(fl);
            f = static_cast<int>((s - fl) * 32 + 0.5);
            if (f == 32) { ++i0; f = 0; }
            if (i0 < 0) { i0 = 0; f = 0; }
            if (i0 >= n - 1) { i0 = n - 1; f = 0; }
          };
          int x0, fx, y0, fy;
          axis(taps[k].px.x(), cw, x0, fx);
          axis(taps[k].px.y(), ch, y0, fy);
          const uint32_t index = uint32_t(L.row0[cam] + y0) * uint32_t(L.stride_px) + uint32_t(x0);
          out.word[out.n] = index | (uint32_t(fx) << 22) | (uint32_t(fy) << 27);
          out.weight[out.n] = static_cast<uint8_t>(q[k] - 1);
          ++out.n;
        }
      }
  });
  map.count.resize(px.size());
  map.row_start.resize(H + 1);
  size_t total = 0;
  for (int row = 0; row < H; ++row) {
    map.row_start[row] = static_cast<uint32_t>(total);
    for (int col = 0; col < W; ++col) total += px[size_t(row) * W + col].n;
  }
  map.row_start[H] = static_cast<uint32_t>(total);
  map.word.resize(total);
  map.weight.resize(total);
  tbb::parallel_for(0, H, [&](int row) {
    size_t k = map.row_start[row];
    for (int col = 0; col < W; ++col) {
      const PixelTaps& p = px[size_t(row) * W + col];
      map.count[size_t(row) * W + col] = p.n;
      for (int t = 0; t < p.n; ++t, ++k) {
        map.word[k] = p.word[t];
        map.weight[k] = p.weight[t];
      }
    }
  });
  return map;
}

std::string map_key(const Rig& rig, const MapOptions& opt) {
  nlohmann::json j;
  j["rig"] = rig_to_json(rig);
  j["projection"] = to_string(opt.grid.projection);
  j["size"] = {opt.grid.width, opt.grid.height};
  j["method"] = pano::to_string(opt.method);
  j["q"] = {opt.params.search.q.x(), opt.params.search.q.y(), opt.params.search.q.z()};
  j["min_r"] = opt.params.search.min_r_mm;
  j["sigma"] = opt.params.gaussian_sigma_rel;
  j["sad_eps"] = opt.params.sad_epsilon;
  if (opt.min_weight > 0) j["min_weight"] = opt.min_weight;
  std::string active;
  for (bool a : opt.active) active += a ? '1' : '0';
  j["active"] = active;
  j["format"] = kFormatVersion;
  char buf[32];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(fnv1a(j.dump())));
  return buf;
}

namespace {
template <class T>
void put(std::ostream& o, const T& v) { o.write(reinterpret_cast<const char*>(&v), sizeof v); }
template <class T>
void put_vec(std::ostream& o, const std::vector<T>& v) {
  put<uint64_t>(o, v.size());
  o.write(reinterpret_cast<const char*>(v.data()), std::streamsize(v.size() * sizeof(T)));
}
template <class T>
bool get(std::istream& i, T& v) { return bool(i.read(reinterpret_cast<char*>(&v), sizeof v)); }
template <class T>
bool get_vec(std::istream& i, std::vector<T>& v, uint64_t limit) {
  uint64_t n = 0;
  if (!get(i, n) || n > limit) return false;
  v.resize(n);
  return bool(i.read(reinterpret_cast<char*>(v.data()), std::streamsize(n * sizeof(T))));
}
}  // namespace

void save_map(const CompiledMap& map, const std::filesystem::path& path) {
  write_atomically(path, [&](const std::filesystem::path& tmp) {
    std::ofstream o(tmp, std::ios::binary);
    if (!o) throw IoError("cannot write map file " + tmp.string());
    put(o, kMagic);
    put(o, kFormatVersion);
    put<int32_t>(o, map.width);
    put<int32_t>(o, map.height);
    put<int32_t>(o, static_cast<int32_t>(map.method));
    put<float>(o, map.sad_epsilon);
    put<int32_t>(o, map.layout.stride_px);
    put<int32_t>(o, map.layout.rows);
    put<int32_t>(o, static_cast<int32_t>(map.layout.row0.size()));
    for (size_t c = 0; c < map.layout.row0.size(); ++c) {
      put<int32_t>(o, map.layout.row0[c]);
      put<int32_t>(o, map.layout.size[c].width);
      put<int32_t>(o, map.layout.size[c].height);
    }
    put_vec(o, map.count);
    put_vec(o, map.row_start);
    put_vec(o, map.word);
    put_vec(o, map.weight);
    put(o, kMagic);
    o.flush();
    if (!o) throw IoError("cannot write map file " + tmp.string());
  });
}

std::optional<CompiledMap> load_map(const std::filesystem::path& path) {
  std::ifstream i(path, std::ios::binary);
  if (!i) return std::nullopt;
  uint32_t magic = 0, version = 0;
  if (!get(i, magic) || magic != kMagic || !get(i, version) || version != kFormatVersion) return std::nullopt;
  CompiledMap m;
  int32_t n = 0, method = 0;
  if (!get(i, m.width) || !get(i, m.height) || !get(i, method) || !get(i, m.sad_epsilon) || !get(i, m.layout.stride_px) || !get(i, m.layout.rows) ||
      !get(i, n) || n < 0 || n > 4096 || m.width <= 0 || m.height <= 0)
    return std::nullopt;
  m.method = static_cast<pano::Method>(method);
  for (int c = 0; c < n; ++c) {
    int32_t r0, w, h;
    if (!get(i, r0) || !get(i, w) || !get(i, h)) return std::nullopt;
    m.layout.row0.push_back(r0);
    m.layout.size.emplace_back(w, h);
  }
  const uint64_t px = uint64_t(m.width) * m.height;
  if (!get_vec(i, m.count, px) || m.count.size() != px) return std::nullopt;
  if (!get_vec(i, m.row_start, uint64_t(m.height) + 1) || m.row_start.size() != size_t(m.height) + 1)
    return std::nullopt;
  if (!get_vec(i, m.word, px * 8) || !get_vec(i, m.weight, px * 8)) return std::nullopt;
  if (m.word.size() != m.weight.size() || m.row_start.back() != m.word.size()) return std::nullopt;
  if (!get(i, magic) || magic != kMagic) return std::nullopt;
  return m;
}

std::filesystem::path default_cache_dir() {
  if (const char* d = std::getenv("OMMA_CACHE_DIR"); d && *d) return d;
  if (const char* d = std::getenv("XDG_CACHE_HOME"); d && *d) return std::filesystem::path(d) / "omma";
  if (const char* d = std::getenv("HOME"); d && *d) return std::filesystem::path(d) / ".cache" / "omma";
  return "/tmp/omma-cache";
}

MapLoad compile_map_cached(const Rig& rig, const MapOptions& opt, const std::filesystem::path& cache_dir) {
  const auto t0 = std::chrono::steady_clock::now();
  MapLoad out;
  if (!cache_dir.empty()) {
    out.file = cache_dir / ("omma-map-" + map_key(rig, opt) + ".bin");
    if (auto m = load_map(out.file)) {
      out.map = std::move(*m);
      out.from_cache = true;
    }
  }
  if (!out.from_cache) {
    out.map = compile_map(rig, opt);
    if (!cache_dir.empty()) {
      try {
        std::filesystem::create_directories(cache_dir);
        save_map(out.map, out.file);
      } catch (const std::exception& e) {
        spdlog::warn("map cache not written ({})", e.what());
      }
    }
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace omma::engine
