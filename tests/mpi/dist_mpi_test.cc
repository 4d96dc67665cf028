// The distribution layer under `mpirun -np 3` on localhost, with a test job (dist_probe.cc):
// outputs byte-identical to one process, dynamic scheduling over every rank, a killed rank and the
// resumed rerun, and bad input (one rank cannot read the input, unwritable output, more ranks than
// items, an item that fails): one clear error, no half-written output.
#include <sys/stat.h>

#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {
namespace fs = std::filesystem;
using json = nlohmann::json;

// As root, OpenMPI wants --allow-run-as-root; --oversubscribe: more ranks than the 2 cores.
const std::string kMpirun = std::string(OMMA_MPIEXEC) + " --allow-run-as-root --oversubscribe";

// item_NNNN.bin -> contents, and every other file name (temporaries, journals).
struct Folder {
  std::map<std::string, std::string> items;
  std::set<std::string> others;
};
Folder read_folder(const fs::path& dir) {
  Folder f;
  if (!fs::exists(dir)) return f;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("item_", 0) == 0)
      f.items[name] = slurp(e.path());
    else
      f.others.insert(name);
  }
  return f;
}

class DistMpi : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = temp_dir("dist-mpi");
    in_ = dir_ / "in";
    fs::create_directories(in_);
    for (int i = 0; i < 12; ++i) std::ofstream(in_ / fmt::format("in_{:04d}.txt", i)) << 1000 + 7 * i;
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string probe(const fs::path& out, const std::string& extra = "") const {
    return fmt::format("{} --input {} --out {} {}", OMMA_DIST_PROBE, in_.string(), out.string(), extra);
  }
  // The single-process reference (no mpirun).
  Folder reference(int items) {
    const fs::path ref = dir_ / "ref";
    const RunResult r = run_command(probe(ref, fmt::format("--items {}", items)), 60);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    Folder f = read_folder(ref);
    EXPECT_EQ(f.items.size(), size_t(items));
    return f;
  }
  fs::path dir_, in_;
};

TEST_F(DistMpi, ThreeRanksMakeByteIdenticalOutputsAndAManifest) {
  const Folder ref = reference(9);
  const fs::path out = dir_ / "mpi";
  const RunResult r = run_command(kMpirun + " -np 3 " + probe(out, "--items 9 --json"), 60);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Folder got = read_folder(out);
  ASSERT_EQ(got.items.size(), 9u);
  for (const auto& [name, bytes] : ref.items) EXPECT_TRUE(got.items.at(name) == bytes) << name;
  EXPECT_EQ(got.others, std::set<std::string>{"manifest.json"});  // no journal, no temporaries left

  const json m = json::parse(slurp(out / "manifest.json"));
  EXPECT_EQ(m["ranks"], 3);
  EXPECT_EQ(m["mpi"], true);
  EXPECT_EQ(m["made"], 9);
  EXPECT_EQ(m["reused"], 0);
  ASSERT_EQ(m["outputs"].size(), 9u);
  std::map<int, int> per_rank;
  for (size_t i = 0; i < 9; ++i) {
    const json& o = m["outputs"][i];
    EXPECT_EQ(o["item"], int(i));
    EXPECT_EQ(o["size"], 65536);
    EXPECT_GE(o["seconds"].get<double>(), o["render"].get<double>());
    EXPECT_GT(o["render"].get<double>(), 0.015);  // the item's wait, >= 20 ms
    ++per_rank[o["rank"].get<int>()];
  }
  // Dynamic scheduling: every rank (rank 0 works too) made some of the 9 items of 20-60 ms.
  EXPECT_EQ(per_rank.size(), 3u) << m.dump();
  // The checksum is the standard tool's (xxhsum -H3), when it is installed.
  const RunResult x = run_command("xxhsum -H3 " + (out / "item_0004.bin").string(), 20);
  if (x.exit_code == 0) {
    const std::string hex = m["outputs"][4]["checksum"].get<std::string>().substr(5);
    EXPECT_NE(x.out.find("= " + hex), std::string::npos) << x.out << " vs " << hex;
  }
}

