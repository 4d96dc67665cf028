#include "apps/split_render.h"

#include <chrono>
#include <cstring>
#include <deque>
#include <functional>
#include <map>
#include <optional>
#include <thread>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "omma/core/io.h"
#include "omma/core/valid.h"
#include "omma/dist/worker_thread.h"
#include "omma/io/metadata.h"
#include "omma/io/tiff_writer.h"

namespace omma::dist {
namespace fs = std::filesystem;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

bool SplitOptions::IsValid(std::string* why) const {
  if (window < 0) return invalid(why, "window must be >= 0");
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
    h = {{"band", r->band},
         {"seconds", r->seconds},
         {"error", r->error},
         {"rows", r->pixels.rows},
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

namespace {

// Rank 0 opens the output first (a failure there is everybody's error): the options, the ranks
// against the bands, a BigTIFF path. Returns the error ("" if none).
std::string open_output(const Comm& comm, const render::PanoRenderer& renderer, const fs::path& path,
                        const SplitOptions& options, Rank0 mode, std::optional<io::BigTiffWriter>& writer) {
  try {
    if (std::string why; !options.IsValid(&why)) throw std::invalid_argument(why);
    const std::string ext = lower_extension(path);
    if (ext != ".tif" && ext != ".tiff")
      throw std::invalid_argument(
          "--split tiles writes one BigTIFF: the output must end in .tif or .tiff, not '" +
          path.filename().string() + "'");
    const int nb = renderer.bands(), size = comm.size();
    const int workers = size - (mode == Rank0::kServes ? 1 : 0);
    if (workers > nb)
      throw std::invalid_argument(fmt::format("{} ranks for {} bands: start at most {}, or use smaller bands",
                                              size, nb, nb + (mode == Rank0::kServes ? 1 : 0)));
    const auto& g = renderer.options().grid;
    writer.emplace(path, g.width, g.height, false, 16, io::panorama_xmp(g));  // with the 360-degree XMP
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

// A rank other than 0: renders the bands it is given until told to stop, reporting each with the
// next request.
void work(Comm& comm, const std::function<BandResult(int64_t)>& render_one) {
  std::string report = encode(nullptr);
  for (;;) {
    comm.send(0, kTagBand, report);
    const int b = std::stoi(comm.recv().data);
    if (b < 0) break;
    const BandResult r = render_one(b);
    report = encode(&r);
  }
}

// Rank 0's bookkeeping: which band to hand out next (at most `window` ahead of the writer), and the
// bands that arrived, written in order as soon as the next one is there.
class BandWriter {
 public:
  BandWriter(const render::PanoRenderer& renderer, io::BigTiffWriter& writer, int window, int ranks,
             SplitSummary& sum)
      : renderer_(renderer),
        writer_(writer),
        nb_(renderer.bands()),
        window_(window),
        ranks_(ranks),
        sum_(sum) {}
  // The band to hand out: -1 stop; -2 wait for the writer.
  int next_band() {
    if (!failure_.empty() || next_hand_ >= nb_) return -1;
    if (next_hand_ >= next_write_ + window_) return -2;
    return next_hand_++;
  }
  void accept(BandResult&& r, int from) {
    if (!r.error.empty()) {
      if (failure_.empty())
        failure_ = fmt::format("{}band {} (rows {}..): {}", ranks_ > 1 ? fmt::format("rank {}, ", from) : "",
                               r.band, renderer_.band(r.band).y, r.error);
      return;
    }
    ++sum_.bands_per_rank[from];
    sum_.render_seconds += r.seconds;
    held_[r.band] = std::move(r.pixels);
    sum_.max_held = std::max(sum_.max_held, static_cast<int>(held_.size()));
    const auto tw = Clock::now();
    try {
      for (auto it = held_.find(next_write_); it != held_.end() && failure_.empty();
           it = held_.find(next_write_)) {
        writer_.write_rows(it->second);
        held_.erase(it);
        ++next_write_;
      }
    } catch (const std::exception& e) {
      if (failure_.empty()) failure_ = e.what();
    }
    sum_.write_seconds += std::chrono::duration<double>(Clock::now() - tw).count();
  }
  // After serving: the failure, if any ("" when every band was written and the file finished).
  std::string finish() {
    if (failure_.empty() && next_write_ != nb_)
      failure_ = fmt::format("only {} of {} bands were written", next_write_, nb_);
    if (failure_.empty()) {
      try {
        const auto tw = Clock::now();
        writer_.finish();
        sum_.write_seconds += std::chrono::duration<double>(Clock::now() - tw).count();
      } catch (const std::exception& e) {
        failure_ = e.what();
      }
    }
    return failure_;
  }

 private:
  const render::PanoRenderer& renderer_;
  io::BigTiffWriter& writer_;
  const int nb_, window_, ranks_;
  SplitSummary& sum_;
  std::map<int, cv::Mat> held_;
  int next_write_ = 0, next_hand_ = 0;
  std::string failure_;
};

// Rank 0 hands out bands to the other ranks (and renders some itself with kWorks) until every rank
// is told to stop.
void serve(Comm& comm, Rank0 mode, const std::function<BandResult(int64_t)>& render_one, BandWriter& out) {
  std::optional<WorkerThread<BandResult>> local;
  bool local_done = mode != Rank0::kWorks;
  if (!local_done) local.emplace(render_one);
  std::deque<int> waiting;       // ranks that asked for a band while the window was full
  int remote = comm.size() - 1;  // ranks not yet told to stop
  for (;;) {
    if (local && !local_done && !local->busy()) {
      const int b = out.next_band();
      if (b >= 0) local->assign(b);
      if (b == -1) local_done = true;
    }
    while (!waiting.empty()) {
      const int b = out.next_band();
      if (b == -2) break;
      comm.send(waiting.front(), kTagAssign, std::to_string(b));
      waiting.pop_front();
      if (b == -1) --remote;
    }
    const bool local_busy = local && local->busy();
    if (remote == 0 && !local_busy && local_done) break;
    if (local_busy)
      if (auto r = local->wait_result(remote > 0 ? std::chrono::microseconds(500) : std::chrono::hours(1)))
        out.accept(std::move(*r), 0);
    if (remote > 0) {
      if (auto m = comm.try_recv()) {
        if (auto r = decode(m->data)) out.accept(std::move(*r), m->source);
        waiting.push_back(m->source);
      } else if (!local_busy) {
        std::this_thread::sleep_for(std::chrono::microseconds(500));
      }
    }
  }
}

}  // namespace

SplitSummary render_split(Comm& comm, render::PanoRenderer& renderer, const fs::path& path,
                          const SplitOptions& options) {
  const auto t0 = Clock::now();
  const int rank = comm.rank(), size = comm.size();
  const Rank0 mode = size == 1 ? Rank0::kWorks : options.rank0;
  SplitSummary sum;
  sum.bands = renderer.bands();
  const std::function<BandResult(int64_t)> render_one = [&renderer](int64_t b) {
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
  std::optional<io::BigTiffWriter> writer;
  broadcast_verdict(comm, rank == 0 ? open_output(comm, renderer, path, options, mode, writer) : "");
  if (rank != 0) {
    work(comm, render_one);
    broadcast_verdict(comm, "");
    return sum;
  }
  sum.bands_per_rank.assign(size, 0);
  BandWriter out(renderer, *writer, options.window > 0 ? options.window : 2 * size, size, sum);
  serve(comm, mode, render_one, out);
  const std::string failure = out.finish();
  writer.reset();  // without finish(): removes the temporary file
  sum.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  broadcast_verdict(comm, failure);
  return sum;
}

}  // namespace omma::dist
