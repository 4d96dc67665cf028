// Projection surfaces D(w) for the stitcher: the distance, from the observer q, at which
// each panorama direction w meets the scene. The geometry of sampling a camera on the surface is in
// contributors.h (X = q + D w, camera i's ray X - c_i); this file holds the depth maps themselves.
//
// A depth map is CV_32FC1, the panorama grid's size (row-major like the panorama), values in mm
// along w from q; +infinity means the scene at infinity (the thesis's model). Every function that
// takes a depth map accepts an empty Mat as "+infinity everywhere".
//
// Files. Depth files (the simulator's DIR/truth_depth.tiff, `omma stitch --depth-out`) are 32-bit
// float TIFF, one channel, millimetres, +infinity where no surface lies within the scene's range.
// read_depth also accepts 16-bit PNG/TIFF in units of 1/100 mm with 0 meaning +infinity.
#pragma once

#include <filesystem>
#include <limits>
#include <string>

#include <opencv2/core.hpp>

#include "omma/core/grid.h"
#include "omma/core/rig.h"

namespace omma::pano {

inline constexpr double kInfiniteDepth = std::numeric_limits<double>::infinity();

// D at output pixel (col, row) of `depth` (+infinity if depth is empty).
inline double depth_at(const cv::Mat& depth, int col, int row) {
  return depth.empty() ? kInfiniteDepth : static_cast<double>(depth.at<float>(row, col));
}

// Throws std::invalid_argument (naming `what`) unless depth is empty or CV_32FC1 of the grid's size
// with every value > 0 (+infinity allowed; NaN, 0 and negative values are not).
void check_depth(const cv::Mat& depth, const PanoGrid& grid, const std::string& what = "depth map");

// The sphere of radius R (mm) around the dome centre (the origin) seen from q: D solves
// |q + D w| = R, i.e. D = -q.w + sqrt((q.w)^2 - |q|^2 + R^2). Throws std::invalid_argument if the
// sphere does not enclose every camera centre and q (a "stitching distance" inside the dome).
cv::Mat sphere_depth(const Rig& rig, const PanoGrid& grid, double radius_mm, const Vec3& q = Vec3::Zero());

// Throws std::invalid_argument (naming `what` and the first such pixel) if a finite depth puts the
// surface inside the dome: the point q + D w no farther from the dome centre than the farthest
// camera centre (the same bound as sphere_depth's). Cameras cannot see a surface behind them.
void check_depth_outside_dome(const cv::Mat& depth, const Rig& rig, const PanoGrid& grid,
                              const Vec3& q = Vec3::Zero(), const std::string& what = "depth map");

// Depth files (see the file comment). read_depth throws IoError if unreadable and
// std::invalid_argument if the size differs from the grid or a value is not > 0.
cv::Mat read_depth(const std::filesystem::path& path, const PanoGrid& grid);
void write_depth(const std::filesystem::path& path, const cv::Mat& depth);  // float TIFF, atomic

// An image a person can read: the depth in colour (turbo colour map over inverse depth, so near
// detail is spread out; near = red, far = blue, +infinity black) with a legend bar underneath
// labelled in mm. near_mm / far_mm: the legend's range (0: the map's 2nd / 98th percentile).
cv::Mat depth_colormap(const cv::Mat& depth, double near_mm = 0, double far_mm = 0,
                       const std::string& title = "depth");

}  // namespace omma::pano
