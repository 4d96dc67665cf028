// Video files through FFmpeg's libraries (libavcodec, libavformat, libswscale): H.264 (libx264) and
// VP9 (libvpx-vp9), with the 360-degree metadata of the panorama's grid (spherical_video.h).
//
// Containers by extension (lower case): .mp4 .m4v (MP4, `moov` before `mdat`: "fast start", so a
// browser plays it while it downloads), .mov (QuickTime), .mkv (Matroska), .webm (WebM), .avi.
// Codecs: H.264 in mp4, m4v, mov, mkv, avi; VP9 in webm, mkv, mp4. `kAuto` picks VP9 for .webm and
// H.264 for every other container.
//
// Frames in: 8-bit BGR (CV_8UC3), 16-bit BGR (CV_16UC3, 0..65535) or 8-bit grey (CV_8UC1), all of
// the size the writer was opened with. They are converted (libswscale, ITU-R BT.709 matrix, limited
// "TV" range, as players assume for HD video) to 4:2:0 Y'CbCr, 8 bits (yuv420p, every player) or
// 10 bits (yuv420p10le: H.264 High 10, VP9 profile 2; few browsers play 10-bit H.264). 4:2:0 needs an
// even width and height.
//
// Time: frame i is shown at i / fps seconds (time base 1/fps for H.264 and VP9 streams; the
// container rescales it). A keyframe starts every gop_s seconds (rounded to whole frames, at least
// 1), so a player seeks to within gop_s.
//
// Files are written atomically: the frames go to a temporary file beside the target
// (.NAME.partial.EXT, see partial_path), which close() renames onto the target after the container's
// index and the spherical metadata are written; an encoder or write error (a full disk), abort() or
// the destructor without close() removes it and leaves the target as it was. A temporary file that a
// killed earlier writer left behind is removed when the next writer of that target opens (with a
// warning naming it).
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include <opencv2/core.hpp>

#include "omma/core/grid.h"

namespace omma::io {

enum class VideoCodec { kAuto, kH264, kVp9 };
std::string to_string(VideoCodec codec);                // "auto", "h264", "vp9"
VideoCodec parse_video_codec(const std::string& name);  // the names above; throws std::invalid_argument

// Encoder speed against size: x264's presets. VP9 maps them to libvpx's cpu-used 8 (ultrafast) .. 0
// (veryslow), with the realtime deadline from ultrafast to faster and the good deadline from fast on.
enum class VideoPreset {
  kUltrafast,
  kSuperfast,
  kVeryfast,
  kFaster,
  kFast,
  kMedium,
  kSlow,
  kSlower,
  kVeryslow
};
std::string to_string(VideoPreset preset);                // "ultrafast" .. "veryslow"
VideoPreset parse_video_preset(const std::string& name);  // the names above; throws std::invalid_argument

struct VideoOptions {
  VideoCodec codec = VideoCodec::kAuto;  // kAuto: from the file's extension (see above)
  // Quality as the encoder's constant rate factor (lower = better and larger; a step of 6 about
  // halves or doubles the bit rate). -1: the codec's default, 20 for H.264 (0..51, "visually
  // lossless" near 18) and 31 for VP9 (0..63, constant quality mode with no bit-rate cap).
  int crf = -1;
  double fps = 30;       // frames per second, > 0 and <= 1000 (the stream's time base is 1/fps)
  double gop_s = 2.0;    // keyframe interval, seconds (> 0): every round(gop_s * fps) frames, at least 1
  bool ten_bit = false;  // yuv420p10le instead of yuv420p
  // Encoder speed (see VideoPreset). Default faster: a live 1080x1080 panorama at 30 frames/s on
  // two cores.
  VideoPreset preset = VideoPreset::kFaster;
  int threads = 0;  // encoder threads (0: the encoder's choice, about one per core)
  bool IsValid(std::string* why = nullptr) const;
};

// The codec `options.codec` means for `path` (kAuto resolved); throws std::invalid_argument for an
// extension that is not a video container omma writes, or a codec that container does not hold.
VideoCodec resolve_video_codec(const std::filesystem::path& path, VideoCodec codec);

// True for the extensions VideoWriter writes (.mp4 .m4v .mov .mkv .webm .avi, any case).
bool is_video_path(const std::filesystem::path& path);

// The temporary file a writer of `path` writes before it renames it: .STEM.partial.EXT beside it.
std::filesystem::path partial_path(const std::filesystem::path& path);

// What close() wrote.
struct VideoSummary {
  std::filesystem::path path;
  std::string codec;    // "h264" or "vp9"
  std::string pix_fmt;  // "yuv420p" or "yuv420p10le"
  int width = 0, height = 0;
  long frames = 0;
  double fps = 0;
  int crf = 0;             // the CRF used (the codec's default resolved)
  bool spherical = false;  // 360-degree metadata written
};

class VideoWriter {
 public:
  // Opens `path` (its temporary file) for `size` frames. With `projection`, close() writes the
  // 360-degree metadata of PanoGrid{*projection, size} (spherical_video.h: MP4/MOV V1 and V2 boxes,
  // Matroska/WebM Projection elements); without it, a plain video. Throws std::invalid_argument for
  // invalid options, an unknown extension or an odd size, IoError if the folder is missing or the
  // file or encoder cannot be opened.
  VideoWriter(const std::filesystem::path& path, cv::Size size, const VideoOptions& options = {},
              std::optional<Projection> projection = std::nullopt);
  ~VideoWriter();  // without close(): abort()
  VideoWriter(const VideoWriter&) = delete;
  VideoWriter& operator=(const VideoWriter&) = delete;

  // Encodes one frame (see above for types and size). Throws IoError on an encoder or write error
  // (the temporary file is then removed), std::invalid_argument for a wrong size or type.
  void write(const cv::Mat& frame);
  // Flushes the encoder, writes the index and the spherical metadata and renames the file into
  // place. Throws IoError (the target untouched, the temporary file removed) if no frame was written
  // or anything fails.
  VideoSummary close();
  // Removes the temporary file; the target is untouched. Safe to call more than once.
  void abort();

  long frames() const;
  const std::filesystem::path& path() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace omma::io
