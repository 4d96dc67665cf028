#include "omma/dist/job.h"

#include <fcntl.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cstring>
#include <deque>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <thread>
#include <unordered_map>

#include <fmt/format.h>

#include "omma/core/checksum.h"
#include "omma/core/io.h"
#include "omma/core/log.h"
#include "omma/core/progress.h"
#include "omma/core/valid.h"
#include "omma/dist/worker_thread.h"

namespace omma::dist {
namespace fs = std::filesystem;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

ItemTimes& ItemTimes::operator+=(const ItemTimes& o) {
  read += o.read;
  develop += o.develop;
  render += o.render;
  write += o.write;
  return *this;
}

json ItemRecord::to_json() const {
  return {{"item", item},
          {"output", output},
          {"size", size},
          {"checksum", checksum},
          {"rank", rank},
          {"host", host},
          {"seconds", seconds},
          {"cpu_seconds", cpu_seconds},
          {"read", times.read},
          {"develop", times.develop},
          {"render", times.render},
          {"write", times.write},
          {"checksum_seconds", checksum_seconds},
          {"reused", reused}};
}

ItemRecord ItemRecord::from_json(const json& j) {
  ItemRecord r;
  r.item = j.at("item").get<int64_t>();
  r.output = j.at("output").get<std::string>();
  r.size = j.at("size").get<uint64_t>();
  r.checksum = j.at("checksum").get<std::string>();
  r.rank = j.value("rank", -1);
  r.host = j.value("host", "");
  r.seconds = j.value("seconds", 0.0);
  r.cpu_seconds = j.value("cpu_seconds", 0.0);
  r.times.read = j.value("read", 0.0);
  r.times.develop = j.value("develop", 0.0);
  r.times.render = j.value("render", 0.0);
  r.times.write = j.value("write", 0.0);
  r.checksum_seconds = j.value("checksum_seconds", 0.0);
  r.reused = j.value("reused", false);
  return r;
}

Rank0 parse_rank0(const std::string& s) {
  if (s == "works") return Rank0::kWorks;
  if (s == "serves") return Rank0::kServes;
  throw std::invalid_argument("rank 0 mode '" + s + "' (use works or serves)");
}

const char* rank0_name(Rank0 r) { return r == Rank0::kWorks ? "works" : "serves"; }

bool RunOptions::IsValid(std::string* why) const {
  if (manifest.empty()) return invalid(why, "a manifest path is required");
  return true;
}

json RunSummary::to_json() const {
  json outs = json::array();
  for (const auto& r : records) outs.push_back(r.to_json());
  json j = {{"format", "omma-job-manifest"},
            {"version", 1},
            {"parameters", parameters},
            {"items", items},
            {"ranks", ranks},
            {"mpi", mpi},
            {"rank0", rank0_name(rank0)},
            {"made", made},
            {"reused", reused},
            {"seconds", seconds},
            {"setup_seconds", setup_seconds},
            {"totals",
             {{"read", totals.read},
              {"develop", totals.develop},
              {"render", totals.render},
              {"write", totals.write},
              {"checksum", checksum_seconds},
              {"cpu", cpu_seconds}}},
            {"outputs", outs}};
  if (!input.is_null()) j["input"] = input;
  return j;
}

bool is_temporary_of(const fs::path& file, const fs::path& output) {
  const std::string name = file.filename().string();
  auto digits_between = [&](size_t from, size_t to) {
    if (to <= from) return false;
    return std::all_of(name.begin() + from, name.begin() + to, [](char c) { return c >= '0' && c <= '9'; });
  };
  // core/io.h: "." + stem + ".tmp" + digits + extension
  const std::string a = "." + output.stem().string() + ".tmp", ext = output.extension().string();
  if (name.size() > a.size() + ext.size() && name.compare(0, a.size(), a) == 0 &&
      name.compare(name.size() - ext.size(), ext.size(), ext) == 0 &&
      digits_between(a.size(), name.size() - ext.size()))
    return true;
  // streaming writers: filename + ".tmp" + digits
  const std::string b = output.filename().string() + ".tmp";
  return name.size() > b.size() && name.compare(0, b.size(), b) == 0 && digits_between(b.size(), name.size());
}

namespace {

enum Tag : int { kTagRequest = 1, kTagAssign = 2 };

double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

double process_cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

// What a rank reports after an item: its record, or the error.
struct ItemResult {
  int64_t item = -1;
  std::string host;
  std::optional<ItemRecord> record;
  std::string error;
};

json result_to_json(const ItemResult& r) {
  if (r.record) return {{"record", r.record->to_json()}};
  return {{"item", r.item}, {"host", r.host}, {"error", r.error}};
}

ItemResult result_from_json(const json& j) {
  ItemResult r;
  if (j.contains("record")) {
    r.record = ItemRecord::from_json(j["record"]);
    r.item = r.record->item;
  } else {
    r.item = j.at("item").get<int64_t>();
    r.error = j.at("error").get<std::string>();
    r.host = j.value("host", "");
  }
  return r;
}

ItemResult run_one(Job& job, int64_t item, int rank, const std::string& host) {
  ItemResult res;
  res.item = item;
  res.host = host;
  const auto t0 = Clock::now();
  const double cpu0 = process_cpu_seconds();
  try {
    ItemRecord r;
    r.item = item;
    r.output = job.output(item).string();
    r.rank = rank;
    r.host = host;
    r.times = job.run(item);
    const auto t1 = Clock::now();
    const FileDigest d = file_digest(job.output(item));
    r.checksum_seconds = since(t1);
    r.size = d.size;
    r.checksum = d.checksum;
    r.seconds = since(t0);
    r.cpu_seconds = process_cpu_seconds() - cpu0;
    res.record = std::move(r);
  } catch (const std::exception& e) {
    res.error = e.what();
  }
  return res;
}

// The distinct folders of the outputs (and of the manifest).
std::vector<fs::path> output_folders(const Job& job, const fs::path& manifest) {
  std::set<fs::path> dirs;
  auto parent = [](const fs::path& p) { return p.has_parent_path() ? p.parent_path() : fs::path("."); };
  dirs.insert(parent(manifest));
  for (int64_t i = 0; i < job.items(); ++i) dirs.insert(parent(job.output(i)));
  return {dirs.begin(), dirs.end()};
}

// Creates the folder if needed and checks that a file can be created in it. Throws IoError.
void check_writable(const fs::path& dir, int rank) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (!fs::is_directory(dir))
    throw IoError(
        fmt::format("cannot create the output folder '{}'{}", dir.string(), ec ? ": " + ec.message() : ""));
  const fs::path probe = dir / fmt::format(".omma-write-probe-{}-{}", rank, ::getpid());
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0644);
  if (fd < 0)
    throw IoError(
        fmt::format("cannot write in the output folder '{}': {}", dir.string(), std::strerror(errno)));
  ::close(fd);
  fs::remove(probe, ec);
}

