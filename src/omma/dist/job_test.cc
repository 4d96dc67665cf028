// The distribution layer as one process (LocalComm): the same code path as under mpirun, whose
// tests are in tests/mpi/.
#include "omma/dist/job.h"

#include <fstream>
#include <map>
#include <random>
#include <sstream>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "omma/core/checksum.h"
#include "omma/core/io.h"

namespace omma::dist {
namespace {
namespace fs = std::filesystem;
using json = nlohmann::json;

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

fs::path fresh_dir(const std::string& tag) {
  std::random_device rd;
  const fs::path p = fs::temp_directory_path() / fmt::format("omma-dist-{}-{}", tag, rd());
  fs::create_directories(p);
  return p;
}

// Item i writes "item i of <salt>" repeated (i + 1) times; counts the items it made.
class TextJob : public Job {
 public:
  TextJob(fs::path dir, int64_t n, std::string salt = "a")
      : dir_(std::move(dir)), n_(n), salt_(std::move(salt)) {}
  int64_t items() const override { return n_; }
  fs::path output(int64_t i) const override { return dir_ / fmt::format("out_{:03d}.txt", i); }
  json parameters() const override { return {{"salt", salt_}}; }
  ItemTimes run(int64_t i) override {
    if (i == fail_at) throw std::runtime_error("bad frame");
    std::string s;
    for (int64_t k = 0; k <= i; ++k) s += fmt::format("item {} of {}\n", i, salt_);
    write_text_atomically(output(i), s);
    ++made[i];
    ItemTimes t;
    t.render = 0.001 * (i + 1);
    return t;
  }
  std::string expected(int64_t i) const {
    std::string s;
    for (int64_t k = 0; k <= i; ++k) s += fmt::format("item {} of {}\n", i, salt_);
    return s;
  }
  std::map<int64_t, int> made;
  int64_t fail_at = -1;

