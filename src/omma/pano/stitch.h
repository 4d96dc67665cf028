// The reference panorama stitcher (thesis §2.4.2, ch. 4): plain per-direction floating-point code.
// For every output pixel u: direction w_u from the grid (grid.h), camera search (eq. 2.3), pixel
// position in each contributing camera with the full camera model (eq. 5.21-5.26), bilinear sample
// of that camera's frame (pixel centres at integer + 0.5, conventions.h), weights of the chosen
// method (weights.h), weighted sum. The engine's compiled maps must reproduce this output.
//
// Images: frames may be 8U, 16U or 32F (values [0,1]) with 1 or 3 channels (BGR, as OpenCV reads);
// results are CV_32FC3 BGR in [0,1] (use omma::to_u8 to write 8-bit files).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/core/grid.h"
#include "omma/core/progress.h"
#include "omma/core/rig.h"
#include "omma/pano/method.h"
#include "omma/pano/surface.h"
#include "omma/pano/weights.h"

namespace omma::pano {

struct StitchOptions {
  Method method = Method::kMrf;
  PanoGrid grid;      // output projection and size (default vr180 1080x1080)
  BlendParams blend;  // observer point q, Gaussian sigma, SAD epsilon
  // The projection surface D(w) (surface.h, contributors.h): CV_32FC1 of the grid's size, mm from
  // q; empty = +infinity everywhere (the thesis's model, eq. 2.3-2.5). Every method works on any D.
  cv::Mat depth;
  bool progress = true;  // progress bar on stderr (also silenced by set_progress_enabled(false))

  // False (with the reason in *why) when a value lies outside the range the code relies on.
  bool IsValid(std::string* why = nullptr) const;
};

// Checks the inputs of every function below: at least one camera, one frame per camera, each the
// size the rig says, 1 or 3 channels. Throws std::invalid_argument with a clear message.
void check_frames(const Rig& rig, const std::vector<cv::Mat>& frames);

// Frames as CV_32FC3 in [0,1] (what the functions below use internally).
std::vector<cv::Mat> frames_to_float(const std::vector<cv::Mat>& frames);

// Bilinear sample of a CV_32FC3 image at continuous pixel coordinate px (centres at +0.5); the
// border pixels are replicated outside.
cv::Vec3f sample_bilinear(const cv::Mat& image32fc3, const Vec2& px);
// Gray level Y of BT.601 (the YCbCr luma the thesis uses in §4.3) of a BGR colour.
inline double luma(const cv::Vec3f& bgr) { return 0.114 * bgr[0] + 0.587 * bgr[1] + 0.299 * bgr[2]; }

// Every output pixel of options.grid with its contributors on the surface options.depth
// (contributors.h) and the method's geometric weights (weights.h; for sad the mrf prior of eq.
// 4.18), summing to 1: what stitch() blends, and what the engine's depth-adaptive map compiles.
// f(col, row, contributors, weights) is called once per pixel seen by a camera, from oneTBB
// threads (rows in blocks). `progress` (optional) is stepped once per finished row.
using PixelWeightsFn = std::function<void(int col, int row, const std::vector<Contributor>& cs,
                                          const std::vector<double>& weights)>;
void for_each_pixel_weights(const Rig& rig, const StitchOptions& options, const PixelWeightsFn& f,
                            Progress* progress = nullptr);

// The panorama, CV_32FC3 BGR [0,1], options.grid.height x options.grid.width; black where no
// camera sees the direction. sad uses the per-frame weights of eq. 4.17-4.18 (sad_weights).
cv::Mat stitch(const Rig& rig, const std::vector<cv::Mat>& frames, const StitchOptions& options);

}  // namespace omma::pano
