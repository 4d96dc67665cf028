// `omma render` of a recording under `mpirun -np 3`: the frame sets spread over the
// ranks give the same bytes as one process, a rerun makes only what is missing, one panorama split
// by bands (--split tiles) gives the same bytes too, and bad input (a recording one rank cannot
// read, more ranks than frame sets) gives one clear error. Few tests, several checks each: every
// mpirun costs a second or two of start-up.
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "omma/design/prototype.h"
#include "omma/io/recording.h"
#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {
namespace fs = std::filesystem;
using json = nlohmann::json;

const std::string kMpirun = std::string(OMMA_MPIEXEC) + " --allow-run-as-root --oversubscribe";
constexpr int kSets = 6;

// A recording of 12 Giga-Eye cameras (skip-5 mode, 432 x 324) and kSets frame sets of smooth
// 12-bit patterns that differ per camera and set.
class RenderMpi : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(temp_dir("render-mpi"));
    Rig rig = *design::builtin_rig("gigaeye-44-skip5");
    rig.cameras.resize(12);
    io::RecordingManifest m;
    m.rig = rig;
    m.fps = 10;
    io::RecordingWriter w(rec(), m);
    for (int s = 0; s < kSets; ++s)
      for (int c = 0; c < 12; ++c) {
        cv::Mat raw(rig.cameras[c].in.height, rig.cameras[c].in.width, CV_16UC1);
        for (int y = 0; y < raw.rows; ++y)
          for (int x = 0; x < raw.cols; ++x)
            raw.at<uint16_t>(y, x) = static_cast<uint16_t>(
                2048 + 1500 * std::sin(x / 17.0 + c + 0.7 * s) * std::cos(y / (11.0 + s)) +
                300 * ((x + y) % 2));
        w.append(c, raw, s, s * 100'000'000LL + c * 1000);
      }
    w.close();
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
  }
  static fs::path rec() { return *dir_ / "rec"; }
  static fs::path ref() { return *dir_ / "ref"; }
  static std::string render_args(const fs::path& out, const std::string& extra = "") {
    return fmt::format(
        "render {} --size 360x120 --band-rows 16 --method linear --no-cache --out {}/p_{{set}}.tif {}",
        rec().string(), out.string(), extra);
  }
  static std::string mpi_render(int np, const fs::path& out, const std::string& extra = "") {
    return fmt::format("{} -np {} {} {}", kMpirun, np, OMMA_BINARY, render_args(out, extra));
  }
  static fs::path* dir_;
};
fs::path* RenderMpi::dir_ = nullptr;

