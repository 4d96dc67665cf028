// Compiled-map files are untrusted input: a damaged cache file is refused
// and recompiled, never rendered from.
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include <gtest/gtest.h>

#include "omma/core/checksum.h"
#include "omma/core/io.h"
#include "omma/render/compiled_map.h"
#include "omma/render/render.h"
#include "omma/testing/synthetic.h"

namespace omma::render {
namespace {

struct Fixture {
  Rig rig = testing::test_rig_24();
  MapOptions opt;
  CompiledMap map;
  std::vector<uint8_t> file;
  std::vector<cv::Mat> frames;
  cv::Mat want;
  explicit Fixture(int size = 128) {
    opt.grid = PanoGrid{Projection::kVr180, size, size};
    opt.method = pano::Method::kMrf;
    map = compile_map(rig, opt);
    file = map_file_bytes(map, map_key(rig, opt));
    frames = testing::random_frames(rig, 3);
    want = render_of(map);
  }
  cv::Mat render_of(const CompiledMap& m) const {
    FrameStore store(m.layout);
    for (size_t c = 0; c < frames.size(); ++c) store.set(int(c), frames[c]);
    cv::Mat out;
    render(m, store, out, RenderOptions{.threads = 1});
    return out;
  }
  static void fix_checksum(std::vector<uint8_t>& b) {
    const uint32_t crc = crc32(b.data(), b.size() - 4);
    std::memcpy(b.data() + b.size() - 4, &crc, 4);
  }
  size_t header_bytes() const { return 8 + kMapKeyBytes + 7 * 4 + 12 * rig.cameras.size(); }
};

bool same(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && cv::norm(a, b, cv::NORM_INF) == 0;
}

TEST(MapFile, RoundTripIsExact) {
  const Fixture f;
  std::string why;
  const auto back = parse_map_for(f.file.data(), f.file.size(), f.rig, f.opt, &why);
  ASSERT_TRUE(back.has_value()) << why;
  EXPECT_EQ(back->runs, f.map.runs);
  EXPECT_EQ(back->weight, f.map.weight);
  EXPECT_EQ(back->delta, f.map.delta);
  EXPECT_TRUE(same(f.render_of(*back), f.want));
  // Written for other options: the key and the header say so.
  MapOptions other = f.opt;
  other.method = pano::Method::kLinear;
  EXPECT_FALSE(parse_map_for(f.file.data(), f.file.size(), f.rig, other).has_value());
}

// A map written before the grids were the world the right way round (format 5, core/conventions.h
// kGridConvention 1) maps the mirrored panorama: it is refused with a message that names the
// version, even when its checksum is intact, and never rendered from.
TEST(MapFile, AMapOfTheMirroredGridsIsRefused) {
  const Fixture f;
  std::vector<uint8_t> old = f.file;
  const uint32_t v5 = 5;
  std::memcpy(old.data() + 4, &v5, 4);  // u32 magic, u32 version (compiled_map.h)
  Fixture::fix_checksum(old);
  std::string why;
  EXPECT_FALSE(parse_map_for(old.data(), old.size(), f.rig, f.opt, &why).has_value());
  EXPECT_NE(why.find("version 5"), std::string::npos) << why;
  EXPECT_EQ(kMapFormatVersion, 6u);
  EXPECT_EQ(kGridConvention, 2);
}

// Every bit of the header and 2000 random bits elsewhere, and 40 random 4 KiB blocks: the CRC-32
// refuses each. The same header flips with the checksum made to match again (as if the damage had
// been written by a program): the header checks against the rig refuse each of them too.
TEST(MapFile, BitFlipSweepIsRefused) {
  const Fixture f(64);
  std::mt19937 rng(21);
  std::vector<size_t> bits;
  for (size_t b = 0; b < 8 * f.header_bytes(); ++b) bits.push_back(b);
  for (int i = 0; i < 2000; ++i) bits.push_back(rng() % (8 * f.file.size()));
  int refused = 0, refused_fixed = 0, header_flips = 0;
  for (size_t bit : bits) {
    std::vector<uint8_t> b = f.file;
    b[bit / 8] ^= uint8_t(1u << (bit % 8));
    refused += !parse_map_for(b.data(), b.size(), f.rig, f.opt).has_value();
    if (bit < 8 * f.header_bytes()) {
      ++header_flips;
      Fixture::fix_checksum(b);
      refused_fixed += !parse_map_for(b.data(), b.size(), f.rig, f.opt).has_value();
    }
  }
  EXPECT_EQ(refused, int(bits.size()));
  EXPECT_EQ(refused_fixed, header_flips);
  for (int i = 0; i < 40; ++i) {
    std::vector<uint8_t> b = f.file;
    const size_t at = rng() % (b.size() - 4096);
    for (size_t k = 0; k < 4096; ++k) b[at + k] = uint8_t(rng());
    EXPECT_FALSE(parse_map_for(b.data(), b.size(), f.rig, f.opt).has_value()) << "block at " << at;
  }
  // The adversarial run's crash: ff ff ff ff over each 4-byte header word (checksum fixed).
  for (size_t at = 0; at + 4 <= f.header_bytes(); at += 4) {
    std::vector<uint8_t> b = f.file;
    std::memset(b.data() + at, 0xff, 4);
    Fixture::fix_checksum(b);
    EXPECT_FALSE(parse_map_for(b.data(), b.size(), f.rig, f.opt).has_value()) << "word at " << at;
  }
}

// Without the checksum (fixed after each flip), the structural checks alone (CompiledMap::IsValid)
// keep every accepted map safe to render: every tap inside the store, weights summing to 128. Run
// under the sanitizers (scripts/test.sh), an out-of-bounds read would fail here.
TEST(MapFile, StructuralChecksKeepDamagedMapsSafeToRender) {
  const Fixture f;
  std::mt19937 rng(5);
  int accepted = 0, tries = 150;
  for (int i = 0; i < tries; ++i) {
    std::vector<uint8_t> b = f.file;
    const size_t bit = 8 * f.header_bytes() + rng() % (8 * (b.size() - 8 - f.header_bytes()));
    b[bit / 8] ^= uint8_t(1u << (bit % 8));
    Fixture::fix_checksum(b);
    if (const auto m = parse_map_for(b.data(), b.size(), f.rig, f.opt)) {
      ++accepted;
      ASSERT_TRUE(m->IsValid());
      const cv::Mat out = f.render_of(*m);  // must not crash or read outside the store
      EXPECT_EQ(out.size(), f.want.size());
    }
  }
  std::printf("  %d of %d body bit flips pass the structural checks alone (the CRC refuses them)\n", accepted,
              tries);
}

// Through the cache, as `omma run` uses it: a damaged file is reported, recompiled and replaced.
TEST(MapFile, DamagedCacheFileIsRecompiledAndReplaced) {
  const Fixture f;
  const auto dir = std::filesystem::temp_directory_path() / "omma_map_file_test";
  std::filesystem::remove_all(dir);
  const MapLoad first = compile_map_cached(f.rig, f.opt, dir);
  ASSERT_FALSE(first.from_cache);
  const std::vector<uint8_t> good = read_file(first.file, kMaxDataFileBytes);
  auto damage = [&](size_t at, size_t n, uint8_t v) {
    std::vector<uint8_t> b = good;
    b.resize(std::max(b.size(), at + n));
    std::memset(b.data() + at, v, n);
    std::ofstream(first.file, std::ios::binary)
        .write(reinterpret_cast<const char*>(b.data()), std::streamsize(b.size()));
  };
  for (auto [at, n, v] : {std::tuple<size_t, size_t, uint8_t>{36, 4, 0xff},
                          {48, 4, 0xff},
                          {1000, 4096, 0x5a},
                          {good.size() - 3, 1, 0},
                          {good.size(), 100, 0}}) {
    damage(at, n, v);
    const MapLoad again = compile_map_cached(f.rig, f.opt, dir);
    EXPECT_FALSE(again.from_cache) << at;
    EXPECT_TRUE(same(f.render_of(again.map), f.want)) << at;
    EXPECT_TRUE(compile_map_cached(f.rig, f.opt, dir).from_cache) << "not replaced, " << at;
  }
  std::filesystem::resize_file(first.file, good.size() / 2);
  EXPECT_FALSE(compile_map_cached(f.rig, f.opt, dir).from_cache);
  std::filesystem::remove_all(dir);
}

// The cache is used only where no one but the user could have planted a map (compiled_map.h: the
// trust model): a folder or file others may write is passed over, with the same result.
TEST(MapFile, CacheOthersCanWriteIsNotUsed) {
  namespace fs = std::filesystem;
  const Fixture f;
  const auto dir = fs::temp_directory_path() / "omma_map_cache_trust_test";
  fs::remove_all(dir);
  const MapLoad first = compile_map_cached(f.rig, f.opt, dir);  // creates the folder, mode 0700
  EXPECT_EQ(fs::status(dir).permissions() & fs::perms::all, fs::perms::owner_all);
  EXPECT_EQ(fs::status(first.file).permissions() & fs::perms::all,
            fs::perms::owner_read | fs::perms::owner_write);
  EXPECT_TRUE(compile_map_cached(f.rig, f.opt, dir).from_cache);
  EXPECT_EQ(cache_dir_problem(dir), "");
  // A folder anyone may write, like a shared /tmp/omma-cache: not used, the map compiled.
  fs::permissions(dir, fs::perms::all);
  EXPECT_NE(cache_dir_problem(dir).find("may be written by others"), std::string::npos)
      << cache_dir_problem(dir);
  const MapLoad shared = compile_map_cached(f.rig, f.opt, dir);
  EXPECT_FALSE(shared.from_cache);
  EXPECT_TRUE(same(f.render_of(shared.map), f.want));
  fs::permissions(dir, fs::perms::owner_all);
  // A map file others may write, or a link in place of one: not used.
  fs::permissions(first.file, fs::perms::group_write, fs::perm_options::add);
  EXPECT_FALSE(compile_map_cached(f.rig, f.opt, dir).from_cache);  // ... and replaced by a private one
  EXPECT_TRUE(compile_map_cached(f.rig, f.opt, dir).from_cache);
  const fs::path elsewhere = dir.string() + "_planted.bin";
  fs::copy_file(first.file, elsewhere, fs::copy_options::overwrite_existing);
  fs::remove(first.file);
  fs::create_symlink(elsewhere, first.file);
  EXPECT_FALSE(compile_map_cached(f.rig, f.opt, dir).from_cache);
  // A link to a folder of someone else's, or a file in place of the folder.
  if (::getuid() == 0) {
    const fs::path other = dir.string() + "_other";
    fs::create_directories(other);
    ASSERT_EQ(::chown(other.c_str(), 65534, 65534), 0);
    EXPECT_NE(cache_dir_problem(other).find("belongs to user 65534"), std::string::npos);
    fs::remove_all(other);
  }
  std::ofstream(dir.string() + "_file") << "x";
  EXPECT_NE(cache_dir_problem(dir.string() + "_file").find("not a folder"), std::string::npos);
  fs::remove(dir.string() + "_file");
  fs::remove(elsewhere);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace omma::render
