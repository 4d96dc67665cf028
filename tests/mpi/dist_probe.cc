// omma_dist_probe: a test job for the distribution layer (omma/dist/job.h), run by the MPI tests
// under mpirun and as one process. Item i reads IN/in_NNNN.txt (a seed), waits
// (1 + i % 3) * --cost-ms (items of unequal cost, so that dynamic scheduling matters), and writes
// OUT/item_NNNN.bin: --bytes pseudo-random bytes (splitmix64) from the seed and i, atomically.
// Faults for the tests: --die-at I (a rank other than 0 that makes an item >= I writes half its
// temporary file and kills itself with SIGKILL), --fail-at I (item I throws).
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <thread>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "omma/core/io.h"
#include "omma/core/log.h"
#include "omma/dist/job.h"

namespace {
namespace fs = std::filesystem;
using omma::dist::ItemTimes;

struct ProbeArgs {
  std::string input, out;
  int64_t items = 9;
  int cost_ms = 20, bytes = 65536;
  int64_t die_at = -1, fail_at = -1;
  std::string rank0 = "works";
  bool no_resume = false, json = false;
};

class ProbeJob : public omma::dist::Job {
 public:
  ProbeJob(const ProbeArgs& a, int rank) : a_(a), rank_(rank) {}
  int64_t items() const override { return a_.items; }
  fs::path output(int64_t i) const override { return fs::path(a_.out) / fmt::format("item_{:04d}.bin", i); }
  std::string item_name(int64_t i) const override { return fmt::format("probe item {}", i); }
  nlohmann::json parameters() const override { return {{"bytes", a_.bytes}, {"items", a_.items}}; }
  void setup() override {
    if (!fs::is_directory(a_.input)) throw omma::IoError("cannot read the input folder '" + a_.input + "'");
  }
  ItemTimes run(int64_t i) override {
    using clock = std::chrono::steady_clock;
    ItemTimes t;
    auto t0 = clock::now();
    const uint64_t seed =
        std::stoull(omma::read_text_file(fs::path(a_.input) / fmt::format("in_{:04d}.txt", i)));
    auto t1 = clock::now();
    t.read = std::chrono::duration<double>(t1 - t0).count();
    if (i == a_.fail_at)
      throw std::runtime_error(fmt::format("input in_{:04d}.txt is damaged (--fail-at)", i));
    std::this_thread::sleep_for(std::chrono::milliseconds(a_.cost_ms * (1 + i % 3)));
    std::string data(a_.bytes, '\0');
    uint64_t x = seed * 0x9e3779b97f4a7c15ull + static_cast<uint64_t>(i);
    for (auto& c : data) {  // splitmix64
      uint64_t z = (x += 0x9e3779b97f4a7c15ull);
      z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
      z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
      c = static_cast<char>(z ^ (z >> 31));
    }
    auto t2 = clock::now();
    t.render = std::chrono::duration<double>(t2 - t1).count();
    omma::write_atomically(output(i), [&](const fs::path& tmp) {
      std::ofstream f(tmp, std::ios::binary);
      if (a_.die_at >= 0 && i >= a_.die_at && rank_ != 0) {
        f.write(data.data(), data.size() / 2);
        f.flush();
        std::raise(SIGKILL);
      }
      f.write(data.data(), data.size());
      if (!f) throw omma::IoError("cannot write " + tmp.string());
    });
    t.write = std::chrono::duration<double>(clock::now() - t2).count();
    return t;
  }

 private:
  ProbeArgs a_;
  int rank_;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Test job for omma's distribution layer"};
  ProbeArgs a;
  app.add_option("--input", a.input)->required();
  app.add_option("--out", a.out)->required();
  app.add_option("--items", a.items);
  app.add_option("--cost-ms", a.cost_ms);
  app.add_option("--bytes", a.bytes);
  app.add_option("--die-at", a.die_at);
  app.add_option("--fail-at", a.fail_at);
  app.add_option("--rank0", a.rank0);
  app.add_flag("--no-resume", a.no_resume);
  app.add_flag("--json", a.json);
  CLI11_PARSE(app, argc, argv);
  omma::init_logging(false, false);  // stderr: stdout is the --json summary
  try {
    auto comm = omma::dist::make_comm();
    ProbeJob job(a, comm->rank());
    omma::dist::RunOptions o;
    o.manifest = fs::path(a.out) / "manifest.json";
    o.rank0 = omma::dist::parse_rank0(a.rank0);
    o.resume = !a.no_resume;
    o.progress = false;
    o.label = "probe items";
    try {
      const auto sum = omma::dist::run_job(*comm, job, o);
      if (a.json && comm->rank() == 0) std::cout << sum.to_json().dump() << std::endl;
    } catch (const omma::dist::JobError& e) {
      if (!e.quiet()) std::fprintf(stderr, "omma: error: %s\n", e.what());
      return 1;  // comm's destructor finalises MPI on every rank
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "omma: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
