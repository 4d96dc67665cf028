// Bounds on the sizes and counts that enter omma from files and options, in one place, so that no
// product of them overflows (pixel counts, byte counts and store offsets are computed in size_t, and
// OpenCV's int rows x cols x channels stays below 2^31) and no input can make a command run for hours.
#pragma once

#include <cstdint>
#include <string>

namespace omma {

// Any image or panorama: at most 16384 pixels a side and 2^28 (268 M) pixels, so that
// width * height * 4 channels * 2 bytes fits in 2^31 (OpenCV's int arithmetic).
inline constexpr int kMaxImageSide = 16384;
inline constexpr std::int64_t kMaxImagePixels = std::int64_t(1) << 28;

// Panoramas rendered band by band (`omma render`, render/pano_render.h: the Giga-Eye's 17700 x 4650)
// may be larger: at most 65536 pixels a side and 2^30 pixels in all, while each band (a map's
// window, as wide as the panorama) holds at most kMaxImagePixels; 2^30 keeps every pixel index of the whole
// panorama in a signed 32-bit int.
inline constexpr int kMaxBandedSide = 65536;
inline constexpr std::int64_t kMaxBandedPixels = std::int64_t(1) << 30;

// Cameras per rig. The compiled map (render/compiled_map.h) addresses the frame store with 32-bit
// offsets in units of 2 bytes, i.e. at most 8 GiB of store: 6 bytes per pixel (row pairs) times the
// widest camera's width times the sum of the heights, e.g. 22 906 cameras of 250 x 250, or 44 of the
// Giga-Eye's 2592 x 1944 in 1.3 GiB; the live engine runs one thread per camera. 4096 bounds both the
// count (threads, per-camera arrays, the map file's camera table) and, with kMaxImageSide, the
// store row index (4096 x 16384 < 2^31); StoreLayout::for_rig checks the 8 GiB.
inline constexpr int kMaxCameras = 4096;

// Focal lengths (pixels) relative to the image size: f >= kMinFocalRel * max(W, H) (a pinhole image
// then spans at most 2 atan(500) = 179.77 deg, the most a pinhole camera can image) and
// f <= kMaxFocalRel * max(W, H) (an angle of view of 0.006 deg: a 1000 mm lens on 2 um pixels
// is 5 10^5 px on a 5000 px sensor, f/W = 100). Keeps 1/f and f * (x / z) far from denormals and
// overflow.
inline constexpr double kMinFocalRel = 1e-3;
inline constexpr double kMaxFocalRel = 1e4;

// Further sanity bounds of a rig camera (core/rig.h validate_camera): positions and the dome radius
// within 1 km of the dome centre, the principal point within 16 image sides of the image origin,
// distortion |k| <= 10^6 (k5 multiplies R^6 and is loosely determined for narrow lenses).
inline constexpr double kMaxPositionMm = 1e6;
inline constexpr double kMaxCentreRel = 16;
inline constexpr double kMaxDistortion = 1e6;

// Throws std::invalid_argument ("<what> WxH is out of range ...") unless 1 <= width, height <=
// kMaxImageSide and width * height <= kMaxImagePixels. 64-bit arguments so that callers can pass
// values before narrowing them to int.
void check_image_size(std::int64_t width, std::int64_t height, const std::string& what);
// The same with kMaxBandedSide and kMaxBandedPixels: a panorama rendered band by band.
void check_banded_size(std::int64_t width, std::int64_t height, const std::string& what);

}  // namespace omma
