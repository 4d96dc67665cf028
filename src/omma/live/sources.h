// Camera sources of the live engine. Each source delivers the frames of ONE
// camera of the rig; the engine runs every source in its own thread, free-running at its own rate
// into a latest-frame buffer (engine.h).
//
// Source specs (`omma run --source`), either one per camera in rig order, or one spec for all:
//   DIR                 image sequence of one camera: DIR/*.png|jpg|jpeg|bmp|tif|tiff, name order
//   FILE.mp4|mkv|avi|mov|webm   video file of one camera (OpenCV videoio / FFmpeg)
//   /dev/videoN, v4l2:N V4L2 capture device of one camera
//   frames:DIR          (all cameras) a frames folder DIR/cam_XX.png (frames.h), repeated as stills
//   pano:IMAGE[@DEG_S]  (all cameras) views of an equirect-full 360x180 photograph turning about the
//                       dome axis at DEG_S degrees per second (default 10): an animated test scene
//   link:FILE or FILE.bin  raw sensor-link file of one camera (isp/link.h chips): decoded in a
//                       background thread, damaged rows concealed, developed by the ISP (isp.h)
//   sim:SCENE[@SPEED]   (all cameras) the simulator (sim/): SCENE = colon (the dome moving back and
//                       forth along the colon, peak SPEED mm/s, default 5), photo:PATH, usaf,
//                       checker (turning back and forth about the dome axis, peak SPEED deg/s,
//                       default 10), room[:PATH.json] (the rig moving back and forth along the
//                       room's corridor, +x, peak SPEED mm/s, default 300: sim/room.h); ideal
//                       cameras (no noise), one ray per pixel. The cameras
//                       free-run at their own rates with their own phase and jitter (sim_loop.h):
//                       a loop of the motion is pre-rendered at start-up, then played back
//   gst:PIPELINE        any GStreamer pipeline ending in raw video of the camera's size (gst.h)
//   PATTERN with {id}   expanded once per camera with its two-digit id, e.g. "cams/cam_{id}.mp4"
#pragma once

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/core/rig.h"

namespace omma::live {

// The fastest motion a simulated or panorama source takes ("sim:SCENE@SPEED", "pano:IMAGE@DEG_PER_S"):
// 10^4 mm/s or deg/s (28 turns a second; faster only blurs every frame).
inline constexpr double kMaxSimSpeed = 1e4;
// Frame rates (frames/s) that sources, the render loop and sinks take: 0 where an option says so
// (as fast as possible), else kMinRate .. kMaxRate (one frame every 1000 s .. 10^4 a second; their
// periods in ns stay far inside int64 and double precision).
inline constexpr double kMinRate = 1e-3;
inline constexpr double kMaxRate = 1e4;
inline bool valid_rate(double fps, bool zero_ok) {
  return (zero_ok && fps == 0) || (fps >= kMinRate && fps <= kMaxRate);
}

class SourceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

using Clock = std::chrono::steady_clock;

class CameraSource {
 public:
  virtual ~CameraSource() = default;
  // Blocks until the next frame (8- or 16-bit, 1/3/4 channels); false at the end of the source.
  // Throws on a read failure. Called from one engine thread at a time. The frame handed out must
  // not be modified by the source afterwards (a new buffer, or one that never changes): the engine
  // keeps a reference to it instead of copying.
  virtual bool read(cv::Mat& frame) = 0;
  // The rate the source runs at, frames per second (0: as fast as it can deliver).
  virtual double fps() const = 0;
  // Sources that model a free-running sensor keep their own clock: the instant (steady_clock) at
  // which their next frame is captured; the engine calls read() then. time_point{} (the default):
  // the engine paces the source by fps().
  virtual Clock::time_point next_capture() { return {}; }
  // The capture instant of the frame the last read() returned; time_point{} (the default): the
  // moment read() returned. Frame ages (the engine's latency) count from this instant.
  virtual Clock::time_point last_capture() const { return {}; }
  virtual std::string describe() const = 0;
  // True if the frames already have the rig camera's photometric model applied (the sensor-link
  // source develops raw frames with the model as the ISP's flat gain, isp/photometric.h), so the
  // engine must not apply it again.
  virtual bool photometric_applied() const { return false; }
};

// The simulated sensors of sim: sources (sim_loop.h). The thesis's cameras free-run at 44-56 fps,
// each on its own oscillator (§5.1, Table 5.1): each camera's rate is drawn once, uniformly in
// [fps_min, fps_max], its phase uniformly in one period, and each frame's capture instant is
// jittered about the camera's clock.
struct SimCameraOptions {
  double fps_min = 44, fps_max = 56;  // frames/s
  double jitter_ms = 0.5;             // standard deviation of a frame's capture instant, ms (clipped
                                      // to a quarter period)
  double loop_s = 1;                  // the motion's period = the pre-rendered loop's length, s
  double max_memory_mb = 1024;        // the loop is shortened (with a warning) to fit, MB
  uint64_t seed = 1;                  // rates, phases and jitter
  bool progress = true;               // progress line on stderr while pre-rendering
  bool IsValid(std::string* why = nullptr) const;
};

struct SourceOptions {
  double fps = 30;  // rate of image sequences, stills and pano: sources (0 = as fast as possible);
                    // video files and devices use their own rate unless `force_fps`
  bool force_fps = false;
  bool loop = false;     // image sequences and video files start again at their end
  SimCameraOptions sim;  // sim: sources (their rates are the sensors' own, not `fps`)
  double stall_s = 5;    // gst: sources (gst.h): no new frame for this long fails the camera, s (> 0)
  bool IsValid(std::string* why = nullptr) const;  // fps >= 0, sim valid
};

// Opens the sources for every camera of `rig` from the specs (see the file comment). Throws
// SourceError naming the spec if one cannot be opened or the count does not fit the rig.
std::vector<std::unique_ptr<CameraSource>> open_sources(const Rig& rig, const std::vector<std::string>& specs,
                                                        const SourceOptions& opt = {});

// A source that serves fixed frames (tests): `frames` repeated, `limit` frames in all (0 = endless),
// then it ends, or (fail = true) throws.
std::unique_ptr<CameraSource> still_source(cv::Mat frame, double fps, int limit = 0, bool fail = false);

}  // namespace omma::live
