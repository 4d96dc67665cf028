// Camera sources of the live engine (issue 5 point 3). Each source delivers the frames of ONE
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
//   sim:SCENE[@SPEED]   (all cameras) the simulator (sim/): SCENE = colon (the dome moving along
//                       the colon at SPEED mm/s, default 5), photo:PATH, usaf, checker (turning at
//                       SPEED deg/s, default 10); ideal cameras (no noise), one ray per pixel
//   PATTERN with {id}   expanded once per camera with its two-digit id, e.g. "cams/cam_{id}.mp4"
#pragma once

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/core/rig.h"

namespace omma::engine {

class SourceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class CameraSource {
 public:
  virtual ~CameraSource() = default;
  // Blocks until the next frame (8- or 16-bit, 1/3/4 channels); false at the end of the source.
  // Throws on a read failure. Called from the source's own thread only.
  virtual bool read(cv::Mat& frame) = 0;
  // The rate the source runs at, frames per second (0: as fast as it can deliver).
  virtual double fps() const = 0;
  virtual std::string describe() const = 0;
};

struct SourceOptions {
  double fps = 30;    // rate of image sequences, stills and pano: sources (0 = as fast as possible);
                      // video files and devices use their own rate unless `force_fps`
  bool force_fps = false;
  bool loop = false;  // image sequences and video files start again at their end
  // sim: sources deliver the sensor's raw 12-bit RGGB mosaic (CV_16UC1) with the simulator's
  // default sensor effects (noise, vignetting, gains) instead of ideal 8-bit frames (omma record).
  bool raw = false;
};

// Opens the sources for every camera of `rig` from the specs (see the file comment). Throws
// SourceError naming the spec if one cannot be opened or the count does not fit the rig.
std::vector<std::unique_ptr<CameraSource>> open_sources(const Rig& rig, const std::vector<std::string>& specs,
                                                        const SourceOptions& opt = {});

// A source that serves fixed frames (tests): `frames` repeated, `limit` frames in all (0 = endless),
// then it ends, or (fail = true) throws.
std::unique_ptr<CameraSource> still_source(cv::Mat frame, double fps, int limit = 0, bool fail = false);

}  // namespace omma::engine
