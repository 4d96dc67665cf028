// 360-degree metadata of panorama outputs, so that photo viewers, video players
// and sharing platforms recognise omma's panoramas as spherical, and know which part of the
// sphere they cover. One place for every writer (apps, engine sinks, Python bindings).
//
// Where each grid (grid.h) lies on the full 360 x 180 degree equirectangular sphere, in pixels of
// the image's own resolution along each axis (SphericalLayout, spherical_layout()):
//   equirect       360 x 90 deg, the dome axis (+z) along the top row: the TOP HALF of the sphere
//                  (the dome axis is the zenith). Full W x 2H, the image at left 0, top 0.
//   vr180          180 x 180 deg with the dome axis at the centre, right = -x, up = +y: the FRONT
//                  HALF (the dome axis looks forward, the VR180 convention). Full 2W x H, the image
//                  at left W/2, top 0.
//   equirect-full  the whole sphere: full W x H.
//   equirect-100   360 x 100 deg from the zenith down (Giga-Eye): full W x round(1.8 H), top 0.
// Every grid is the world the right way round (conventions.h (G1), (G2)), as these formats assume,
// so no pose or flip is written. This layout is exact as fractions of the sphere whatever the
// pixels' aspect (what video's bounds are), but its full size is 2:1 only when the pixels are square.
//
// Photos (JPEG, PNG, TIFF): Google's Photo Sphere XMP (namespace GPano, http://ns.google.com/photos/
// 1.0/panorama/): ProjectionType equirectangular, UsePanoramaViewer, FullPanoWidth/HeightPixels,
// CroppedAreaImageWidth/HeightPixels, CroppedAreaLeft/TopPixels (what Google Photos, Facebook,
// Photo Sphere Viewer, Pannellum and exiftool read). Viewers take FullPanoWidthPixels as 360 deg and
// FullPanoHeightPixels as 180 deg, both at the image's one pixel pitch, so GPano is true only for
// square pixels. The rule (photo_sphere_layout()):
//   - the pixels are square when W / span_w == H / span_h within half a pixel, i.e.
//     |H - W span_h / span_w| <= 0.5 (vr180: H == W; equirect: H = W/4; equirect-100: H = W 100/360;
//     equirect-full: H = W/2); then the full sphere is W 360/span_w x round(that / 2) (equirect,
//     equirect-100: W x round(W/2); vr180: 2W x W; equirect-full: W x H), the image at left
//     (full width - W)/2 for vr180 (else 0), top 0: FullPanoWidth = 2 FullPanoHeight (within a
//     pixel for odd W), the crop / full ratios = the grid's angular span / 360 x 180 deg;
//   - otherwise (e.g. the thesis's default 1920x512 equirect: 5.33 x 5.69 px/deg; the Giga-Eye's
//     9000x2400 equirect-100: 25 x 24 px/deg) NO GPano is written, since no GPano fits such pixels,
//     and write_panorama() logs one warning per grid size naming the square-pixel size to use
//     (1920x480, 9000x2500). omma does not resample to make the metadata fit.
// Where: JPEG in an APP1 segment after the JFIF APP0 (XMP spec part 3); PNG in an iTXt chunk with
// keyword "XML:com.adobe.xmp" after IHDR; TIFF and BigTIFF in tag 700 (XMLPacket, TIFF/EP, XMP spec
// part 3), with the tags TIFF 6.0 requires (XResolution, YResolution 72, ResolutionUnit inch) so
// that `exiftool -validate` finds nothing to warn about. A BigTIFF is only written when the image
// does not fit a classic TIFF or the name ends in .btf (exiftool warns about a BigTIFF named .tif).
//
// Videos (MP4, MOV, Matroska, WebM): Spherical Video V2 and, in MP4/MOV, V1, with the layout above
// as projection bounds and crop: spherical_video.h, which writes, replaces and reads them.
#pragma once

