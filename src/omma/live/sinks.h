// Sinks of the live engine. Sink specs (`omma run --sink`):
//   FILE.mp4 | .mov | .mkv | .webm | .avi   video file (io/video_writer.h, FFmpeg's libraries:
//                                    H.264 in mp4/mov/mkv/avi, VP9 in webm, or as SinkOptions::video
//                                    says; MP4 "fast start"), written to a temporary file
//                                    (.NAME.partial.EXT beside it) and renamed into place at the end;
//                                    an encoder or write error (full disk) removes it; with the
//                                    Spherical Video V1 + V2 metadata of SinkOptions::projection
//                                    (io/spherical_video.h; mkv/webm V2 only, avi none)
//   -                                raw frames on stdout for a pipe into ffmpeg: each panorama
//                                    W x H x 3 bytes, BGR, rows top to bottom (rawvideo bgr24), the
//                                    size and rate stated on stderr at the start; nothing else is
//                                    written to stdout (`omma run` refuses --json with it)
//   png:DIR  or  DIR/                PNG sequence DIR/frame_000000.png ... (each written atomically,
//                                    with the GPano XMP with SinkOptions::spherical_metadata)
//   cam:ID:SINK                      camera ID's own frames passed through to SINK (a video file or
//                                    PNG folder) instead of the panorama: the ASIC's output
//                                    multiplexer (thesis §6.3)
//   http:PORT  or  http://HOST:PORT  live view on SinkOptions::bind (default 127.0.0.1; HOST, if
//                                    given, is that address): `/` a 360-degree viewer page
//                                    (Pannellum, embedded in the binary: web/), `/stream.mjpg` the
//                                    MJPEG stream, `/frame.jpg` the latest frame, `/stats.json` the
//                                    running statistics (the engine's progress JSON, engine.h, and
//                                    `viewers`), `/config.json` projection and size.
//                                    At most `max_streams` viewers stream at once (the next one gets
//                                    503); they have their own worker threads, so they never block
//                                    the page, the stats or a single frame.
//                                    Token (SinkOptions::token; by default required when the address
//                                    is not loopback): every resource but the viewer's own files
//                                    (/viewer/..., /favicon.ico) needs `?token=T` (T: 32 hex digits,
//                                    128 bits of std::random_device), else 403; compared in constant
//                                    time. The page passes its own token on to its requests. The
//                                    URL with the token is logged at warning level (shown even with
//                                    --quiet); a non-loopback address is warned about.
//   rtsp://HOST:PORT/PATH            RTSP server (H.264) at that URL (gst.h)
//   srt://HOST:PORT[?mode=...]       H.264 in MPEG-TS over SRT, listener by default (gst.h)
// Opening a sink checks that it can be written (folder creatable, writer opens, port free) and
// throws SinkError otherwise; a failed or aborted run leaves no partial video file behind. An
// interrupted run (SIGINT, SIGTERM: `omma run` stops cleanly) leaves a playable file; one killed
// outright leaves only the temporary file, which the next run writing that output removes (with
// a warning naming it).
#pragma once

#include <memory>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "omma/core/grid.h"
#include "omma/core/rig.h"
#include "omma/io/video_writer.h"
#include "omma/render/compiled_map.h"

namespace omma::live {

class SinkError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Sink {
 public:
  virtual ~Sink() = default;
  // One rendered panorama; `store` holds the camera frames it was made from.
  virtual void write(const cv::Mat& panorama, const render::FrameStore& store) = 0;
  // The run ended normally: make the output final (rename the video into place).
  virtual void finish() {}
  // The run failed: remove partial output.
  virtual void abort() {}
  virtual void set_stats(const nlohmann::json& stats) {}
  virtual std::string describe() const = 0;
};

// Live view: when the URLs need a token (see above).
enum class TokenMode {
  kAuto,    // required when the address is not loopback (is_loopback_address)
  kRandom,  // always required
  kNone,    // never (also on the network: anyone who reaches the port sees the panorama)
};

struct SinkOptions {
  double fps = 30;        // frame rate written into video files
  int jpeg_quality = 80;  // live view
  int max_streams = 8;    // live view: concurrent /stream.mjpg viewers (the page is one)
  Projection projection =
      Projection::kVr180;  // the panoramas' projection (live view: how the viewer shows them)
  // Video files and PNG frames carry the 360-degree metadata of `projection` (Spherical Video V1
  // and V2: io/spherical_video.h; GPano XMP: io/metadata.h); off: plain files (and always for
  // cam:ID pass-through sinks).
  bool spherical_metadata = false;
  // Video files: codec, quality, keyframe interval, bit depth, speed (their rate is `fps` above).
  io::VideoOptions video;
  // Live view: the address to listen on, a numeric IPv4 or IPv6 address ("0.0.0.0", "::": every
  // interface) or "localhost" (= 127.0.0.1), and when its URLs need a token.
  std::string bind = "127.0.0.1";
  TokenMode token = TokenMode::kAuto;
  // fps > 0, jpeg_quality 1..100, max_streams >= 1, bind a numeric address or localhost, video
  bool IsValid(std::string* why = nullptr) const;
};

// Whether `address` (as SinkOptions::bind) is a loopback address: IPv4 127.0.0.0/8, IPv6 ::1 or
// ::ffff:127.0.0.0/104 (RFC 1122, RFC 4291), or "localhost". False for anything else, the
// wildcards 0.0.0.0 and :: (every interface) included, and for what is not an address.
bool is_loopback_address(const std::string& address);
// A fresh live view token: 128 bits of std::random_device, as 32 lowercase hex digits.
std::string random_token();
// Token parsing for the command line: "auto", "random", "none" (std::invalid_argument otherwise).
TokenMode parse_token_mode(const std::string& text);

// The port of a network sink spec (http:PORT, http://HOST:PORT, rtsp://, srt://): TEXT as a number
// 1..65535, else SinkError "sink 'SPEC': port 'TEXT': expected a port number 1-65535".
int parse_port(const std::string& spec, const std::string& text);

// Opens one sink. `pano_size` is the panorama size; the rig gives camera sizes for cam:ID sinks.
std::unique_ptr<Sink> open_sink(const std::string& spec, const Rig& rig, cv::Size pano_size,
                                const SinkOptions& opt = {});

}  // namespace omma::live
