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
//                        {"camera": id, "file": "cam_07.h5", "width": W, "height": H}, ...],
//                        "complete": true once the recorder closed it normally}
//   DIR/cam_XX.h5       /frames  uint16 [N][H][W], chunked one frame per chunk: the RGGB mosaic,
//                                12-bit values in the low bits ((0,0) = R, (0,1) = G, (1,1) = B)
//                       /seq     uint64 [N]: the source's frame sequence number (gaps = frames the
//                                recorder dropped or the source skipped)
//                       /t_ns    int64 [N]: capture time, ns since start_unix_ns (steady clock);
//                                written LAST for each frame: the count of /t_ns entries >= 0 is
//                                the number of complete frames
//                       attributes: width, height, bits, bayer, camera
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
  // Every field within its bounds (the validators above), a valid rig, one distinct valid file name
  // per camera.
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
  int64_t t_ns = 0;  // the set's time (its earliest frame)
  std::vector<int64_t> frame;
};

struct CameraMatchStats {
  int64_t frames = 0;      // complete frames in the stream
  int64_t dropped = 0;     // gaps in the sequence numbers
  int64_t duplicates = 0;  // frames repeating the previous sequence number
  int64_t missing = 0;     // frame sets without a frame of this camera
  int64_t extra = 0;       // frames left out of every set (a second frame within one set)
};

struct MatchResult {
  std::vector<FrameSet> sets;
  std::vector<CameraMatchStats> cameras;
  int64_t complete_sets = 0;
};

// Matches frames of free-running cameras into sets by timestamp: frames are taken in time order,
// and a set gathers, at most one per camera, the frames within half a period (period_ns / 2) of its
// first frame. Throws RecordingError naming the camera if its timestamps go backwards, or if the
// sets would hold more than kMaxFrameSetEntries frame indices. Dropped counts saturate at INT64_MAX.
MatchResult match_frame_sets(const std::vector<std::vector<FrameMeta>>& metas, int64_t period_ns);

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

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  RecordingManifest manifest_;
  std::vector<std::vector<FrameMeta>> metas_;
  MatchResult match_;
};

}  // namespace omma::io