TEST_F(DistMpi, AKilledRankFailsTheRunAndTheRerunRedoesOnlyTheRest) {
  const Folder ref = reference(12);
  const fs::path out = dir_ / "killed";
  // The first rank other than 0 that takes an item >= 7 writes half of it and dies (SIGKILL).
  const RunResult r1 = run_command(kMpirun + " -np 3 " + probe(out, "--items 12 --die-at 7"), 60);
  EXPECT_NE(r1.exit_code, 0);
  // mpirun names the dead process; rank 0 says where the finished items are and what to do.
  EXPECT_NE(r1.err.find("signal 9"), std::string::npos) << r1.err;
  EXPECT_NE(r1.err.find("run the same command again"), std::string::npos) << r1.err;
  const Folder after_kill = read_folder(out);
  int temporaries = 0;
  for (const auto& name : after_kill.others)
    temporaries += name.rfind(".item_", 0) == 0 && name.find(".tmp") != std::string::npos;
  EXPECT_GE(temporaries, 1) << "the dead rank's half-written item";
  for (const auto& [name, bytes] : after_kill.items)
    EXPECT_TRUE(bytes == ref.items.at(name)) << name << " half-written";
  EXPECT_FALSE(after_kill.others.count("manifest.json"));
  EXPECT_TRUE(after_kill.others.count("manifest.json.journal"));
  std::map<std::string, ino_t> inode;  // a reused output keeps its inode (a remade one is renamed onto it)
  for (const auto& [name, bytes] : after_kill.items) {
    struct stat st {};
    ASSERT_EQ(::stat((out / name).c_str(), &st), 0);
    inode[name] = st.st_ino;
  }

  // The rerun also checks the other scheduling mode: rank 0 only hands out items.
  const RunResult r2 = run_command(kMpirun + " -np 3 " + probe(out, "--items 12 --rank0 serves"), 60);
  ASSERT_EQ(r2.exit_code, 0) << r2.err;
  const Folder got = read_folder(out);
  EXPECT_TRUE(got.items == ref.items);
  EXPECT_EQ(got.others, std::set<std::string>{"manifest.json"});  // the half-written temporary is gone
  const json m = json::parse(slurp(out / "manifest.json"));
  EXPECT_EQ(m["rank0"], "serves");
  int reused = 0;
  for (const auto& o : m["outputs"]) {
    if (!o["reused"].get<bool>()) {
      EXPECT_NE(o["rank"], 0) << "rank 0 only serves";
    }
    const std::string name = fs::path(o["output"].get<std::string>()).filename().string();
    if (o["reused"].get<bool>()) {
      ++reused;
      struct stat st {};
      ASSERT_EQ(::stat((out / name).c_str(), &st), 0);
      EXPECT_EQ(st.st_ino, inode.at(name)) << name << " was made again";
    }
  }
  EXPECT_GE(reused, 4) << "items 0-6 were handed out before 7; most had finished";
  EXPECT_EQ(m["reused"], reused);
  EXPECT_EQ(m["made"], 12 - reused);
}

TEST_F(DistMpi, BadInputGivesOneClearErrorAndNoOutput) {
  const fs::path out = dir_ / "bad";
  // One rank cannot read the input (MPMD: ranks 0 and 1 get it, rank 2 a path it cannot read, as on
  // a node without the mount).
  const std::string unmounted = fmt::format("{} --input {} --out {} --items 6", OMMA_DIST_PROBE,
                                            (dir_ / "not-mounted").string(), out.string());
  RunResult r = run_command(kMpirun + " -np 2 " + probe(out, "--items 6") + " : -np 1 " + unmounted, 60);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(count(r.err, "omma: error:"), 1) << r.err;
  EXPECT_NE(r.err.find("rank 2"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("not-mounted"), std::string::npos) << r.err;
  Folder got = read_folder(out);
  EXPECT_TRUE(got.items.empty());
  EXPECT_TRUE(got.others.empty()) << *got.others.begin();

  // An output folder that cannot be created: a regular file where its parent should be
  // (permissions would not stop root, who runs CI).
  std::ofstream(dir_ / "file") << "x";
  r = run_command(kMpirun + " -np 3 " + probe(dir_ / "file" / "out", "--items 6"), 60);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(count(r.err, "omma: error:"), 1) << r.err;
  EXPECT_NE(r.err.find("output folder"), std::string::npos) << r.err;

  // (More ranks than items: render_mpi_test.cc, with the render's frame sets.)
}

TEST_F(DistMpi, AFailingItemStopsTheJobWithOneErrorAndTheRerunFinishes) {
  const Folder ref = reference(9);
  const fs::path out = dir_ / "fail";
  const RunResult r1 = run_command(kMpirun + " -np 3 " + probe(out, "--items 9 --fail-at 5"), 60);
  EXPECT_EQ(r1.exit_code, 1) << r1.err;
  EXPECT_EQ(count(r1.err, "omma: error:"), 1) << r1.err;
  EXPECT_NE(r1.err.find("probe item 5: input in_0005.txt is damaged"), std::string::npos) << r1.err;
  const Folder partial = read_folder(out);
  EXPECT_FALSE(partial.items.count("item_0005.bin"));
  for (const auto& [name, bytes] : partial.items) EXPECT_TRUE(bytes == ref.items.at(name)) << name;
  const RunResult r2 = run_command(kMpirun + " -np 3 " + probe(out, "--items 9 --json"), 60);
  ASSERT_EQ(r2.exit_code, 0) << r2.err;
  EXPECT_TRUE(read_folder(out).items == ref.items);
  const json m = r2.json();
  EXPECT_EQ(m["reused"].get<int>(), int(partial.items.size()));
  EXPECT_EQ(m["made"].get<int>(), 9 - int(partial.items.size()));
}

}  // namespace
}  // namespace omma::test
