// Raw multi-camera recordings (Giga-Eye, thesis §7.1-7.2: 12-bit raw Bayer, uncompressed, per
// camera; the thesis writes raw sectors of SSDs and matches frames by index).
//
// Container: HDF5 (a documented, self-describing format that h5py, h5dump, MATLAB and HDFView
// read), one file per camera plus a JSON manifest. Chosen over Matroska/FFV1 by measurement
// (docs/results/giga_bench.md): the recorder must keep up with the disk, and FFV1's lossless coding of
// 12-bit mosaics runs far below the disk's sequential rate on this 2-core machine; HDF5 also gives
// random access by frame for free (what an MPI renderer needs) and crash safety through SWMR.
//
//   DIR/manifest.json   {"format": "omma-recording", "version": 1, "container": "hdf5",
//                        "rig": {omma-rig}, "sensor_mode": "skip1", "clock_mhz": 66, "fps": 30,
//                        "bits": 12, "bayer": "RGGB", "start_unix_ns": ..., "streams": [
//                        {"camera": id, "file": "cam_07.h5", "width": W, "height": H,
//                         "fps": 47 (optional: the camera's own nominal rate, 0 = not known),
//                         "exposure_s": 0.01 (optional)}, ...],
//                        "complete": true once the recorder closed it normally}
//   DIR/cam_XX.h5       /frames  uint16 [N][H][W], chunked one frame per chunk: the RGGB mosaic,
//                                12-bit values in the low bits ((0,0) = R, (0,1) = G, (1,1) = B)
//                       /seq     uint64 [N]: the source's frame sequence number (gaps = frames the
//                                recorder dropped or the source skipped)
//                       /t_ns    int64 [N]: capture time, ns since start_unix_ns (steady clock);
//                                written LAST for each frame: the count of /t_ns entries >= 0 is
//                                the number of complete frames
//
// Self-describing streams: each cam_XX.h5 alone says what it holds (h5dump -A, h5py's .attrs).
// Attribute naming follows NeXus (NXdetector, NXlog): a `units` attribute on datasets (UDUNITS
// strings), `long_name`, NXlog's `start` (ISO 8601 epoch of relative times) on the time dataset,
// NXdetector's field names where NeXus has one (bit_depth_readout, count_time = exposure,
// frame_time = 1 / frame rate); the layout stays the flat three datasets (no NXentry groups, so
// readers of version-1 streams keep working). The Bayer pattern also in DNG's form (CFAPattern,
// 0 = R, 1 = G, 2 = B, row by row over a CFARepeatPatternDim of 2 x 2). Root attributes:
//     camera (int64: the camera's id), camera_index (int64: its position in the rig, rig order),
//     width, height (int64, pixels), bits and bit_depth_readout (int64: significant bits),
//     bayer_pattern ("RGGB"), cfa_pattern (uint8 [4] = 0 1 1 2), cfa_repeat_pattern_dim
//     (int64 [2] = 2 2), frame_rate_hz (float64: the camera's own nominal rate, 0 = not known),
//     frame_time (float64, s: 1 / frame_rate_hz, 0 = not known), frame_set_rate_hz (float64: the
//     recording's nominal rate `fps`, the frame-set period of match_frame_sets), count_time
//     (float64, s: exposure; only when known), sensor_mode (string), sensor_width, sensor_height
//     (int64, pixels: the mode's resolution), clock_mhz (float64, 0 = not given), time_base
//     (string: what t_ns counts from), start_unix_ns (int64), start_time (ISO 8601 UTC string),
//     rig (string: the whole omma-rig JSON of the recording, so one stream is unambiguous),
//     format ("omma-recording"), version (int64, 1), creator ("omma X.Y.Z")
//   /frames attributes: units "counts", long_name, bayer_pattern
//   /seq attributes:    units "1", long_name
//   /t_ns attributes:   units "ns", long_name, start (ISO 8601 UTC of start_unix_ns), start_unix_ns,
//                       time_base
// Readers need none of the added attributes: streams written before them (camera, width, height,
// bits only) read as before.
// Files are written in SWMR mode (HDF5 single-writer / multiple-reader) and flushed every
// flush_interval (0.5 s): a recorder killed at any moment leaves every stream readable up to its
// last flush (readers open with SWMR-read; plain h5dump needs `h5clear -s FILE` first).
//
// Recordings are untrusted input: the reader believes nothing the folder says that it can check, and
// every refusal is a RecordingError naming the camera and the file, within seconds:
//   - the manifest is parsed strictly: integers must be JSON integers in range (no floats, no
//     booleans, nothing wrapped), numbers finite, each field within the bounds below; the writer
//     and `omma record` check the same fields with the same functions (valid_recording_fps ...), so
//     they never write a recording the reader refuses;
//   - manifest.json and the streams must be regular files in the folder (a symbolic link must point
//     to one in the folder; FIFOs, devices and folders are refused before anything opens them), the
//     stream names plain (no '/', no "..", no control character or NUL) and distinct;
//   - a stream holds exactly the hard-linked datasets frames, seq and t_ns of the types, ranks and
//     chunking above (no external or soft links, no external storage, no virtual datasets, no
//     filters), and its attributes camera, width, height and bits equal its camera's in the
//     manifest (its position in the manifest cannot hand one camera's frames to another);
//   - extents are read as 64-bit and checked against the manifest and the file's size (N frames of
//     H x W take N * (2 H W + 16) bytes of an uncompressed stream) before anything is allocated;
//   - HDF5's metadata reads are retried at most kRecordingReadAttempts times;
//   - every frame read (RecordingReader::read, thus `omma recording check` and `omma render`) must
//     be stored in the file and fit the manifest's bit depth.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "omma/core/rig.h"
#include "omma/render/frame_reader.h"

