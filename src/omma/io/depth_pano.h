// 360-degree depth panoramas that viewers and tools understand: the depth map of a panorama
// (pano/surface.h: CV_32FC1, the grid's size, mm from the observer q along each pixel's direction w,
// +infinity where no surface lies) as
//
//  1. a 16-bit gray PNG beside the colour panorama (write_depth_png): the value is the depth in whole
//     millimetres, rounded (so within 0.5 mm), 0 = unknown or infinity, saturating at 65535 mm
//     (65.5 m: farther finite depths read 65535); depths below 1 mm read 1. Its XMP (PNG iTXt,
//     metadata.h) holds GPano (when the grid's pixels are square, as the colour panorama's) so that
//     360-degree viewers place it, and Google's depth-map fields (namespace GDepth,
//     http://ns.google.com/photos/1.0/depthmap/) describing these pixels: Format RangeLinear, Near 0,
//     Far 65535, Units mm (so depth = Near + (Far - Near) v / 65535 = v mm), MeasureType OpticRay (along
//     each pixel's ray from q, not along an optical axis), Software, ImageWidth/ImageHeight, and a
//     dc:description saying the above in words. The image itself is the data (no GDepth:Data).
//     read_depth_png reads it back (0 -> +infinity). NB: pano::read_depth's 16-bit files are in 1/100 mm;
//     use the float TIFF (the --depth-out / --depth-pano data beside it) with `--depth truth:`.
//
//  2. Google's depth-map XMP inside the colour panorama itself (write_panorama_with_depth), the
//     format of depth photos (GDepth): Format RangeInverse, Near = the smallest finite depth, Far = the
//     largest (mm), Units mm, MeasureType OpticRay, Mime image/png, Data = base64 of a 16-bit PNG of the
//     normalised depth v = round(65535 d_n), d_n = Far (D - Near) / (D (Far - Near)), which decodes as
//     D = Far Near / (Far - d_n (Far - Near)) (RangeInverse: most levels near; d_n = 0 when Far == Near).
//     The format has no infinity: infinite directions are stored as Far (the depth PNG keeps them as 0).
//     JPEG: the GPano and GDepth fields in the standard XMP with xmpNote:HasExtendedXMP, the data in
//     Extended XMP (XMP spec part 3, 1.1.3.1: APP1 segments of at most 64 KB, GUID = MD5 of the
//     extended packet), as depth photos do; PNG: one iTXt packet with everything. A depth map without a
//     finite value gets no GDepth (there is no range), only the GPano of write_panorama.
#pragma once

#include <filesystem>
#include <string>

#include <opencv2/core.hpp>

#include "omma/core/grid.h"

namespace omma::io {

inline constexpr double kDepthPngMaxMm = 65535;  // the 16-bit depth PNG saturates here

// The finite depths' range: near_mm = min, far_mm = max over the finite values; finite = their count
// (0: near_mm = far_mm = 0).
struct DepthRange {
  double near_mm = 0, far_mm = 0;
  long long finite = 0;
};
// depth: CV_32FC1 (empty: no finite value). Throws std::invalid_argument for another type.
DepthRange depth_range(const cv::Mat& depth);

// CV_32FC1 mm -> CV_16UC1 (1 above) and back (0 -> +infinity). Throw std::invalid_argument on other
// types, NaN or depths <= 0.
cv::Mat depth_to_png16(const cv::Mat& depth_mm);
cv::Mat depth_from_png16(const cv::Mat& png16);

// The XMP packet of the depth PNG (1 above) for `grid`.
std::string depth_png_xmp(const PanoGrid& grid);
// Writes depth_to_png16(depth) with depth_png_xmp(grid) atomically to `path` (must end in .png).
// depth: CV_32FC1 of the grid's size. Throws std::invalid_argument / IoError.
void write_depth_png(const std::filesystem::path& path, const cv::Mat& depth, const PanoGrid& grid);
// Reads a depth PNG (any 16-bit one-channel PNG of whole mm) as CV_32FC1 mm, 0 -> +infinity. IoError.
cv::Mat read_depth_png(const std::filesystem::path& path);

// GDepth RangeInverse (2 above): the 16-bit normalised image of `depth` for range r, and back.
cv::Mat gdepth_encode_inverse(const cv::Mat& depth, const DepthRange& r);
cv::Mat gdepth_decode_inverse(const cv::Mat& png16, double near_mm, double far_mm);

// Writes the colour panorama like write_panorama (metadata.h) with Google's depth map of `depth`
// embedded (2 above). .jpg/.jpeg and .png only (std::invalid_argument otherwise). Throws IoError.
void write_panorama_with_depth(const std::filesystem::path& path, const cv::Mat& colour, const cv::Mat& depth,
                               const PanoGrid& grid);

}  // namespace omma::io
