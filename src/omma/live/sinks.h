// Sinks of the live engine. Sink specs (`omma run --sink`):
//   FILE.mp4 | FILE.mkv | FILE.avi   video file (OpenCV VideoWriter: mp4v in mp4, MJPG in mkv/avi),
//                                    written to a temporary file (.NAME.partial.EXT beside it),
//                                    checked (it opens and holds every frame) and renamed into
//                                    place at the end; a failed check (full disk) removes it;
//                                    mp4 with Spherical Video V2 metadata (SinkOptions)
//   png:DIR  or  DIR/                PNG sequence DIR/frame_000000.png ... (each written atomically,
//                                    with the GPano XMP with SinkOptions::spherical_metadata)
//   cam:ID:SINK                      camera ID's own frames passed through to SINK (a video file or
//                                    PNG folder) instead of the panorama: the ASIC's output
//                                    multiplexer (thesis §6.3)
//   http:PORT  or  http://127.0.0.1:PORT   live view on 127.0.0.1: `/` a 360-degree viewer page
//                                    (Pannellum, embedded in the binary: web/), `/stream.mjpg` the
//                                    MJPEG stream, `/frame.jpg` the latest frame, `/stats.json` the
//                                    running statistics, `/config.json` projection and size.
//                                    At most `max_streams` viewers stream at once (the next one gets
//                                    503); they have their own worker threads, so they never block
//                                    the page, the stats or a single frame.
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

struct SinkOptions {
  double fps = 30;        // frame rate written into video files
  int jpeg_quality = 80;  // live view
  int max_streams = 8;    // live view: concurrent /stream.mjpg viewers (the page is one)
  Projection projection =
      Projection::kVr180;  // the panoramas' projection (live view: how the viewer shows them)
  // MP4 files and PNG frames carry the 360-degree metadata of `projection` (omma/io/metadata.h:
  // Spherical Video V2, GPano XMP); off: plain files (and always for cam:ID pass-through sinks).
  bool spherical_metadata = false;
  bool IsValid(std::string* why = nullptr) const;  // fps > 0, jpeg_quality 1..100, max_streams >= 1
};

// Opens one sink. `pano_size` is the panorama size; the rig gives camera sizes for cam:ID sinks.
std::unique_ptr<Sink> open_sink(const std::string& spec, const Rig& rig, cv::Size pano_size,
                                const SinkOptions& opt = {});

}  // namespace omma::live
