// Distributed jobs: N independent work items, each producing one output file, spread over the
// ranks of a Comm (MPI under mpirun, or one local process: the same code path).
//
// Scheduling: dynamic. Rank 0 hands out items in order, one at a time, as ranks ask for work (items
// differ in cost: frame sets with more cameras, slower files); by default rank 0 also works, on a
// second thread, while its main thread serves the others (RunOptions::rank0; docs/results/mpi_bench.md
// "Rendering on a cluster" has the measurement).
//
// Outputs: each item writes its output under its final name atomically (temporary name, rename:
// core/io.h). After each item its rank hashes the file (checksum.h) and reports to rank 0, which
// appends a line to the JOURNAL (manifest path + ".journal") at once, and at the end writes the
// MANIFEST (JSON, atomically) and removes the journal:
//   {"format": "omma-job-manifest", "version": 1, "parameters": {...job...}, "items": N,
//    "ranks": K, "mpi": true, "rank0": "works", "made": M, "reused": R, "seconds": wall,
//    "input": {...Job::input_summary, only when not null...},
//    "totals": {"read": s, "develop": s, "render": s, "write": s, "checksum": s},
//    "outputs": [{"item": i, "output": path, "size": bytes, "checksum": "xxh3:...", "rank": r,
//                 "host": h, "seconds": s, "cpu_seconds": s, "read": s, "develop": s, "render": s,
//                 "write": s, "checksum_seconds": s, "reused": false}, ...]}   (item order)
//
// Resuming: a rerun reads the earlier manifest and journal (same parameters only), verifies the
// outputs they list (exists, size, checksum; the ranks share this work), reuses those that match
// and makes the rest. Temporaries left by killed ranks are removed first. So a job interrupted at
// any point (a rank killed, mpirun stopped, the machine rebooted) loses only the items in flight.
//
// Errors: every rank prepares (Job::setup) and checks that it can write the output folders; any
// failure on any rank, an item that throws, or more ranks than items ends the job on all ranks with
// ONE message, thrown as JobError on rank 0 ("rank 2 (host): ...") and as a quiet JobError on the
// others. Items that finished before the error stay recorded (the journal), items not started are
// not started. A rank that dies is mpirun's business: it stops the job and names the rank; rank 0
// then prints where the finished items are recorded.
#pragma once

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "omma/dist/comm.h"

