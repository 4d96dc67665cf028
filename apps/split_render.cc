#include "apps/split_render.h"

#include <chrono>
#include <cstring>
#include <deque>
#include <map>
#include <optional>
#include <thread>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "omma/io/tiff_writer.h"
#include "omma/dist/worker_thread.h"

namespace omma::dist {
namespace fs = std::filesystem;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

bool SplitOptions::IsValid(std::string* why) const {
  if (window < 0) {
    if (why) *why = "window must be >= 0";
    return false;
  }
  return true;
}

namespace {

enum Tag : int { kTagBand = 11, kTagAssign = 12 };

struct BandResult {
  int band = -1;
  double seconds = 0;
  std::string error;
  cv::Mat pixels;  // CV_8UC3
};

// [8-byte header length][JSON header][pixels]: one message per band.
std::string encode(const BandResult* r) {
  json h = nullptr;
  size_t bytes = 0;
  if (r) {
    h = {{"band", r->band}, {"seconds", r->seconds}, {"error", r->error}, {"rows", r->pixels.rows},
         {"cols", r->pixels.cols}};
    bytes = r->error.empty() ? r->pixels.total() * r->pixels.elemSize() : 0;
  }
  const std::string hs = h.dump();
  const uint64_t n = hs.size();
  std::string out(8 + hs.size() + bytes, '\0');
  std::memcpy(out.data(), &n, 8);
  std::memcpy(out.data() + 8, hs.data(), hs.size());
  if (bytes) std::memcpy(out.data() + 8 + hs.size(), r->pixels.data, bytes);
  return out;
}

std::optional<BandResult> decode(const std::string& m) {
  uint64_t n = 0;
  std::memcpy(&n, m.data(), 8);
  const json h = json::parse(m.substr(8, n));
  if (h.is_null()) return std::nullopt;
  BandResult r;
  r.band = h["band"];
  r.seconds = h["seconds"];
  r.error = h["error"];
  if (r.error.empty()) {
    r.pixels.create(h["rows"].get<int>(), h["cols"].get<int>(), CV_8UC3);
    std::memcpy(r.pixels.data, m.data() + 8 + n, r.pixels.total() * 3);
  }
  return r;
}

}  // namespace

SplitSummary render_split(Comm& comm, render::PanoRenderer& renderer, const fs::path& path,
                          const SplitOptions& options) {
  const auto t0 = Clock::now();
  const int rank = comm.rank(), size = comm.size();
  const Rank0 mode = size == 1 ? Rank0::kWorks : options.rank0;
  const int nb = renderer.bands();
  const int window = options.window > 0 ? options.window : 2 * size;
  SplitSummary sum;
  sum.bands = nb;

  auto render_one = [&renderer](int64_t b) {
    BandResult r;
    r.band = static_cast<int>(b);
    const auto t = Clock::now();
    try {
      renderer.render_band(r.band, r.pixels);
      if (!r.pixels.isContinuous()) r.pixels = r.pixels.clone();
    } catch (const std::exception& e) {
      r.error = e.what();
    }
    r.seconds = std::chrono::duration<double>(Clock::now() - t).count();
    return r;
  };

  // Rank 0 opens the output first: a failure there is everybody's error.
  std::string error;
  std::optional<io::BigTiffWriter> writer;
  if (rank == 0) {
    try {
      if (std::string why; !options.IsValid(&why)) throw std::invalid_argument(why);
      std::string ext = path.extension().string();
      for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      if (ext != ".tif" && ext != ".tiff")
        throw std::invalid_argument("--split tiles writes one BigTIFF: the output must end in .tif or .tiff, not '" +
                                    path.filename().string() + "'");
      const int workers = size - (mode == Rank0::kServes ? 1 : 0);
      if (workers > nb)
        throw std::invalid_argument(fmt::format("{} ranks for {} bands: start at most {}, or use smaller bands", size, nb,
                                                nb + (mode == Rank0::kServes ? 1 : 0)));
      const auto& g = renderer.options().grid;
      writer.emplace(path, g.width, g.height);
    } catch (const std::exception& e) {
      error = e.what();
    }
  }
  broadcast_verdict(comm, error);

  if (rank != 0) {
    std::string report = encode(nullptr);
    for (;;) {
      comm.send(0, kTagBand, report);
      const int b = std::stoi(comm.recv().data);
      if (b < 0) break;
      const BandResult r = render_one(b);
      report = encode(&r);
    }
    broadcast_verdict(comm, "");
    return sum;
  }

  sum.bands_per_rank.assign(size, 0);
  std::map<int, cv::Mat> held;
  int next_write = 0, next_hand = 0;
  std::string failure;
  auto next_band = [&]() -> int {  // -1: stop; -2: wait for the writer
    if (!failure.empty() || next_hand >= nb) return -1;
    if (next_hand >= next_write + window) return -2;
    return next_hand++;
  };
  auto accept = [&](BandResult&& r, int from) {
    if (!r.error.empty()) {
      if (failure.empty())
        failure = fmt::format("{}band {} (rows {}..): {}", size > 1 ? fmt::format("rank {}, ", from) : "", r.band,
                              renderer.band(r.band).y, r.error);
      return;
    }
    ++sum.bands_per_rank[from];
    sum.render_seconds += r.seconds;
    held[r.band] = std::move(r.pixels);
    sum.max_held = std::max(sum.max_held, static_cast<int>(held.size()));
    const auto tw = Clock::now();
    try {
      for (auto it = held.find(next_write); it != held.end() && failure.empty(); it = held.find(next_write)) {
        writer->write_rows(it->second);
        held.erase(it);
        ++next_write;
      }
    } catch (const std::exception& e) {
      if (failure.empty()) failure = e.what();
    }
    sum.write_seconds += std::chrono::duration<double>(Clock::now() - tw).count();
  };
  {
    std::optional<WorkerThread<BandResult>> local;
    bool local_done = mode != Rank0::kWorks;
    if (!local_done) local.emplace(render_one);
    std::deque<int> waiting;  // ranks that asked for a band while the window was full
    int remote = size - 1;     // ranks not yet told to stop
    for (;;) {
      if (local && !local_done && !local->busy()) {
        const int b = next_band();
        if (b >= 0) local->assign(b);
        if (b == -1) local_done = true;
      }
      while (!waiting.empty()) {
        const int b = next_band();
        if (b == -2) break;
        comm.send(waiting.front(), kTagAssign, std::to_string(b));
        waiting.pop_front();
        if (b == -1) --remote;
      }
      const bool local_busy = local && local->busy();
      if (remote == 0 && !local_busy && local_done) break;
      if (local_busy)
        if (auto r = local->wait_result(remote > 0 ? std::chrono::microseconds(500) : std::chrono::hours(1)))
          accept(std::move(*r), 0);
      if (remote > 0) {
        if (auto m = comm.try_recv()) {
          if (auto r = decode(m->data)) accept(std::move(*r), m->source);
          waiting.push_back(m->source);
        } else if (!local_busy) {
          std::this_thread::sleep_for(std::chrono::microseconds(500));
        }
      }
    }
  }
  if (failure.empty() && next_write != nb) failure = fmt::format("only {} of {} bands were written", next_write, nb);
  if (failure.empty()) {
    try {
      const auto tw = Clock::now();
      writer->finish();
      sum.write_seconds += std::chrono::duration<double>(Clock::now() - tw).count();
    } catch (const std::exception& e) {
      failure = e.what();
    }
  }
  writer.reset();  // without finish(): removes the temporary file
  sum.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  broadcast_verdict(comm, failure);
  return sum;
}

}  // namespace omma::dist