// The journal: one JSON line per finished item, appended with one write() each (a killed rank 0
// loses at most the line being written; a torn last line is ignored when read back).
class Journal {
 public:
  Journal() = default;
  void open(const fs::path& path, const json& header) {
    path_ = path;
    fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd_ < 0)
      throw IoError(fmt::format("cannot create the journal '{}': {}", path.string(), std::strerror(errno)));
    append(json{{"parameters", header}});
  }
  void append(const json& line) {
    const std::string s = line.dump() + "\n";
    if (::write(fd_, s.data(), s.size()) != static_cast<ssize_t>(s.size()))
      throw IoError(fmt::format("cannot append to the journal '{}' (disk full?)", path_.string()));
  }
  void close_and_remove() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    std::error_code ec;
    fs::remove(path_, ec);
  }
  ~Journal() {
    if (fd_ >= 0) ::close(fd_);
  }

 private:
  fs::path path_;
  int fd_ = -1;
};

fs::path journal_path(const fs::path& manifest) {
  fs::path j = manifest;
  j += ".journal";
  return j;
}

// Records of an earlier run with the same parameters, by output path (an earlier run over another
// range of frame sets numbers its items differently): the manifest, then the journal (later wins).
std::map<std::string, ItemRecord> previous_records(const fs::path& manifest, const json& params) {
  std::map<std::string, ItemRecord> out;
  auto take = [&](const json& rec) {
    try {
      ItemRecord r = ItemRecord::from_json(rec);
      out[r.output] = r;
    } catch (const json::exception&) {
    }
  };
  if (fs::exists(manifest)) {
    try {
      const json m = json::parse(read_text_file(manifest));
      if (m.value("parameters", json()) == params) {
        for (const auto& r : m.at("outputs")) take(r);
      } else {
        spdlog::warn("{} was made with other parameters: its outputs are made again", manifest.string());
      }
    } catch (const std::exception& e) {
      spdlog::warn("ignoring the unreadable manifest {}: {}", manifest.string(), e.what());
    }
  }
  const fs::path jp = journal_path(manifest);
  if (fs::exists(jp)) {
    std::ifstream in(jp);
    std::string line;
    bool same = false, first = true;
    while (std::getline(in, line)) {
      json j;
      try {
        j = json::parse(line);
      } catch (const json::exception&) {
        break;  // a torn last line
      }
      if (first) {
        same = j.value("parameters", json()) == params;
        first = false;
        if (!same) spdlog::warn("{} was made with other parameters: ignored", jp.string());
        continue;
      }
      if (same) take(j);
    }
  }
  return out;
}

