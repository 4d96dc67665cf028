// GStreamer in the live runtime: any GStreamer pipeline as a camera (gst:PIPELINE), and the panorama
// out over RTSP (gst-rtsp-server) and SRT (MPEG-TS). Built when GStreamer's development files are
// present (CMake option OMMA_GSTREAMER, AUTO by default; OMMA_HAVE_GSTREAMER says so); otherwise
// these specs throw SourceError / SinkError saying that this omma was built without GStreamer.
//
// Source spec (sources.h, one per camera or one pattern with {id}):
//   gst:PIPELINE   a gst-launch-1.0 style pipeline description whose last element delivers raw
//                  video of the camera's size (any format videoconvert takes): omma appends
//                  "! videoconvert ! video/x-raw,format=BGR ! appsink" (sync=true: files play at
//                  their rate; live sources at theirs) and keeps only the newest frame (a
//                  free-running camera); each camera its own pipeline. Frames are copied out as 8-bit
//                  BGR (the row stride respected); the first frame of another size than the rig
//                  camera's fails the camera with both sizes. The source's rate (CameraSource::fps)
//                  is the caps' framerate, 0 until the first frame or if variable. A pipeline that
//                  cannot be built (gst_parse_launch's message, e.g. no element "foo") fails
//                  opening; one that posts an error on its bus fails the camera with that error and
//                  the element's name; one that delivers no frame for SourceOptions::stall_s seconds
//                  fails it as stalled; the engine drops a failed camera and recompiles the map
//                  without it (engine.h). End of stream ends it (SourceOptions::loop: a flushing seek
//                  back to the start, or, where that brings no frame, a restart of the pipeline).
//                  Closing stops the pipeline (state NULL), waiting at most 2 s for one that is stuck.
//
// Sink specs (sinks.h):
//   rtsp://HOST:PORT/PATH   an RTSP server on HOST:PORT (HOST a numeric address or localhost, as
//                  SinkOptions::bind) serving H.264 (x264enc, SinkOptions::video's crf/gop/preset) at
//                  rtsp://HOST:PORT/PATH to any number of readers (one shared encoder)
//   srt://HOST:PORT[?mode=listener|caller]   H.264 in MPEG-TS over SRT: by default a listener on
//                  HOST:PORT that readers call (ffplay srt://HOST:PORT); mode=caller pushes to a
//                  listener there. A reader that disconnects does not stop the run.
// Neither RTSP's SDP nor MPEG-TS carries the Spherical Video metadata (io/spherical_video.h).
#pragma once

#include <memory>
#include <string>

#include <opencv2/core.hpp>

#include "omma/core/rig.h"
#include "omma/live/sinks.h"
#include "omma/live/sources.h"

namespace omma::live {

// True when this omma was built with GStreamer (the functions below work).
bool gstreamer_built();

// Initialises GStreamer once per process (thread-safe; later calls do nothing). Throws
// std::runtime_error if GStreamer cannot be initialised or was not built in.
void init_gstreamer();

// Opens a gst:PIPELINE source for `cam` (spec without the "gst:" prefix): frames of the camera's size,
// SourceOptions::stall_s. Throws SourceError.
std::unique_ptr<CameraSource> open_gst_source(const std::string& pipeline, const RigCamera& cam,
                                              const SourceOptions& opt);

// Opens an rtsp:// or srt:// sink of panoramas of `pano_size`. Throws SinkError.
std::unique_ptr<Sink> open_gst_sink(const std::string& spec, cv::Size pano_size, const SinkOptions& opt);

}  // namespace omma::live
