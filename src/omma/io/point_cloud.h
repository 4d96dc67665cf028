// Coloured point clouds from a panorama and its depth map (the 3D the cameras' overlaps give), and
// their file format, PLY.
//
// Geometry. A depth map (CV_32FC1, the panorama grid's size; pano/surface.h) holds per output pixel the
// distance D in mm from the observer q along the pixel's direction w (grid.h, pixel centres at
// integer + 0.5, conventions.h); the surface point is X = q + D w in the rig (dome) frame (the frame of
// contributors.h: right-handed, origin at the dome centre, +z the dome axis), in millimetres.
// Pixels whose D is +infinity (the scene at infinity, or no surface) have no point.
//
// PLY (Turk's polygon file format as read by MeshLab, CloudCompare, Open3D, three.js's PLYLoader):
//   ply
//   format binary_little_endian 1.0
//   comment omma <version>: x y z in millimetres in the rig (dome) frame: origin the dome centre, +z the
//   comment dome axis; X = q + D w seen from q = (qx, qy, qz) mm; colours 8-bit sRGB of the panorama
//   comment <the caller's comment lines, if any>
//   element vertex N
//   property float x
//   property float y
//   property float z
//   property uchar red
//   property uchar green
//   property uchar blue
//   end_header
// then N records of 15 bytes (3 little-endian IEEE floats, 3 bytes), in the panorama's row-major
// order of the pixels kept. Written atomically (core/io.h: a temporary name, then renamed).
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/core/geometry.h"
#include "omma/core/grid.h"

namespace omma::io {

struct PointCloud {
  std::vector<std::array<float, 3>> xyz;    // mm, rig frame
  std::vector<std::array<uint8_t, 3>> rgb;  // red, green, blue (8-bit sRGB), one per point
  std::vector<std::string> comments;        // the PLY's comment lines (read_ply: as in the file)
  size_t size() const { return xyz.size(); }
};

struct PointCloudOptions {
  Vec3 q = Vec3::Zero();  // the observer the depth is measured from, mm (the stitcher's SearchOptions::q)
  // Keep every step-th pixel in each axis: pixels (col, row) with col % step == 0 and row % step == 0,
  // so at most ceil(W / step) * ceil(H / step) points. >= 1.
  int step = 1;
  // With a confidence map: skip pixels whose confidence is below this (0: keep every finite pixel).
  double min_confidence = 0;
  bool IsValid(std::string* why = nullptr) const;
};

// The points X = q + D w of every kept pixel with finite D (and confidence >= min_confidence where a
// confidence map is given), coloured with the panorama's pixel. depth: CV_32FC1 grid-sized (empty =
// +infinity everywhere: no points); colour: CV_8UC3 (OpenCV's BGR order) or CV_8UC1 (gray, r = g = b)
// or CV_8UC4 (BGRA, alpha ignored), grid-sized; confidence: empty or CV_32FC1 grid-sized. Throws
// std::invalid_argument on other types or sizes, invalid options, or a depth that is NaN or <= 0.
PointCloud depth_to_points(const cv::Mat& depth, const cv::Mat& colour, const PanoGrid& grid,
                           const PointCloudOptions& opt = {}, const cv::Mat& confidence = {});

// The PLY file of `cloud` (layout above) as bytes; cloud.comments are written after omma's own two
// lines (each must be one line: a newline in one throws std::invalid_argument). q goes into the comment.
std::string encode_ply(const PointCloud& cloud, const Vec3& q = Vec3::Zero());
// encode_ply written atomically to `path`. Throws IoError if it cannot be written.
void write_ply(const std::filesystem::path& path, const PointCloud& cloud, const Vec3& q = Vec3::Zero());

// Reads a PLY whose vertices have float x, y, z and uchar red, green, blue (in any order, beside other
// scalar properties, which are skipped), binary_little_endian or ascii, with no other element before
// the vertices (faces after them are ignored). Throws IoError naming the path if the file is missing,
// is not such a PLY or is truncated.
PointCloud read_ply(const std::filesystem::path& path);
PointCloud parse_ply(const std::string& bytes, const std::string& what = "PLY data");

}  // namespace omma::io
