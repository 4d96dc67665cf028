// 360-degree metadata of panorama outputs, so that photo viewers, video players
// and sharing platforms recognise omma's panoramas as spherical, and know which part of the
// sphere they cover. One place for every writer (apps, engine sinks, Python bindings).
//
// Where each grid (grid.h) lies on the full 360 x 180 degree equirectangular sphere, in pixels of
// the image's own resolution (SphericalLayout):
//   equirect       360 x 90 deg, the dome axis (+z) along the top row: the TOP HALF of the sphere
//                  (the dome axis is the zenith). Full W x 2H, the image at left 0, top 0.
//   vr180          180 x 180 deg with the dome axis at the centre, right = -x, up = +y: the FRONT
//                  HALF (the dome axis looks forward, the VR180 convention). Full 2W x H, the image
//                  at left W/2, top 0.
//   equirect-full  the whole sphere: full W x H.
//   equirect-100   360 x 100 deg from the zenith down (Giga-Eye): full W x round(1.8 H), top 0.
// Every grid is the world the right way round (conventions.h (G1), (G2)), as these formats assume,
// so no pose or flip is written.
//
// Photos (JPEG, PNG): Google's Photo Sphere XMP (namespace GPano, http://ns.google.com/photos/1.0/
// panorama/): ProjectionType equirectangular, UsePanoramaViewer, FullPanoWidth/HeightPixels,
// CroppedAreaImageWidth/HeightPixels, CroppedAreaLeft/TopPixels (what Google Photos, Facebook,
// Photo Sphere Viewer, Pannellum and exiftool read). JPEG: in an APP1 segment after the JFIF APP0
// (XMP spec part 3); PNG: in an iTXt chunk with keyword "XML:com.adobe.xmp" after IHDR.
//
// Videos (MP4): Spherical Video V2 (Google's RFC "Spherical Video V2"): `st3d` (mono)
// and `sv3d` (svhd, proj with prhd = zero pose and `equi` with the projection bounds of the crop,
// 0.32 fixed point fractions of the full sphere) appended to the first video track's sample entry.
// FFmpeg/ffprobe report it as "Spherical Mapping" side data (equirectangular, or tiled
// equirectangular with the bounds for a crop); YouTube and ExoPlayer read V2. (V1's XML uuid box
// is not written: V2 carries the crop as bounds, and readers that know V1 know V2.)
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include <opencv2/core.hpp>

#include "omma/core/grid.h"

namespace omma::io {

// Where an image of `grid` lies on the full equirectangular sphere, in pixels.
struct SphericalLayout {
  int full_width = 0, full_height = 0;  // the full 360 x 180 sphere at the image's resolution
  int left = 0, top = 0;                // the image's offset in it
  int width = 0, height = 0;            // the image (= grid size)
};
SphericalLayout spherical_layout(const PanoGrid& grid);

// The XMP packet with the GPano fields of `grid` (UTF-8 text).
std::string gpano_xmp(const PanoGrid& grid);

// `encoded` (a whole JPEG or PNG file) with the XMP packet inserted; `ext` is the file's extension
// (".jpg", ".jpeg" or ".png", any case). Throws IoError if the bytes are not that format.
std::string embed_xmp(std::string_view encoded, const std::string& ext, const std::string& xmp);

// True for the extensions write_panorama() adds XMP to (.jpg, .jpeg, .png).
bool carries_xmp(const std::filesystem::path& path);

// Writes a panorama of `grid` atomically (io.h): JPEG and PNG with the GPano XMP, any other format
// as write_image() does. Throws IoError.
void write_panorama(const std::filesystem::path& path, const cv::Mat& image, const PanoGrid& grid);

// Adds Spherical Video V2 metadata for `grid` to the MP4 file at `path` (rewritten atomically;
// the media data is copied unchanged, chunk offsets are moved if the movie box precedes it). A
// file that already has an sv3d box is left as it is. Throws IoError if `path` is not an MP4 file
// with a video track.
void add_spherical_video_metadata(const std::filesystem::path& path, const PanoGrid& grid);

}  // namespace omma::io