 private:
  fs::path dir_;
  int64_t n_;
  std::string salt_;
};

RunOptions options_for(const fs::path& dir) {
  RunOptions o;
  o.manifest = dir / "manifest.json";
  o.progress = false;
  return o;
}

TEST(Checksum, IsTheStandardXxh3) {
  // `printf 'hello\n' | xxhsum -H3` prints 99fc819aaba2462a (xxhash 0.8.1).
  EXPECT_EQ(xxh3_hex("hello\n", 6), "xxh3:99fc819aaba2462a");
  const fs::path dir = fresh_dir("sum");
  std::string big(3 << 20, '\0');  // larger than the 1 MiB read buffer
  for (size_t i = 0; i < big.size(); ++i) big[i] = static_cast<char>(i * 131 % 251);
  std::ofstream(dir / "big.bin", std::ios::binary) << big;
  const FileDigest d = file_digest(dir / "big.bin");
  EXPECT_EQ(d.size, big.size());
  EXPECT_EQ(d.checksum, xxh3_hex(big.data(), big.size()));
  EXPECT_THROW(file_digest(dir / "missing"), IoError);
  fs::remove_all(dir);
}

TEST(Job, OneProcessMakesEveryItemAndAManifest) {
  const fs::path dir = fresh_dir("one");
  TextJob job(dir, 5);
  LocalComm comm;
  const RunSummary s = run_job(comm, job, options_for(dir));
  EXPECT_EQ(s.items, 5);
  EXPECT_EQ(s.made, 5);
  EXPECT_EQ(s.reused, 0);
  EXPECT_FALSE(s.mpi);
  EXPECT_NEAR(s.totals.render, 0.015, 1e-12);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(slurp(job.output(i)), job.expected(i));
  const json m = json::parse(slurp(dir / "manifest.json"));
  EXPECT_EQ(m["format"], "omma-job-manifest");
  ASSERT_EQ(m["outputs"].size(), 5u);
  for (int i = 0; i < 5; ++i) {
    const json& o = m["outputs"][i];
    EXPECT_EQ(o["item"], i);
    EXPECT_EQ(o["size"], job.expected(i).size());
    EXPECT_EQ(o["checksum"], xxh3_hex(job.expected(i).data(), job.expected(i).size()));
    EXPECT_EQ(o["rank"], 0);
    EXPECT_FALSE(o["reused"].get<bool>());
  }
  EXPECT_FALSE(fs::exists(dir / "manifest.json.journal"));
  fs::remove_all(dir);
}

TEST(Job, ResumeReusesVerifiedOutputsAndRemakesDamagedOnes) {
  const fs::path dir = fresh_dir("resume");
  LocalComm comm;
  {
    TextJob job(dir, 6);
    run_job(comm, job, options_for(dir));
  }
  // Item 1: same size, one byte changed (only the checksum tells); item 3: truncated; item 4:
  // deleted; a temporary of item 5 left by a killed write; an unrelated file that looks similar.
  {
    std::string s = slurp(dir / "out_001.txt");
    s[2] ^= 1;
    std::ofstream(dir / "out_001.txt", std::ios::binary) << s;
  }
  fs::resize_file(dir / "out_003.txt", 3);
  fs::remove(dir / "out_004.txt");
  std::ofstream(dir / ".out_005.tmp123456.txt") << "half";
  std::ofstream(dir / ".out_005.tmpx.txt") << "not ours";
  TextJob job(dir, 6);
  const RunSummary s = run_job(comm, job, options_for(dir));
  EXPECT_EQ(job.made, (std::map<int64_t, int>{{1, 1}, {3, 1}, {4, 1}}));
  EXPECT_EQ(s.made, 3);
  EXPECT_EQ(s.reused, 3);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(slurp(job.output(i)), job.expected(i));
  EXPECT_FALSE(fs::exists(dir / ".out_005.tmp123456.txt"));
  EXPECT_TRUE(fs::exists(dir / ".out_005.tmpx.txt"));
  const json m = json::parse(slurp(dir / "manifest.json"));
  EXPECT_TRUE(m["outputs"][0]["reused"].get<bool>());
  EXPECT_FALSE(m["outputs"][1]["reused"].get<bool>());

  // Size-only verification would have kept the flipped byte: checksums matter.
  {
    std::string t = slurp(dir / "out_002.txt");
    t[0] ^= 1;
    std::ofstream(dir / "out_002.txt", std::ios::binary) << t;
  }
  TextJob sized(dir, 6);
  RunOptions o = options_for(dir);
  o.verify_checksums = false;
  EXPECT_EQ(run_job(comm, sized, o).made, 0);
  fs::remove_all(dir);
}

TEST(Job, OtherParametersOrNoResumeRemakeEverything) {
  const fs::path dir = fresh_dir("params");
  LocalComm comm;
  TextJob a(dir, 4, "a");
  run_job(comm, a, options_for(dir));
  TextJob b(dir, 4, "b");
  EXPECT_EQ(run_job(comm, b, options_for(dir)).made, 4);
  EXPECT_EQ(slurp(b.output(2)), b.expected(2));
  TextJob c(dir, 4, "b");
  RunOptions o = options_for(dir);
  o.resume = false;
  EXPECT_EQ(run_job(comm, c, o).made, 4);
  TextJob d(dir, 4, "b");
  EXPECT_EQ(run_job(comm, d, options_for(dir)).made, 0);
  fs::remove_all(dir);
}

TEST(Job, AFailingItemReportsItsNameAndKeepsTheFinishedOnesInTheJournal) {
  const fs::path dir = fresh_dir("fail");
  LocalComm comm;
  TextJob job(dir, 6);
  job.fail_at = 3;
  try {
    run_job(comm, job, options_for(dir));
    FAIL() << "no error";
  } catch (const JobError& e) {
    EXPECT_FALSE(e.quiet());
    const std::string w = e.what();
    EXPECT_NE(w.find("item 3: bad frame"), std::string::npos) << w;
    EXPECT_NE(w.find("3 of 6 items are finished"), std::string::npos) << w;
  }
  EXPECT_FALSE(fs::exists(dir / "manifest.json"));
  EXPECT_TRUE(fs::exists(dir / "manifest.json.journal"));
  EXPECT_FALSE(fs::exists(job.output(4)));  // not started after the failure
  TextJob again(dir, 6);
  const RunSummary s = run_job(comm, again, options_for(dir));
  EXPECT_EQ(s.reused, 3);
  EXPECT_EQ(again.made, (std::map<int64_t, int>{{3, 1}, {4, 1}, {5, 1}}));
  EXPECT_FALSE(fs::exists(dir / "manifest.json.journal"));
  fs::remove_all(dir);
}

TEST(Job, UnwritableOutputAndNothingToDoAreClearErrors) {
  const fs::path dir = fresh_dir("bad");
  std::ofstream(dir / "file") << "x";
  LocalComm comm;
  TextJob job(dir / "file" / "sub", 3);
  RunOptions o = options_for(dir / "file" / "sub");
  try {
    run_job(comm, job, o);
    FAIL() << "no error";
  } catch (const JobError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot create the output folder"), std::string::npos) << e.what();
  }
  TextJob none(dir, 0);
  EXPECT_THROW(run_job(comm, none, options_for(dir)), JobError);
  fs::remove_all(dir);
}

TEST(Job, TemporariesAreRecognisedByTheirExactPattern) {
  EXPECT_TRUE(is_temporary_of("d/.pano_00001.tmp123.tif", "d/pano_00001.tif"));
  EXPECT_TRUE(is_temporary_of("d/pano_00001.tif.tmp4567", "d/pano_00001.tif"));
  EXPECT_FALSE(is_temporary_of("d/.pano_00001.tmp.tif", "d/pano_00001.tif"));
  EXPECT_FALSE(is_temporary_of("d/.pano_00001.tmp12.png", "d/pano_00001.tif"));
  EXPECT_FALSE(is_temporary_of("d/.pano_00011.tmp12.tif", "d/pano_00001.tif"));
  EXPECT_FALSE(is_temporary_of("d/pano_00001.tif", "d/pano_00001.tif"));
  EXPECT_FALSE(is_temporary_of("d/pano_00001.tif.tmp4x", "d/pano_00001.tif"));
}

}  // namespace
}  // namespace omma::dist