// Rank 0's message when mpirun stops the job (a rank died, or mpirun was interrupted): it sends
// SIGTERM to every rank. Prepared before the job runs (a signal handler may only write()).
char g_stop_message[1024];
size_t g_stop_len = 0;
void on_stop_signal(int sig) {  // C++ linkage: file-local (anonymous namespace)
  ssize_t n = ::write(STDERR_FILENO, g_stop_message, g_stop_len);
  (void)n;
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

struct SignalGuard {
  struct sigaction old_term {
  }, old_int{}, old_hup{};
  bool on = false;
  void install(const fs::path& journal) {
    const std::string m = fmt::format(
        "omma: error: the job was stopped (a rank died, or mpirun was interrupted); the finished outputs are "
        "recorded in {}: run the same command again to make only the rest\n",
        journal.string());
    g_stop_len = std::min(m.size(), sizeof g_stop_message);
    std::memcpy(g_stop_message, m.data(), g_stop_len);
    struct sigaction sa {};
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGTERM, &sa, &old_term);
    sigaction(SIGINT, &sa, &old_int);
    sigaction(SIGHUP, &sa, &old_hup);
    on = true;
  }
  ~SignalGuard() {
    if (!on) return;
    sigaction(SIGTERM, &old_term, nullptr);
    sigaction(SIGINT, &old_int, nullptr);
    sigaction(SIGHUP, &old_hup, nullptr);
  }
};

}  // namespace

void broadcast_verdict(Comm& comm, const std::string& error_on_rank0) {
  const std::string verdict = comm.broadcast(comm.rank() == 0 ? error_on_rank0 : std::string());
  if (!verdict.empty()) throw JobError(verdict, comm.rank() != 0);
}

void check_all_ranks(Comm& comm, const std::string& my_error, const std::string& what) {
  const std::string mine = my_error.empty() ? "" : json{{"host", comm.host()}, {"error", my_error}}.dump();
  const auto all = comm.gather(mine);
  std::string msg;
  if (comm.rank() == 0) {
    std::vector<std::string> parts;
    std::set<std::string> distinct;
    for (const auto& m : all) distinct.insert(m.empty() ? "" : json::parse(m)["error"].get<std::string>());
    const bool same_everywhere = distinct.size() == 1 && !all[0].empty();
    if (same_everywhere) parts.push_back(*distinct.begin());  // given once
    for (size_t r = 0; r < all.size() && !same_everywhere; ++r)
      if (!all[r].empty()) {
        const json j = json::parse(all[r]);
        parts.push_back(comm.size() > 1 ? fmt::format("rank {} ({}): {}", r, j["host"].get<std::string>(),
                                                      j["error"].get<std::string>())
                                        : j["error"].get<std::string>());
      }
    if (!parts.empty()) {
      msg = what + parts[0];
      for (size_t i = 1; i < parts.size(); ++i) msg += "; " + parts[i];
    }
  }
  broadcast_verdict(comm, msg);
}

