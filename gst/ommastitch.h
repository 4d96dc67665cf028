// The GStreamer plugin "omma" (libgstomma.so) and its element "ommastitch": N camera streams in, one
// panorama out, rendered by omma's live engine (src/omma/live/engine.h) inside the element.
//
// Pads:
//   sink_%u  (request, one per rig camera: pad sink_I is rig camera I, rig order; every pad sink_0 ..
//            sink_<N-1> must exist when the element goes to PAUSED; from then until READY a request
//            is refused: NULL and a warning on the bus saying why; a pad released then ends its
//            camera, as below, with the reason "its sink pad was released"). Caps may change
//            mid-stream (another format is converted on). video/x-raw in BGR, RGB, BGRx,
//            BGRA, RGBx, RGBA, GRAY8, I420, YV12, NV12, NV21, YUY2 or UYVY, converted to BGR with
//            GstVideoConverter as it arrives; width x height must be the rig camera's in.width x
//            in.height (other sizes: an error on the bus naming the pad, the camera and both sizes).
//   src      (always) video/x-raw, format BGR, RGB or I420 (as downstream prefers), the panorama's
//            width x height (property size), framerate = fps (0 -> 0/1, variable).
//
// Properties (set in NULL or READY; read when going to PAUSED):
//   rig                  rig file (JSON) or built-in rig name, as `omma run --rig` (required)
//   method, projection   as `omma run --method / --projection` (default linear, vr180)
//   size                 panorama "WxH", pixels (default 1080x1080, as omma run)
//   depth, photometric   depth-adaptive rendering (default off); the rig's photometric model (on)
//   fps                  panorama rate, frames/s (default 30; 0: render whenever a camera has a new
//                        frame; else 10^-3 .. 10^4)
//   sync                 (default on) a pad's buffer waits for its running time on the pipeline
//                        clock before it is published to the engine (as a sink with sync=true), so
//                        file sources play at their own rate; off: published on arrival
//   first-frame-timeout  s: a camera without a first frame by then is dropped (default 5)
//   stall-timeout        s: a pad without a buffer that long (while PLAYING) fails its camera as
//                        stalled; the camera is dropped (default 5)
//   threads              renderer threads (0: all)
//   cache-dir            map cache folder (default none: the map is compiled at every start)
//   stats                (read-only) JSON object of the latest "omma-stats" figures ("{}" before)
//
// Running: the element behaves as a live source towards downstream: READY->PAUSED loads the rig and
// checks pads and properties (a failure is an error on the bus and a failed state change) and
// returns NO_PREROLL; the engine thread starts at the first PAUSED->PLAYING (compiling the map
// first) and stops at PAUSED->READY (stop flag, every pad source woken, the thread joined; a map
// still compiling is waited for: the compile cannot be interrupted). Nothing is pushed while PAUSED
// (the engine goes on rendering; PTS stay increasing across a pause). Flush events on a sink pad
// discard its pending buffer; seeks on the src pad are refused (the panorama is live). Each
// camera is a free-running source with a latest-frame buffer: a pad's capture instant is the
// moment its buffer is published. Output buffers: PTS = the pipeline's running time when the
// panorama is pushed (without a clock: frame number / fps), DURATION = 1/fps (fps > 0). The src
// pad sends stream-start, caps and a TIME segment first, and EOS once every sink pad has had EOS.
// Latency query: live, minimum 1/fps.
//
// A pad that reaches EOS or stalls, or whose camera gets no first frame, drops its camera: the map
// is recompiled without it and the output continues; one warning on the bus names the camera and
// the reason, e.g. "ommastitch: camera 3 (sink_3) dropped: stalled: no buffer for 1 s; ..." (none
// for cameras that simply end, together with the last one). No camera delivering a first frame is
// the engine failing: "ommastitch: no panorama was rendered: ...". A wrong pad count, an unreadable rig, bad
// properties, unsupported caps, a downstream flow error or the engine failing are errors on the bus.
//
// Measurements: about twice a second an element message "omma-stats" with the double fields fps,
// render-ms, latency-ms (the engine's latency, engine.h: pad publish -> panorama rendered, mean over
// the last interval), push-latency-ms (mean over the last interval: the oldest pad-publish instant
// among the frames of a panorama -> its gst_pad_push returned) and the integer fields cameras-live,
// dropped-cameras, frames (panoramas so far).
//
// Logging: omma's own log (spdlog's default logger: on stdout, where it would corrupt a pipeline
// writing to fdsink) goes to the GStreamer debug log, category "ommastitch" (GST_DEBUG=ommastitch:5,
// spdlog level debug), once the plugin is loaded. spdlog's logger registry is one per process
// (libspdlog is a shared library, also in the omma libraries linked into the plugin), so this replaces
// the process's default logger; the plugin therefore does it only when the host has no say in it:
// not in a process named "omma" (omma bench --stream loads the plugin and keeps its own log), and
// only while the default logger is still spdlog's own (unnamed). The environment variable
// OMMA_GST_LOG decides instead: "gst" (always redirect) or "keep" (never touch spdlog).
#pragma once

#include <gst/gst.h>

G_BEGIN_DECLS

#define GST_TYPE_OMMA_STITCH (gst_omma_stitch_get_type())
G_DECLARE_FINAL_TYPE(GstOmmaStitch, gst_omma_stitch, GST, OMMA_STITCH, GstElement)

G_END_DECLS