#include <filesystem>
#include <optional>
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
// The table above, at the image's resolution along each axis (exact as fractions of the sphere:
// video's projection bounds). Not a photo's GPano when the pixels are not square.
SphericalLayout spherical_layout(const PanoGrid& grid);

// The GPano layout of `grid` when its pixels are square (the rule above): full width 2:1 with the
// full height, in the image's pixels; nullopt otherwise, with the reason (sizes, px/deg and the
// square-pixel size to use) in *why.
std::optional<SphericalLayout> photo_sphere_layout(const PanoGrid& grid, std::string* why = nullptr);

// The XMP packet with the GPano fields of `grid` (UTF-8 text). Throws std::invalid_argument (the
// reason of photo_sphere_layout) if the grid's pixels are not square.
std::string gpano_xmp(const PanoGrid& grid);

// What write_panorama() embeds: gpano_xmp(grid), or "" for a grid with non-square pixels, after
// logging its reason as one warning (once per projection and size in this process).
std::string panorama_xmp(const PanoGrid& grid);

// `encoded` (a whole JPEG or PNG file) with the XMP packet inserted; `ext` is the file's extension
// (".jpg", ".jpeg" or ".png", any case). Throws IoError if the bytes are not that format.
std::string embed_xmp(std::string_view encoded, const std::string& ext, const std::string& xmp);

// True for the extensions write_panorama() adds XMP to (.jpg, .jpeg, .png, .tif, .tiff).
bool carries_xmp(const std::filesystem::path& path);

// Writes a panorama of `grid` atomically (io.h): JPEG, PNG and TIFF (OpenCV's encoders, any depth
// they take) with panorama_xmp(grid) (none for non-square pixels), TIFF also with its resolution
// tags; any other format as write_image() does. The image must be grid-sized. Throws IoError.
void write_panorama(const std::filesystem::path& path, const cv::Mat& image, const PanoGrid& grid);

// Writes the 360-degree video metadata of `grid` into the video at `path` (rewritten atomically,
// the frames unchanged), replacing any it had: set_spherical_video_metadata() in spherical_video.h.
// Throws IoError if `path` is not an MP4/MOV/MKV/WebM file with a video track.
void add_spherical_video_metadata(const std::filesystem::path& path, const PanoGrid& grid);

// ---- Additions for depth panoramas (depth_pano.h) -------------------------------------------------

// Base64 (RFC 4648 alphabet, with '=' padding) of `bytes`: XMP's binary properties (GDepth:Data).
std::string base64_encode(std::string_view bytes);

// The rdf:Description element of gpano_xmp(grid) (the GPano fields alone, to share a packet with
// other namespaces), or "" when the grid's pixels are not square (no warning).
std::string gpano_description(const PanoGrid& grid);
// A whole XMP packet (xpacket wrapper, x:xmpmeta, rdf:RDF, as gpano_xmp writes) around `descriptions`
// (rdf:Description elements).
std::string xmp_packet(const std::string& descriptions);

// JPEG Extended XMP (XMP spec part 3, 1.1.3.1), for packets beyond one APP1 segment's 64 KB:
// extended_xmp_guid is the GUID of an extended packet (`extended`: an x:xmpmeta serialization without
// the xpacket wrapper): its MD5 as 32 upper-case hex digits, which the standard packet names in
// xmpNote:HasExtendedXMP (namespace http://ns.adobe.com/xmp/note/). embed_xmp_jpeg_extended inserts
// `xmp` (the standard packet) as embed_xmp does and `extended` after it, split into APP1 segments of
// "http://ns.adobe.com/xmp/extension/\0", the GUID, the extended packet's full length and the
// portion's offset (4 bytes each, big-endian), then the portion. Throws IoError if `jpg` is not a JPEG
// or the standard packet does not fit one segment.
std::string extended_xmp_guid(const std::string& extended);
std::string embed_xmp_jpeg_extended(std::string_view jpg, const std::string& xmp,
                                    const std::string& extended);

}  // namespace omma::io