namespace {

// Phase 1, rank 0: options, ranks against items, output folders, set-up, the earlier run's records
// (item -> its record) when resuming. Returns the error ("" if none), named by rank where needed.
std::string prepare_root(Comm& comm, Job& job, const RunOptions& options, Rank0 rank0, json& params,
                         std::map<int64_t, ItemRecord>& previous) {
  const int size = comm.size();
  const int serving = rank0 == Rank0::kServes ? 1 : 0;  // rank 0 only serves: one worker fewer
  bool own = false;                                     // the runner's own checks need no rank name
  try {
    if (std::string why; !options.IsValid(&why)) throw std::invalid_argument(why);
    job.open();
    const int64_t n = job.items();
    if (n < 1) throw std::invalid_argument("there is nothing to make (0 items)");
    own = size - serving > n;
    if (own)
      throw std::invalid_argument(fmt::format("{} ranks{} for {} {}: start at most {} (mpirun -np {})", size,
                                              serving ? " (rank 0 only serves)" : "", n, options.label,
                                              n + serving, n + serving));
    for (const auto& d : output_folders(job, options.manifest)) check_writable(d, 0);
    job.setup();
    params = job.parameters();
    if (options.resume) {
      auto by_path = previous_records(options.manifest, params);
      for (int64_t i = 0; i < n && !by_path.empty(); ++i) {
        const auto it = by_path.find(job.output(i).string());
        if (it == by_path.end()) continue;
        it->second.item = i;
        previous[i] = it->second;
      }
    }
  } catch (const std::exception& e) {
    return size > 1 && !own ? fmt::format("rank 0 ({}): {}", comm.host(), e.what()) : e.what();
  }
  return "";
}

// Phase 2, the other ranks: set-up, output folders. Returns the error ("" if none).
std::string prepare_worker(Comm& comm, Job& job, const RunOptions& options) {
  try {
    job.open();
    for (const auto& d : output_folders(job, options.manifest)) check_writable(d, comm.rank());
    job.setup();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

// Phase 3, every rank: verifies its share (every size-th) of the earlier run's outputs; rank 0
// gets every rank's list of verified items (JSON arrays).
std::vector<std::string> verify_previous(Comm& comm, Job& job, const RunOptions& options,
                                         const std::map<int64_t, ItemRecord>& previous) {
  const int rank = comm.rank(), size = comm.size();
  json to_check = json::array();
  if (rank == 0)
    for (const auto& [i, r] : previous) to_check.push_back(r.to_json());
  to_check = json::parse(comm.broadcast(rank == 0 ? to_check.dump() : std::string()));
  json verified = json::array();
  for (size_t k = rank; k < to_check.size(); k += size) {
    const ItemRecord r = ItemRecord::from_json(to_check[k]);
    try {
      const fs::path p = job.output(r.item);
      if (p.string() != r.output || !fs::is_regular_file(p) || fs::file_size(p) != r.size) continue;
      if (options.verify_checksums && file_digest(p).checksum != r.checksum) continue;
      verified.push_back(r.item);
    } catch (const std::exception&) {
    }
  }
  return comm.gather(verified.dump());
}

// A worker rank: asks for items until told to stop; reports each result with the next request.
void work(Comm& comm, Job& job) {
  std::string report = "null";
  for (;;) {
    comm.send(0, kTagRequest, report);
    const Message m = comm.recv();
    const int64_t item = json::parse(m.data).get<int64_t>();
    if (item < 0) break;
    report = result_to_json(run_one(job, item, comm.rank(), comm.host())).dump();
  }
}

// Temporaries of interrupted writes (killed ranks) beside the outputs: one listing per output folder.
void remove_stale_temporaries(Job& job, int64_t items) {
  std::map<fs::path, std::set<std::string>> names;  // folder -> output file names
  for (int64_t i = 0; i < items; ++i) {
    const fs::path p = job.output(i);
    names[p.has_parent_path() ? p.parent_path() : fs::path(".")].insert(p.filename().string());
  }
  for (const auto& [dir, outs] : names)
    for (const auto& e : fs::directory_iterator(dir)) {
      const std::string name = e.path().filename().string();
      const auto at = name.rfind(".tmp");
      if (at == std::string::npos) continue;
      // The output a temporary would belong to: "NAME.tmpN" -> NAME; ".STEM.tmpN.EXT" -> STEM.EXT.
      std::vector<std::string> owners{name.substr(0, at)};
      if (name[0] == '.') {
        const auto dot = name.find('.', at + 4);
        owners.push_back(name.substr(1, at - 1) + (dot == std::string::npos ? "" : name.substr(dot)));
      }
      for (const auto& o : owners)
        if (outs.count(o) && is_temporary_of(e.path(), dir / o)) {
          spdlog::info("removing {} (left by an interrupted write)", e.path().string());
          fs::remove(e.path());
          break;
        }
    }
}

// Rank 0 serves the items in `todo` to the workers (and works on them itself with kWorks) until
// every worker is told to stop; `accept` takes each result with the rank that made it.
void serve(Comm& comm, Job& job, Rank0 rank0, std::deque<int64_t>& todo,
           const std::function<void(const ItemResult&, int)>& accept) {
  std::optional<WorkerThread<ItemResult>> local;
  if (rank0 == Rank0::kWorks) {
    local.emplace([&job, host = comm.host()](int64_t item) { return run_one(job, item, 0, host); });
    if (!todo.empty()) {
      local->assign(todo.front());
      todo.pop_front();
    }
  }
  int remote = comm.size() - 1;  // workers not yet told to stop
  while (remote > 0 || (local && local->busy())) {
    if (local && local->busy()) {
      if (auto r = local->wait_result(remote > 0 ? std::chrono::microseconds(500) : std::chrono::hours(1))) {
        accept(*r, 0);
        if (!todo.empty()) {
          local->assign(todo.front());
          todo.pop_front();
        }
      }
    }
    if (remote > 0) {
      if (auto m = comm.try_recv()) {
        const json report = json::parse(m->data);
        if (!report.is_null()) accept(result_from_json(report), m->source);
        int64_t next = -1;
        if (!todo.empty()) {
          next = todo.front();
          todo.pop_front();
        } else {
          --remote;
        }
        comm.send(m->source, kTagAssign, json(next).dump());
      } else if (!(local && local->busy())) {
        std::this_thread::sleep_for(std::chrono::microseconds(500));
      }
    }
  }
}

}  // namespace

RunSummary run_job(Comm& comm, Job& job, const RunOptions& options) {
  const auto t_start = Clock::now();
  const int size = comm.size();
  const bool root = comm.rank() == 0;
  RunSummary sum;
  sum.ranks = size;
  sum.mpi = comm.is_mpi();
  sum.rank0 = size == 1 ? Rank0::kWorks : options.rank0;
  const fs::path jpath = journal_path(options.manifest);

  json params;
  std::map<int64_t, ItemRecord> previous;  // item -> the earlier run's record of its output
  broadcast_verdict(comm, root ? prepare_root(comm, job, options, sum.rank0, params, previous) : "");
  check_all_ranks(comm, root ? "" : prepare_worker(comm, job, options), "");
  const auto all_verified = verify_previous(comm, job, options, previous);
  if (!root) {
    work(comm, job);
    broadcast_verdict(comm, "");
    sum.seconds = since(t_start);
    return sum;
  }

  // Rank 0: the items to make, stale temporaries, the journal, then serve (and work).
  sum.items = job.items();
  sum.parameters = params;
  sum.input = job.input_summary();
  std::vector<std::optional<ItemRecord>> records(sum.items);
  for (const auto& part : all_verified)
    for (const auto& i : json::parse(part)) {
      ItemRecord r = previous.at(i.get<int64_t>());
      r.reused = true;
      records[r.item] = r;
    }
  std::deque<int64_t> todo;
  for (int64_t i = 0; i < sum.items; ++i)
    if (!records[i]) todo.push_back(i);
  sum.reused = sum.items - static_cast<int64_t>(todo.size());
  if (sum.reused > 0)
    spdlog::info("resuming: {} of {} {} verified from the earlier run, {} to make", sum.reused, sum.items,
                 options.label, todo.size());

  std::string failure;
  Journal journal;
  try {
    remove_stale_temporaries(job, sum.items);
    journal.open(jpath, params);
    for (const auto& r : records)
      if (r) journal.append(r->to_json());
  } catch (const std::exception& e) {
    failure = e.what();
    todo.clear();
  }
  SignalGuard signals;
  if (sum.mpi) signals.install(jpath);
  sum.setup_seconds = since(t_start);

  Progress progress(options.label, todo.size(), options.progress && !todo.empty());
  serve(comm, job, sum.rank0, todo, [&](const ItemResult& res, int from) {
    if (!res.error.empty()) {
      if (failure.empty())
        failure = fmt::format("{}{}: {}", size > 1 ? fmt::format("rank {} ({}), ", from, res.host) : "",
                              job.item_name(res.item), res.error);
      todo.clear();
      return;
    }
    try {
      journal.append(res.record->to_json());
    } catch (const std::exception& e) {
      if (failure.empty()) failure = e.what();
      todo.clear();
    }
    records[res.item] = *res.record;
    progress.step();
  });
  progress.finish();

  sum.seconds = since(t_start);
  for (const auto& r : records)
    if (r) {
      sum.records.push_back(*r);
      if (!r->reused) {
        ++sum.made;
        sum.totals += r->times;
        sum.checksum_seconds += r->checksum_seconds;
        sum.cpu_seconds += r->cpu_seconds;
      }
    }
  if (failure.empty()) {
    try {
      write_text_atomically(options.manifest, sum.to_json().dump(1) + "\n");
      journal.close_and_remove();
    } catch (const std::exception& e) {
      failure = e.what();
    }
  } else {
    failure += fmt::format(
        " ({} of {} {} are finished and recorded in {}: run the same command again to make the rest)",
        sum.records.size(), sum.items, options.label, jpath.string());
  }
  broadcast_verdict(comm, failure);
  return sum;
}

}  // namespace omma::dist
