#include "omma/live/recorder.h"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <thread>

#include <fmt/format.h>

#include "omma/core/log.h"
#include "omma/core/progress.h"
#include "omma/core/valid.h"

namespace omma::live {

bool RecordOptions::IsValid(std::string* why) const {
  if (!(duration_s >= 0)) return invalid(why, "duration must be >= 0");
  if (frames < 0) return invalid(why, "frames must be >= 0");
  if (queue_frames < 1 || queue_frames > 1000) return invalid(why, "queue must hold 1..1000 frames");
  if (!(flush_interval_s > 0 && flush_interval_s <= 1))
    return invalid(why, "flush interval must be in (0, 1] s");
  // The manifest's own validators: `omma record` never writes a recording its reader refuses.
  if (!(exposure_s >= 0 && exposure_s <= io::kMaxExposureS))
    return invalid(why, fmt::format("exposure must be in [0, {:g}] s", io::kMaxExposureS));
  if ((fps != 0 && !io::valid_recording_fps(fps, why)) || !io::valid_recording_clock_mhz(clock_mhz, why) ||
      !io::valid_sensor_mode(sensor_mode, why))
    return false;
  return true;
}

double derived_recording_fps(const std::vector<double>& source_fps) {
  double slowest = 0;
  for (const double f : source_fps)
    if (f > 0 && (slowest == 0 || f < slowest)) slowest = f;
  if (slowest == 0) return kFallbackFps;
  return std::clamp(kDerivedRateFactor * slowest, io::kMinRecordingFps, io::kMaxRecordingFps);
}

namespace {

struct Queued {
  cv::Mat raw;
  uint64_t seq;
  int64_t t_ns;
};

// One lock per camera queue (a camera thread preempted while it holds its lock delays only its
// own queue, not the writer's round), and one for the writer's wake-up and the error.
struct CameraQueue {
  std::mutex m;
  std::deque<Queued> q;
  int64_t dropped = 0;
};

struct Shared {
  std::mutex m;  // cv, error
  std::condition_variable cv;
  std::vector<CameraQueue> queues;
  std::atomic<int> running{0};  // sources still delivering
  std::atomic<bool> stop{false};
  std::string error;
};

}  // namespace

namespace {

// Camera c's thread: reads its source (free-running at the source's own rate), converts each frame
// to the raw mosaic and queues it for the writer; a full queue drops the frame (the sequence numbers
// show the gap). The first error of any camera is kept in sh.error.
void capture(int c, CameraSource& src, const io::RecordingManifest& manifest, const RecordOptions& opt,
             Shared& sh, std::chrono::steady_clock::time_point t0) {
  uint64_t seq = 0;
  const double fps = src.fps();
  // A source with its own capture clock paces itself and says when each frame was captured.
  const bool own_clock = src.next_capture() != Clock::time_point{};
  auto next_due = std::chrono::steady_clock::now();
  try {
    cv::Mat frame;
    while (!sh.stop && (opt.frames == 0 || int64_t(seq) < opt.frames) && src.read(frame)) {
      // Capture time: the source's own capture instant, else when the source delivered the frame.
      const Clock::time_point captured = own_clock && src.last_capture() != Clock::time_point{}
                                             ? std::max(src.last_capture(), t0)
                                             : std::chrono::steady_clock::now();
      const int64_t t = std::chrono::duration_cast<std::chrono::nanoseconds>(captured - t0).count();
      cv::Mat raw = io::to_raw_mosaic(frame, manifest.bits);
      if (raw.cols != manifest.rig.cameras[c].in.width || raw.rows != manifest.rig.cameras[c].in.height)
        throw std::runtime_error(fmt::format("frames are {}x{}, the rig says {}x{}", raw.cols, raw.rows,
                                             manifest.rig.cameras[c].in.width,
                                             manifest.rig.cameras[c].in.height));
      {
        CameraQueue& cq = sh.queues[c];
        std::lock_guard lock(cq.m);
        if (static_cast<int>(cq.q.size()) >= opt.queue_frames)
          ++cq.dropped;  // the writer is behind: drop, the sequence number shows the gap
        else
          cq.q.push_back({std::move(raw), seq, t});
      }
      sh.cv.notify_one();
      ++seq;
      if (fps > 0 && !own_clock) {  // free-running at the source's own rate (as the live engine does)
        next_due += std::chrono::microseconds(long(1e6 / fps));
        const auto now = std::chrono::steady_clock::now();
        if (next_due < now) next_due = now;
        while (!sh.stop && std::chrono::steady_clock::now() < next_due)
          std::this_thread::sleep_for(std::min<std::chrono::steady_clock::duration>(
              next_due - std::chrono::steady_clock::now(), std::chrono::milliseconds(20)));
      }
    }
  } catch (const std::exception& e) {
    std::lock_guard lock(sh.m);
    if (sh.error.empty()) sh.error = fmt::format("camera {}: {}", manifest.rig.cameras[c].id, e.what());
  }
  --sh.running;
  sh.cv.notify_one();
}

}  // namespace

RecordSummary record(std::vector<std::unique_ptr<CameraSource>> sources, const std::filesystem::path& dir,
                     io::RecordingManifest manifest, const RecordOptions& opt) {
  if (std::string why; !opt.IsValid(&why)) throw std::invalid_argument("record: " + why);
  const int n = static_cast<int>(manifest.rig.cameras.size());
  if (static_cast<int>(sources.size()) != n)
    throw std::invalid_argument(fmt::format("record: {} sources for {} cameras", sources.size(), n));
  manifest.sensor_mode = opt.sensor_mode;
  manifest.clock_mhz = opt.clock_mhz;
  std::vector<double> rates;
  for (const auto& src : sources) rates.push_back(std::max(0.0, src->fps()));
  manifest.fps = opt.fps > 0 ? opt.fps : derived_recording_fps(rates);
  manifest.camera_fps.clear();
  for (const double f : rates) manifest.camera_fps.push_back(io::valid_recording_fps(f) ? f : 0);
  manifest.exposure_s = opt.exposure_s;
  io::RecordingWriter writer(dir, manifest, io::RecordingWriter::Options{opt.flush_interval_s});
  Shared sh;
  std::vector<CameraQueue> queues(n);
  sh.queues.swap(queues);
  sh.running = n;
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<std::thread> threads;
  for (int c = 0; c < n; ++c)
    threads.emplace_back([&, c] { capture(c, *sources[c], manifest, opt, sh, t0); });
  // The writer: this thread, round robin over the queues.
  RecordSummary sum;
  sum.frames.assign(n, 0);
  sum.fps = manifest.fps;
  sum.camera_fps = manifest.camera_fps;
  Progress progress("recording", opt.frames > 0 ? size_t(opt.frames) * n : 0, opt.progress && opt.frames > 0);
  auto should_stop = [&] {
    return (opt.stop && *opt.stop) ||
           (opt.duration_s > 0 &&
            std::chrono::steady_clock::now() - t0 > std::chrono::duration<double>(opt.duration_s));
  };
  auto has_error = [&] {
    std::lock_guard lock(sh.m);
    return !sh.error.empty();
  };
  for (int next = 0;;) {
    const bool sources_done = sh.running == 0;  // read before the scan: their last frames are in it
    Queued q;
    int cam = -1;
    for (int k = 0; k < n && cam < 0; ++k) {
      const int c = (next + k) % n;
      CameraQueue& cq = sh.queues[c];
      std::lock_guard lock(cq.m);
      if (!cq.q.empty()) {
        cam = c;
        q = std::move(cq.q.front());
        cq.q.pop_front();
      }
    }
    if (should_stop()) sh.stop = true;
    if (cam < 0) {
      if (sh.stop || sources_done || has_error()) break;
      std::unique_lock lock(sh.m);
      sh.cv.wait_for(lock, std::chrono::milliseconds(5));
      continue;
    }
    next = cam + 1;
    try {
      writer.append(cam, q.raw, q.seq, q.t_ns);
      ++sum.frames[cam];
      progress.step();
    } catch (const std::exception& e) {
      std::lock_guard lock(sh.m);
      sh.error = e.what();
      sh.stop = true;
      break;
    }
  }
  sh.stop = true;
  for (auto& t : threads) t.join();
  sum.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  sum.bytes = writer.bytes();
  for (int c = 0; c < n; ++c) sum.dropped.push_back(sh.queues[c].dropped);
  sum.error = sh.error;
  try {
    writer.close();
  } catch (const std::exception& e) {
    if (sum.error.empty()) sum.error = e.what();
  }
  return sum;
}

}  // namespace omma::live