namespace omma::io {

class RecordingError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Bounds of the manifest's fields, the same for the writer, the reader and `omma record`.
inline constexpr double kMinRecordingFps = 1e-3;  // one frame in 1000 s
inline constexpr double kMaxRecordingFps = 1e4;
inline constexpr double kMaxRecordingClockMhz = 1e5;  // 0 = not given
inline constexpr int kMinRecordingBits = 8;
inline constexpr int kMaxRecordingBits = 16;
inline constexpr size_t kMaxSensorModeBytes = 1024;
inline constexpr size_t kMaxStreamNameBytes = 255;
inline constexpr double kMaxExposureS = 1e3;
// At most this many HDF5 reads of one piece of metadata (H5Pset_metadata_read_attempts): HDF5's
// SWMR default, 100 with a doubling back-off, retried one damaged checksum for more than 10 minutes;
// 16 end within milliseconds and still ride out a read that races the writer's flush.
inline constexpr unsigned kRecordingReadAttempts = 16;
// Frame sets x cameras the matcher may hold (8 bytes each): 2^28 = 2 GiB, e.g. 56 hours of 44
// cameras at 30 fps.
inline constexpr int64_t kMaxFrameSetEntries = int64_t(1) << 28;

// One validator per manifest field: true, or false with the reason in *why.
bool valid_recording_fps(double fps, std::string* why = nullptr);             // [kMin, kMaxRecordingFps]
bool valid_recording_clock_mhz(double mhz, std::string* why = nullptr);       // [0, kMaxRecordingClockMhz]
bool valid_recording_bits(int64_t bits, std::string* why = nullptr);          // [kMin, kMaxRecordingBits]
bool valid_sensor_mode(const std::string& mode, std::string* why = nullptr);  // printable, <= 1024 bytes
bool valid_start_unix_ns(int64_t ns, std::string* why = nullptr);             // >= 0
// A stream file name: 1..255 bytes, no '/', no "..", no control character (NUL included).
bool valid_stream_file_name(const std::string& name, std::string* why = nullptr);

struct RecordingManifest {
  Rig rig;
  std::string sensor_mode = "full";
  double clock_mhz = 0;  // pixel clock of the sensors (informational)
  double fps = 30;       // nominal frame rate: the matching period is 1 / fps
  int bits = 12;
  int64_t start_unix_ns = 0;
  bool complete = false;
  std::vector<std::string> files;  // per camera (rig order)
  // Per camera (rig order), the camera's own nominal rate in frames/s as its source reports it
  // (free-running sensors differ: 44-56 fps in the thesis), 0 where not known; empty: none known.
  std::vector<double> camera_fps;
  double exposure_s = 0;  // exposure time of every camera, s; 0 = not known
  // Every field within its bounds (the validators above), a valid rig, one distinct valid file name
  // per camera, camera_fps empty or one rate (0 or valid_recording_fps) per camera, exposure_s in
  // [0, kMaxExposureS].
  bool IsValid(std::string* why = nullptr) const;
  nlohmann::json to_json() const;
  // Strict (header comment); the result IsValid. Throws RecordingError.
  static RecordingManifest from_json(const nlohmann::json& j);
};

struct FrameMeta {
  uint64_t seq = 0;
  int64_t t_ns = 0;
};

// Converts a source frame to the recorded mosaic (CV_16UC1, `bits` significant bits): 1-channel
// 16-bit frames are raw already (values must fit `bits`); 3-channel frames are mosaicked RGGB and
// scaled (8-bit v -> v * (2^bits - 1) / 255, rounded; 16-bit v -> v >> (16 - bits)).
cv::Mat to_raw_mosaic(const cv::Mat& frame, int bits = 12);

class RecordingWriter {
 public:
  struct Options {
    double flush_interval_s = 0.5;
  };
  // Creates DIR (must not exist or be an empty folder) with the manifest and one stream per camera
  // (cam_XX.h5, replacing manifest.files). Throws std::invalid_argument before it creates anything
  // unless the manifest IsValid.
  RecordingWriter(const std::filesystem::path& dir, RecordingManifest manifest, Options options);
  RecordingWriter(const std::filesystem::path& dir, RecordingManifest manifest)
      : RecordingWriter(dir, std::move(manifest), Options{}) {}
  ~RecordingWriter();  // closes (without marking the recording complete)
  // Appends one frame of camera index `cam` (rig order): CV_16UC1 of the camera's size. Flushes
  // when flush_interval has passed. Throws RecordingError (e.g. disk full); what was flushed stays.
  void append(int cam, const cv::Mat& raw, uint64_t seq, int64_t t_ns);
  void flush();
  // Flushes, closes the streams and marks the manifest complete.
  void close();
  uint64_t bytes() const { return bytes_; }  // pixel bytes appended
  int64_t frames(int cam) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  uint64_t bytes_ = 0;
};

// Frame sets: one frame (index into its stream) per camera, -1 where the camera has none.
struct FrameSet {
  int64_t t_ns = 0;  // the set's instant (a tick of the frame-set clock, match_frame_sets)
  std::vector<int64_t> frame;
};

struct CameraMatchStats {
  int64_t frames = 0;      // complete frames in the stream
  int64_t dropped = 0;     // gaps in the sequence numbers
  int64_t duplicates = 0;  // frames repeating the previous sequence number
  int64_t missing = 0;     // frame sets without a frame of this camera
  int64_t extra = 0;       // frames left out of every set (a faster camera's frames between the
                           // sets' instants, duplicates, frames before the first or after the last set)
};

struct MatchResult {
  std::vector<FrameSet> sets;
  std::vector<CameraMatchStats> cameras;
  int64_t complete_sets = 0;
};

// Matches frames of free-running cameras into sets by nearest timestamp on a frame-set clock of
// period P = period_ns (the recording's nominal rate):
//   - the sets' instants are T_k = T_0 + k P. T_0 is the earliest instant at which every camera can
//     have a frame within P / 2: max(first frames) - P / 2, but not before min(first frames); if the
//     cameras' first frames are more than P apart (a camera started late) T_0 = min(first frames)
//     and the sets before the late camera's first frame honestly lack it. The last set is the last
//     instant within P / 2 of every camera's last frame (min(last frames) + P / 2), or, if the last
//     frames are more than P apart (a camera stopped early), within P / 2 of the latest frame;
//   - set k takes, per camera, its frame nearest T_k among those within P / 2 of it (|t - T_k| <=
//     P / 2), not yet in a set and not repeating the previous frame's sequence number; a camera
//     without one is missing from the set. An instant with no frame of any camera is no set.
// So a camera whose frames are never more than P apart (its rate above the nominal rate, jitter
// included) is in every set: free-running cameras of different rates give complete sets whenever
// the nominal rate is below the slowest camera's (`omma record` picks 0.9 x the slowest by
// default). Frames of a faster camera between the instants are left out (counted as extra).
// Throws RecordingError naming the camera if its timestamps go backwards or are negative, or if
// the sets would hold more than kMaxFrameSetEntries frame indices. Dropped counts saturate at
// INT64_MAX.
MatchResult match_frame_sets(const std::vector<std::vector<FrameMeta>>& metas, int64_t period_ns);

// What a renderer does with a frame set that lacks cameras (`omma render --incomplete`):
//   kSkip  leave the set out (no panorama for it);
//   kHold  fill each missing camera with its last frame captured at or before the set's instant
//          when that frame is at most max_hold_age_ns old (the set's instant minus the frame's
//          capture time), as a live viewer shows each camera's latest frame; a set that still lacks
//          a camera (none, or too old) is skipped;
//   kFail  refuse the whole range (RecordingError naming the first incomplete set).
enum class IncompletePolicy { kSkip, kHold, kFail };
IncompletePolicy parse_incomplete_policy(
    const std::string& s);  // "skip" | "hold" | "fail"; throws invalid_argument
const char* incomplete_policy_name(IncompletePolicy p);

struct FrameSetPlanOptions {
  IncompletePolicy policy = IncompletePolicy::kHold;
  int64_t max_hold_age_ns = 0;  // kHold: oldest frame held, ns; 0 = two frame-set periods (2 P)
  bool IsValid(std::string* why = nullptr) const;  // max_hold_age_ns >= 0
};

// The frame sets a renderer makes from sets first..last (inclusive) of a match, every camera filled.
struct PlannedSet {
  int64_t set = 0;                   // index in MatchResult::sets (outputs are named after it)
  std::vector<int64_t> frame;        // per camera (rig order), its frame index; all >= 0
  std::vector<int64_t> held_age_ns;  // per camera: 0, or the age of the frame held in its place
};
struct FrameSetPlan {
  IncompletePolicy policy = IncompletePolicy::kHold;
  int64_t max_hold_age_ns = 0;  // resolved (never 0 for kHold)
  std::vector<PlannedSet> sets;
  int64_t considered = 0;             // sets first..last
  int64_t complete = 0;               // of them complete as matched
  int64_t incomplete = 0;             // considered - complete
  int64_t held_sets = 0;              // incomplete sets completed by holding frames
  int64_t held_frames = 0;            // frames held in all
  int64_t skipped = 0;                // incomplete sets left out
  int64_t max_held_age_ns = 0;        // the oldest frame held
  std::vector<int64_t> skipped_sets;  // their indices (the first 1000)
  nlohmann::json to_json() const;     // {"policy", "max_hold_age_s", "frame_sets", "complete", ...}
};
// Throws RecordingError under kFail if a set in the range lacks a camera ("frame set 12 lacks
// camera(s) 3, 7; 5 of 40 frame sets are incomplete ...").
FrameSetPlan plan_frame_sets(const MatchResult& match, const std::vector<std::vector<FrameMeta>>& metas,
                             int64_t first, int64_t last, int64_t period_ns,
                             const FrameSetPlanOptions& options, const std::vector<int>& camera_ids = {});

// Whether `rig` can render a recording made with rig `recorded` (its manifest's rig): "" if so, else
// the reason, to follow the rig's name in a message ("has 3 cameras, the recording 4", "camera 7 is
// 640x480, the recording's 1280x960 (another sensor mode)"): the same number of cameras, each (rig
// order) of the same width and height.
std::string rig_mismatch(const Rig& rig, const Rig& recorded);

// Random access to a recording (SWMR-read: also while it is being written, or after a crash).
class RecordingReader : public render::FrameSetReader {
 public:
  // Throws RecordingError with a clear message naming the camera and the file: missing, invalid or
  // lying manifest, missing, truncated, damaged or forged stream (header comment), mismatched sensor
  // mode (a stream's size is not its camera's), backwards timestamps.
  explicit RecordingReader(const std::filesystem::path& dir);
  ~RecordingReader() override;
  const RecordingManifest& manifest() const { return manifest_; }
  int cameras() const { return static_cast<int>(metas_.size()); }
  int64_t frames(int cam) const { return static_cast<int64_t>(metas_[cam].size()); }
  const std::vector<FrameMeta>& meta(int cam) const { return metas_[cam]; }
  // Frame i of camera index cam (CV_16UC1 mosaic). Throws RecordingError naming the camera and the
  // file if it cannot be read, is not stored in the file, or holds a value above 2^bits - 1.
  cv::Mat read(int cam, int64_t i) const;
  const MatchResult& match() const { return match_; }
  // render::FrameSetReader: the manifest's rig and bits, the matched frame sets.
  const Rig& rig() const override { return manifest_.rig; }
  int bits() const override { return manifest_.bits; }
  int64_t frame_sets() const override { return static_cast<int64_t>(match_.sets.size()); }
  // The raw frames of frame set i, rig order; an empty Mat where the set lacks the camera.
  std::vector<cv::Mat> read_frame_set(int64_t i) const override;
  // The raw frames with these indices (one per camera, rig order; -1 gives an empty Mat).
  std::vector<cv::Mat> read_frames(const std::vector<int64_t>& frame) const;
  int64_t period_ns() const;  // the frame-set period: 1 / manifest().fps
  // plan_frame_sets over sets first..last of this recording (camera ids in its messages).
  FrameSetPlan plan(int64_t first, int64_t last, const FrameSetPlanOptions& options) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  RecordingManifest manifest_;
  std::vector<std::vector<FrameMeta>> metas_;
  MatchResult match_;
};

// A recording's frame sets as planned (plan_frame_sets): item i is planned set i (its output is
// named after plan.sets[i].set), every camera filled, held frames in place of missing ones. Both
// references must outlive it.
class PlannedFrameSets : public render::FrameSetReader {
 public:
  PlannedFrameSets(const RecordingReader& rec, const FrameSetPlan& plan) : rec_(rec), plan_(plan) {}
  const Rig& rig() const override { return rec_.rig(); }
  int bits() const override { return rec_.bits(); }
  int64_t frame_sets() const override { return int64_t(plan_.sets.size()); }
  std::vector<cv::Mat> read_frame_set(int64_t i) const override {
    return rec_.read_frames(plan_.sets.at(size_t(i)).frame);
  }

 private:
  const RecordingReader& rec_;
  const FrameSetPlan& plan_;
};

}  // namespace omma::io
