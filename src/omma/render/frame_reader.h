// Where the offline renderer's frames come from: a reader of raw frame sets (one mosaic per camera
// per set), so that rendering does not depend on any file format. io::RecordingReader (HDF5
// recordings, io/recording.h) is one.
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/core/rig.h"

namespace omma::render {

class FrameSetReader {
 public:
  virtual ~FrameSetReader() = default;
  virtual const Rig& rig() const = 0;      // the rig the frames were taken with
  virtual int bits() const = 0;            // significant bits per raw sample (e.g. 10 or 12)
  virtual int64_t frame_sets() const = 0;  // number of frame sets, indexed 0 .. frame_sets() - 1
  // The raw frames of set i (CV_16UC1 Bayer mosaics), rig order; an empty Mat where the set lacks
  // the camera (develop_frame_set makes it black: `omma render` gives it only planned sets, every
  // camera filled or the set skipped, io::plan_frame_sets). Throws (the reader's own error type) if
  // a frame cannot be read.
  virtual std::vector<cv::Mat> read_frame_set(int64_t i) const = 0;
};

}  // namespace omma::render