namespace omma::dist {

// Seconds one item spent, by stage (what does not apply stays 0).
struct ItemTimes {
  double read = 0;     // reading inputs
  double develop = 0;  // ISP
  double render = 0;   // panorama
  double write = 0;    // encoding and writing the output
  ItemTimes& operator+=(const ItemTimes& o);
};

// One output: the manifest's line for an item.
struct ItemRecord {
  int64_t item = -1;
  std::string output;    // the path as Job::output names it
  uint64_t size = 0;     // bytes
  std::string checksum;  // "xxh3:<16 hex>" (checksum.h)
  int rank = -1;
  std::string host;
  double seconds = 0;      // wall time of the item on its rank, checksum included
  double cpu_seconds = 0;  // CPU time of its process meanwhile (all threads): the work itself,
                           // whatever else shares the machine
  ItemTimes times;
  double checksum_seconds = 0;
  bool reused = false;  // made by an earlier run and verified, not made again
  nlohmann::json to_json() const;
  static ItemRecord from_json(const nlohmann::json& j);  // throws nlohmann::json::exception
};

// The work. Implementations must make output(item) deterministic (the same bytes whichever rank
// makes it: the tests compare MPI runs with a single-process run byte for byte).
class Job {
 public:
  virtual ~Job() = default;
  virtual int64_t items() const = 0;
  // The final path of item's output; distinct for distinct items. Called from any thread.
  virtual std::filesystem::path output(int64_t item) const = 0;
  virtual std::string item_name(int64_t item) const { return "item " + std::to_string(item); }
  // Everything the outputs depend on (input, sizes, method, ...): outputs listed in a manifest with
  // other parameters are not reused.
  virtual nlohmann::json parameters() const { return nlohmann::json::object(); }
  // What open() found in the input that the outputs' reader should know (e.g. the frame sets a
  // renderer left out or completed, and by which policy): rank 0 writes it into the manifest as
  // "input" when it is not null.
  virtual nlohmann::json input_summary() const { return nullptr; }
  // Opens the input, cheaply (items() may depend on it): every rank, before anything else.
  virtual void open() {}
  // Prepares this rank for run() (compiles or loads maps): after the checks that need only open()
  // (ranks against items, output folders). Rank 0 runs it first, the other ranks after it (so that
  // they read caches rank 0 filled). Throw (from either) to report a problem.
  virtual void setup() {}
  // Makes output(item) atomically. On rank 0 it runs on a worker thread. Throw to report a problem.
  virtual ItemTimes run(int64_t item) = 0;
};

enum class Rank0 { kWorks, kServes };     // rank 0 makes items too, or only hands them out
Rank0 parse_rank0(const std::string& s);  // "works" | "serves"
const char* rank0_name(Rank0 r);

struct RunOptions {
  std::filesystem::path manifest;  // required; the journal is manifest + ".journal"
  bool resume = true;              // reuse verified outputs of an earlier run (else remake all)
  bool verify_checksums = true;    // when resuming: size and checksum (false: size only)
  Rank0 rank0 = Rank0::kWorks;     // ignored with one rank (it always works)
  bool progress = true;            // rank 0: progress on stderr
  std::string label = "items";     // progress label
  bool IsValid(std::string* why = nullptr) const;
};

struct RunSummary {
  int ranks = 1;
  bool mpi = false;
  Rank0 rank0 = Rank0::kWorks;
  int64_t items = 0;
  int64_t made = 0;          // by this run
  int64_t reused = 0;        // verified outputs of an earlier run
  double seconds = 0;        // wall time of the whole run (setup included)
  double setup_seconds = 0;  // until the first item was handed out
  ItemTimes totals;          // sums over the items made by this run
  double checksum_seconds = 0;
  double cpu_seconds = 0;
  nlohmann::json parameters;
  nlohmann::json input = nullptr;   // Job::input_summary (rank 0)
  std::vector<ItemRecord> records;  // rank 0: every item, item order; other ranks: empty
  nlohmann::json to_json() const;   // the manifest
};

class JobError : public std::runtime_error {
 public:
  // quiet: this rank is not rank 0, which reports the same failure; print nothing.
  JobError(const std::string& what, bool quiet) : std::runtime_error(what), quiet_(quiet) {}
  bool quiet() const { return quiet_; }

 private:
  bool quiet_;
};

// Runs the job on every rank of `comm` (every rank calls it with the same job and options).
// Returns the summary (complete on rank 0). Throws JobError (see the file comment).
RunSummary run_job(Comm& comm, Job& job, const RunOptions& options);

// A collective: rank 0's verdict ("" = go on; else the error) reaches every rank, which throws
// JobError with it (quietly on ranks other than 0).
void broadcast_verdict(Comm& comm, const std::string& error_on_rank0);

// A collective: every rank reports its error ("" = none). If any rank has one, every rank throws
// JobError: rank 0 with one message, `context` + "rank R (host): error; ...", the others quietly
// (an error every rank has, such as a bad option, is given once, without rank names).
void check_all_ranks(Comm& comm, const std::string& error, const std::string& context = "");

// Whether `file` is a temporary that an atomic write of `output` leaves when it is killed: core/io.h's
// ".STEM.tmpN.EXT", or "NAME.tmpN" (streaming writers such as the BigTIFF writer).
bool is_temporary_of(const std::filesystem::path& file, const std::filesystem::path& output);

}  // namespace omma::dist
