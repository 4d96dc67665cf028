// Compiled-map files (compiled_map.h): writing, and reading them back as untrusted input. Depends on
// omma_core only (the map loader's fuzz target, fuzz/map_fuzz.cc, builds it alone).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>

#include "omma/core/checksum.h"
#include "omma/core/io.h"
#include "omma/core/limits.h"
#include "omma/core/valid.h"
#include "omma/render/compiled_map.h"

namespace omma::render {
namespace {

constexpr uint32_t kMagic = 0x4d4d4f31;  // "1OMM"

// Writes into a byte buffer; the file is the buffer and its CRC-32.
struct Writer {
  std::vector<uint8_t> bytes;
  template <class T>
  void put(const T& v) {
    const auto* p = reinterpret_cast<const uint8_t*>(&v);
    bytes.insert(bytes.end(), p, p + sizeof v);
  }
  template <class T>
  void put_vec(const std::vector<T>& v) {
    put<uint64_t>(v.size());
    const auto* p = reinterpret_cast<const uint8_t*>(v.data());
    bytes.insert(bytes.end(), p, p + v.size() * sizeof(T));
  }
};

// Reads from [p, end): every read is checked against the bytes left, and an array's length against
// them before anything is allocated.
struct Reader {
  const uint8_t* p;
  const uint8_t* end;
  template <class T>
  bool get(T& v) {
    if (size_t(end - p) < sizeof v) return false;
    std::memcpy(&v, p, sizeof v);
    p += sizeof v;
    return true;
  }
  template <class T>
  bool get_vec(std::vector<T>& v) {
    uint64_t n = 0;
    if (!get(n) || n > size_t(end - p) / sizeof(T)) return false;
    v.resize(n);
    if (n) std::memcpy(v.data(), p, n * sizeof(T));
    p += n * sizeof(T);
    return true;
  }
};

}  // namespace

bool StoreLayout::IsValid(std::string* why) const {
  const size_t n = row0.size();
  if (n == 0 || n > size_t(kMaxCameras) || size.size() != n)
    return invalid(why, "bad camera count in the store layout");
  int64_t next = 0, widest = 0;
  for (size_t c = 0; c < n; ++c) {
    if (size[c].width < 1 || size[c].height < 1 || size[c].width > kMaxImageSide ||
        size[c].height > kMaxImageSide)
      return invalid(why, "camera " + std::to_string(c) + ": frame size out of range");
    if (row0[c] != next)
      return invalid(why,
                     "camera " + std::to_string(c) + ": first store row does not follow the previous camera");
    next += size[c].height;
    widest = std::max<int64_t>(widest, size[c].width);
  }
  if (rows != next || stride_px != widest)
    return invalid(why, "store rows or stride do not match the cameras");
  if (bytes() >= kMaxStoreBytes) return invalid(why, "frame store too large");
  return true;
}

bool CompiledMap::IsValid(std::string* why) const {
  // A whole panorama's map or one band of a larger one (as wide as the panorama, core/limits.h).
  if (width <= 0 || height <= 0 || int64_t(width) * height > kMaxImagePixels || width > kMaxBandedSide ||
      height > kMaxImageSide)
    return invalid(why, "map size out of range");
  if (method != pano::Method::kNearest && method != pano::Method::kLinear &&
      method != pano::Method::kGaussian && method != pano::Method::kMrf &&
      method != pano::Method::kMrfSpherical && method != pano::Method::kSad)
    return invalid(why, "unknown method");
  if (!(std::isfinite(sad_epsilon) && sad_epsilon > 0)) return invalid(why, "sad epsilon out of range");
  if (!layout.IsValid(why)) return false;
  const size_t nt = size_t(tiles());
  for (const auto* v : {&tile_run, &tile_tap, &tile_base, &tile_line})
    if (v->size() != nt + 1 || v->front() != 0 || !std::is_sorted(v->begin(), v->end()))
      return invalid(why, "bad tile index");
  if (tile_run.back() != runs.size() || tile_tap.back() != weight.size() || tile_base.back() != base.size() ||
      tile_line.back() != lines.size() || delta.size() != weight.size())
    return invalid(why, "tile index does not match the arrays");
  const bool sad = method == pano::Method::kSad;
  if (sad ? prior.size() != weight.size() : !prior.empty()) return invalid(why, "bad prior array");
  const size_t store = layout.bytes();
  for (uint32_t l : lines)
    if (l >= store) return invalid(why, "prefetch line outside the frame store");
  // Every run, pixel and tap: the renderers rely on these without checking (compiled_map.h).
  for (int t = 0; t < int(nt); ++t) {
    const int w = std::min(width, (t % tiles_x() + 1) * kTileW) - (t % tiles_x()) * kTileW;
    const int h = std::min(height, (t / tiles_x() + 1) * kTileH) - (t / tiles_x()) * kTileH;
    size_t r = tile_run[t], k = tile_tap[t], b = tile_base[t];
    for (int row = 0; row < h; ++row) {
      int cols = 0;
      for (;; r += 2) {
        if (r + 1 >= tile_run[t + 1]) return invalid(why, "runs overflow their tile");
        const int n = runs[r], len = runs[r + 1];
        if (len == 0) break;
        if (n > kMaxTaps || b + n > tile_base[t + 1] || k + size_t(n) * len > tile_tap[t + 1] ||
            cols + len > w)
          return invalid(why, "run overflows its tile");
        for (int p = 0; p < len; ++p) {
          int sum = 0, prior_sum = 0;
          for (int i = 0; i < n; ++i, ++k) {
            const int64_t off = int64_t(base[b + i]) + delta[k];
            if (off < 0 || size_t(off) * 2 + 16 > store) return invalid(why, "tap outside the frame store");
            const uint32_t wk = weight[k];
            int tap = 0;
            for (int j = 0; j < 4; ++j) {
              const int wj = int(wk >> (8 * j) & 0xFF);
              if (wj > 127) return invalid(why, "weight above 127");
              tap += wj;
            }
            if (sad) {
              if (tap != 128) return invalid(why, "sad tap weights do not sum to 128");
              prior_sum += prior[k] + 1;
            }
            sum += tap;
          }
          // The output is sum(w v) / 128: the weights of a pixel sum to exactly 128 (the AVX2
          // kernel's 16-bit sums are exact only then); sad's priors to 256.
          if (n > 0 && (sad ? prior_sum != 256 : sum != 128))
            return invalid(why, "pixel weights do not sum to 128");
        }
        b += n;
        cols += len;
      }
      r += 2;
      if (cols != w) return invalid(why, "tile row of the wrong width");
    }
    if (r != tile_run[t + 1] || k != tile_tap[t + 1] || b != tile_base[t + 1])
      return invalid(why, "tile of the wrong size");
  }
  return true;
}

std::vector<uint8_t> map_file_bytes(const CompiledMap& map, const std::string& key) {
  Writer o;
  o.put(kMagic);
  o.put(kMapFormatVersion);
  char k[kMapKeyBytes] = {};
  std::memcpy(k, key.data(), std::min(key.size(), sizeof k));
  o.put(k);
  o.put<int32_t>(map.width);
  o.put<int32_t>(map.height);
  o.put<int32_t>(static_cast<int32_t>(map.method));
  o.put<float>(map.sad_epsilon);
  o.put<int32_t>(map.layout.stride_px);
  o.put<int32_t>(map.layout.rows);
  o.put<int32_t>(static_cast<int32_t>(map.layout.row0.size()));
  for (size_t c = 0; c < map.layout.row0.size(); ++c) {
    o.put<int32_t>(map.layout.row0[c]);
    o.put<int32_t>(map.layout.size[c].width);
    o.put<int32_t>(map.layout.size[c].height);
  }
  o.put_vec(map.tile_run);
  o.put_vec(map.tile_tap);
  o.put_vec(map.tile_base);
  o.put_vec(map.tile_line);
  o.put_vec(map.runs);
  o.put_vec(map.base);
  o.put_vec(map.delta);
  o.put_vec(map.weight);
  o.put_vec(map.prior);
  o.put_vec(map.lines);
  o.put(kMagic);
  o.put(crc32(o.bytes.data(), o.bytes.size()));
  return std::move(o.bytes);
}

void save_map(const CompiledMap& map, const std::filesystem::path& path, const std::string& key) {
  const std::vector<uint8_t> bytes = map_file_bytes(map, key);
  write_atomically(path, [&](const std::filesystem::path& tmp) {
    std::ofstream o(tmp, std::ios::binary);
    if (!o) throw IoError("cannot write map file " + tmp.string());
    o.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    o.flush();
    if (!o) throw IoError("cannot write map file " + tmp.string());
  });
}

std::optional<CompiledMap> parse_map(const uint8_t* data, size_t n, std::string* key, std::string* why) {
  auto fail = [&](const std::string& m) -> std::optional<CompiledMap> {
    if (why) *why = m;
    return std::nullopt;
  };
  uint32_t magic = 0, version = 0, crc = 0;
  Reader all{data, data + n};
  if (!all.get(magic) || magic != kMagic) return fail("not an omma map file");
  if (!all.get(version) || version != kMapFormatVersion)
    return fail("map format version " + std::to_string(version) + ", not " +
                std::to_string(kMapFormatVersion));
  // The checksum covers everything before it: header, arrays and the closing magic.
  std::memcpy(&crc, data + n - 4, 4);  // n >= 8 here
  if (crc32(data, n - 4) != crc) return fail("checksum mismatch (damaged file)");
  Reader i{all.p, data + n - 4};
  CompiledMap m;
  char k[kMapKeyBytes];
  int32_t cameras = 0, method = 0;
  if (!i.get(k) || !i.get(m.width) || !i.get(m.height) || !i.get(method) || !i.get(m.sad_epsilon) ||
      !i.get(m.layout.stride_px) || !i.get(m.layout.rows) || !i.get(cameras))
    return fail("truncated header");
  if (key) key->assign(k, strnlen(k, sizeof k));
  if (cameras < 1 || cameras > kMaxCameras) return fail("camera count out of range");
  if (method < 0 || method > 255) return fail("unknown method");
  m.method = static_cast<pano::Method>(method);
  for (int c = 0; c < cameras; ++c) {
    int32_t r0, w, h;
    if (!i.get(r0) || !i.get(w) || !i.get(h)) return fail("truncated camera table");
    m.layout.row0.push_back(r0);
    m.layout.size.emplace_back(w, h);
  }
  if (!i.get_vec(m.tile_run) || !i.get_vec(m.tile_tap) || !i.get_vec(m.tile_base) ||
      !i.get_vec(m.tile_line) || !i.get_vec(m.runs) || !i.get_vec(m.base) || !i.get_vec(m.delta) ||
      !i.get_vec(m.weight) || !i.get_vec(m.prior) || !i.get_vec(m.lines))
    return fail("truncated arrays");
  if (!i.get(magic) || magic != kMagic || i.p != i.end) return fail("bad end of file");
  if (std::string w; !m.IsValid(&w)) return fail(w);
  return m;
}

}  // namespace omma::render