TEST_F(RenderMpi, ThreeRanksGiveTheBytesOfOneProcessByFrameSetsOrByBands) {
  // The single-process render.
  const RunResult one = run_omma(render_args(ref()), 120);
  ASSERT_EQ(one.exit_code, 0) << one.err;

  const fs::path out = *dir_ / "sets";
  const RunResult r = run_command(mpi_render(3, out, "--json"), 120);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = r.json();
  EXPECT_EQ(j["panoramas"], kSets);
  EXPECT_EQ(j["distributed"]["ranks"], 3);
  for (int s = 0; s < kSets; ++s) {
    const std::string name = fmt::format("p_{:05d}.tif", s);
    const std::string a = slurp(ref() / name), b = slurp(out / name);
    EXPECT_GT(a.size(), 360u * 120 * 3);
    EXPECT_TRUE(a == b) << name << " differs from the single-process render";
  }
  // The sets differ (the test could not pass by rendering one set everywhere).
  EXPECT_NE(slurp(ref() / "p_00000.tif"), slurp(ref() / "p_00001.tif"));
  const json m = json::parse(slurp(out / "render-manifest.json"));
  ASSERT_EQ(m["outputs"].size(), size_t(kSets));
  std::set<int> ranks;
  for (const auto& o : m["outputs"]) {
    ranks.insert(o["rank"].get<int>());
    EXPECT_GT(o["read"].get<double>(), 0);
    EXPECT_GT(o["develop"].get<double>(), 0);
    EXPECT_GT(o["render"].get<double>(), 0);
    EXPECT_GE(o["seconds"].get<double>(),
              o["read"].get<double>() + o["develop"].get<double>() + o["render"].get<double>());
  }
  EXPECT_GE(ranks.size(), 2u);

  // A lost output and a damaged one: the rerun (2 ranks) makes exactly those two.
  fs::remove(out / "p_00002.tif");
  {
    std::string s = slurp(out / "p_00004.tif");
    s[s.size() / 2] ^= 0x40;
    std::ofstream(out / "p_00004.tif", std::ios::binary) << s;
  }
  const RunResult again = run_command(mpi_render(2, out, "--json"), 120);
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_EQ(again.json()["panoramas"], 2);
  EXPECT_EQ(again.json()["reused"], kSets - 2);
  for (int s : {2, 4}) {
    const std::string name = fmt::format("p_{:05d}.tif", s);
    EXPECT_TRUE(slurp(ref() / name) == slurp(out / name)) << name;
  }

  // One panorama split by bands over the ranks (--split tiles).
  const fs::path tiles = *dir_ / "tiles";
  fs::create_directories(tiles);
  const RunResult t =
      run_command(fmt::format("{} -np 3 {} render {} --sets 3 --size 360x120 --band-rows 16 --method linear "
                              "--no-cache --split tiles "
                              "--out {} --json",
                              kMpirun, OMMA_BINARY, rec().string(), (tiles / "one.tif").string()),
                  120);
  ASSERT_EQ(t.exit_code, 0) << t.err;
  EXPECT_TRUE(slurp(ref() / "p_00003.tif") == slurp(tiles / "one.tif"));
  const json d = t.json()["distributed"];
  EXPECT_EQ(d["split"], "tiles");
  EXPECT_EQ(d["bands"], 8);  // 120 rows / 16
  int bands = 0;
  for (const auto& n : d["bands_per_rank"]) bands += n.get<int>();
  EXPECT_EQ(bands, 8);
  EXPECT_LE(d["max_bands_held"].get<int>(), 6);  // the window: 2 x ranks, never the whole image
  std::set<std::string> left;
  for (const auto& e : fs::directory_iterator(tiles)) left.insert(e.path().filename().string());
  EXPECT_EQ(left, std::set<std::string>{"one.tif"});
}

TEST_F(RenderMpi, BadInputGivesOneClearErrorAndNoOutput) {
  const fs::path out = *dir_ / "bad";
  // Rank 2 gets a recording path it cannot read (as on a node without the mount).
  const RunResult r = run_command(
      fmt::format("{} -np 2 {} {} : -np 1 {} {}", kMpirun, OMMA_BINARY, render_args(out), OMMA_BINARY,
                  fmt::format("render {}/not-mounted --size 360x120 --no-cache --out {}/p_{{set}}.tif",
                              dir_->string(), out.string())),
      120);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(count(r.err, "omma: error:"), 1) << r.err;
  EXPECT_NE(r.err.find("rank 2"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("not-mounted"), std::string::npos) << r.err;
  EXPECT_TRUE(!fs::exists(out) || fs::is_empty(out));

  // More ranks than frame sets.
  const RunResult few = run_command(mpi_render(3, out, "--sets 0:2"), 120);
  EXPECT_EQ(few.exit_code, 1) << few.err;
  EXPECT_EQ(count(few.err, "omma: error:"), 1) << few.err;
  EXPECT_NE(few.err.find("3 ranks for 2 frame sets"), std::string::npos) << few.err;
  EXPECT_TRUE(!fs::exists(out) || fs::is_empty(out));
  // (An output folder no rank can write: the runner's check, tested with the test job in
  // dist_mpi_test.cc.)
}

}  // namespace
}  // namespace omma::test
