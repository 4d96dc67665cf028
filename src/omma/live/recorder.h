// The recorder (thesis §7.2, done in software): N free-running camera sources, each in its own
// thread, their frames converted to 12-bit RGGB mosaics (recording.h, to_raw_mosaic), time-stamped
// when they arrive and numbered by the source's own count, queued, and written by one writer
// thread into a recording. A frame that finds its camera's queue full is dropped (its sequence
// number is skipped, so readers count it). A source that keeps its own capture clock (the
// simulator's free-running sensors: CameraSource::last_capture) gives its own capture instants as
// the timestamps and paces itself; others are paced at their fps() and stamped on arrival. Each
// camera's own rate (CameraSource::fps) goes into the manifest (camera_fps). Stops after `duration_s`, after
// `frames` frames per camera, when every source has ended, or when `stop` is set (SIGINT); a write error (a
// full disk) stops it too: what was written stays readable and the error is in the summary.
#pragma once

#include <atomic>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "omma/io/recording.h"
#include "omma/live/sources.h"

namespace omma::live {

inline constexpr double kDerivedRateFactor = 0.9;
inline constexpr double kFallbackFps = 30;

// The nominal rate RecordOptions::fps = 0 stands for, given the sources' own rates (0 = unknown).
double derived_recording_fps(const std::vector<double>& source_fps);

struct RecordOptions {
  double duration_s = 0;  // 0 = no limit
  int64_t frames = 0;     // frames per camera; 0 = no limit
  int queue_frames = 4;   // per camera
  double flush_interval_s = 0.5;
  std::string sensor_mode = "full";  // io::valid_sensor_mode
  double clock_mhz = 0;              // io::valid_recording_clock_mhz
  // Nominal rate (the frame-set period of io::match_frame_sets) written to the manifest:
  // io::valid_recording_fps, or 0: derived from the sources, kDerivedRateFactor x the slowest
  // source's fps() (so every free-running camera has a frame within half a period of every
  // frame-set instant, its jitter included), kFallbackFps if no source knows its rate.
  double fps = 0;
  double exposure_s = 0;  // written to the manifest when > 0 (io::kMaxExposureS)
  bool progress = true;
  const std::atomic<bool>* stop = nullptr;
  bool IsValid(std::string* why = nullptr) const;
};

struct RecordSummary {
  std::vector<int64_t> frames;   // written per camera
  std::vector<int64_t> dropped;  // dropped for a full queue per camera
  uint64_t bytes = 0;            // pixel bytes written
  double seconds = 0;
  std::string error;               // empty, or why the recording stopped early (disk full, a source)
  double fps = 0;                  // the nominal rate written (derived when RecordOptions::fps was 0)
  std::vector<double> camera_fps;  // each source's own rate (0 = unknown)
  double mb_per_s() const { return seconds > 0 ? bytes / 1e6 / seconds : 0; }
};

// Records `sources` (one per camera of manifest.rig, rig order) into `dir`. Throws RecordingError if
// the recording cannot be created; later errors end the recording and are reported in the summary.
RecordSummary record(std::vector<std::unique_ptr<CameraSource>> sources, const std::filesystem::path& dir,
                     io::RecordingManifest manifest, const RecordOptions& options);

}  // namespace omma::live
