// `omma bench --stream`: latency and load of the live outputs, measured glass to glass with a flash.
//
// Every camera of the rig shows the same flash: a frame that is black or white, switching at known
// instants (every `flash_period_s`, on the steady clock). A reader notes the steady-clock instant
// at which it first holds a decoded panorama of the new level (its mean grey level past the middle);
// one latency sample = that instant - the switch. The cameras free-run at `camera_fps` with capture
// instant = the moment each frame is made, so a sample includes the wait for the next camera frame
// (mean 1/(2 camera_fps)) and for the next panorama tick (mean 1/(2 fps)), as a real camera would.
//
// Measured in one run, on this machine (readers in the same process, loopback only):
//   element  camera frame pushed into ommastitch's sink pads (appsrc) -> panorama out of its src pad
//            (appsink, no encoding): the GStreamer element (gst/), loaded from `plugin`
//   rtsp     the engine (omma run) -> rtsp:// sink (x264enc, gst-rtsp-server) -> a reader (rtspsrc
//            over TCP, avdec_h264)
//   mjpeg    the same run -> the live view's /stream.mjpg (http: sink) -> a reader (souphttpsrc,
//            multipartdemux, jpegdec)
//   readers  K = 1, 2, 4 ... max_readers simultaneous RTSP readers of one run (depayload only, no
//            decode, so the readers do not compete with the server for the two cores as decoders
//            would): each reader's frames/s and the stream's bit rate; the largest K whose slowest
//            reader keeps 95 % of the panorama rate. The cameras show a detailed texture that
//            scrolls (the flash's flat frames would cost the encoder and the network nothing).
// Needs GStreamer (live/gst.h); throws std::runtime_error without it.
#pragma once

#include <string>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "omma/core/rig.h"

namespace omma::bench {

struct StreamBenchOptions {
  cv::Size size{1080, 1080};  // panorama size (vr180)
  double fps = 30;            // panorama rate, 1/s
  double camera_fps = 50;     // the flash cameras' rate, 1/s (the thesis's sensors: 44-56)
  double seconds = 8;         // each latency measurement, s
  double flash_period_s = 1;  // time between two switches of the flash, s (> the latency)
  int max_readers = 16;       // load: readers at most (powers of two up to it)
  double reader_seconds = 3;  // load: the measuring time of each K, s
  // The GStreamer plugin file (libgstomma.so) for the element measurement; empty: the build tree's
  // (gst/ beside the running omma) or the installed one, else GStreamer's registry (GST_PLUGIN_PATH).
  std::string plugin;
  bool element = true, rtsp = true, readers = true;
  bool progress = true;  // one line per step on stderr
  bool IsValid(std::string* why = nullptr) const;
};

// Runs the measurements above on `rig` (its camera sizes; black/white frames need no texture).
// Returns {"element": {...}, "rtsp": {...}, "mjpeg": {...}, "readers": [...], "max_readers_full_rate",
// ...}: for each latency, "median_ms", "p90_ms", "min_ms", "max_ms", "samples" (switches seen),
// and the engine's own figures where one ran.
nlohmann::json run_stream_bench(const Rig& rig, const StreamBenchOptions& opt);

}  // namespace omma::bench
