// 360-degree metadata of video files: what omma writes into every video of a panorama, what
// `omma meta` puts back after an outside re-encode, and what it reads.
//
// Where the frame lies on the sphere is spherical_layout(grid) (metadata.h). Two standards, both
// written, both replaced as a whole when a file is tagged again:
//
//  * Spherical Video V2 (Google's RFC "Spherical Video V2", github.com/google/spatial-media):
//    MP4/MOV: `st3d` (stereo_mode 0, mono) and `sv3d` { `svhd` (metadata source "omma"), `proj`
//    { `prhd` (pose yaw, pitch, roll 0), `equi` (projection bounds top, bottom, left, right: the
//    fractions of the full sphere cut off on each side, 0.32 fixed point, value * 2^32 rounded
//    down) } } appended to the first video track's sample entry. Matroska/WebM: the Video element's
//    Projection (ProjectionType 1 equirectangular, ProjectionPrivate with the same bounds, pose 0),
//    written by FFmpeg's muxer from the stream's spherical side data. FFmpeg/ffprobe report either
//    as "Spherical Mapping" side data ("equirectangular" for the whole sphere, "tiled
//    equirectangular" with bound_left/top/right/bottom in pixels for a crop); YouTube, ExoPlayer,
//    VLC read it.
//  * Spherical Video V1 (Google's RFC "Spherical Video", the older one), MP4/MOV only: a `uuid` box
//    with the id ffcc8263-f855-4a93-8814-587a02521fdd, appended to the video `trak`, holding the
//    RDF/XML of the GSpherical namespace (http://ns.google.com/videos/1.0/spherical/): Spherical and
//    Stitched true, StitchingSoftware, ProjectionType equirectangular, StereoMode mono,
//    FullPanoWidth/HeightPixels, CroppedAreaImageWidth/HeightPixels, CroppedAreaLeft/TopPixels
//    (what older players, Facebook's uploader and exiftool's XMP-GSpherical group read).
//
// In MP4/MOV both are edited in the movie box, which is read into memory (at most 1 GiB); the media
// data is copied unchanged, and chunk offsets are moved by the size change when the movie box
// precedes it ("fast start"). Matroska/WebM files are remuxed (every stream copied, packets
// unchanged).
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <utility>

#include <nlohmann/json.hpp>

#include "omma/core/grid.h"

struct AVSphericalMapping;  // FFmpeg (libavutil/spherical.h)

namespace omma::io {

// FFmpeg's spherical stream side data (AV_PKT_DATA_SPHERICAL) of `grid`, as its Matroska muxer
// writes it into the Projection element: equirectangular for the whole sphere, tiled
// equirectangular with the bounds (0.32 fixed point, as in `equi`) for a crop. Allocated with
// av_spherical_alloc: the caller owns it (av_free, or av_stream_add_side_data takes it); the second
// value is its size in bytes. Throws std::bad_alloc.
std::pair<AVSphericalMapping*, size_t> spherical_side_data(const PanoGrid& grid);

// FFmpeg's text for one of its (negative) error codes (av_strerror), for messages.
std::string av_error(int code);

// The V1 RDF/XML of `grid` (UTF-8), as it goes into the uuid box.
std::string spherical_v1_xml(const PanoGrid& grid);

// True for the extensions of ISO base media files (.mp4 .m4v .mov, any case) and of Matroska
// (.mkv .webm), the containers set_spherical_video_metadata() edits.
bool is_isobmff_path(const std::filesystem::path& path);
bool is_matroska_path(const std::filesystem::path& path);

// Writes the 360-degree metadata of `grid` into the video at `path` (rewritten atomically),
// replacing any the file had (V1 and V2 in MP4/MOV, V2 in Matroska/WebM). Returns false, leaving
// the file untouched, if it already carries exactly this metadata. Throws IoError if the file is
// not a video of these containers or has no video track (it is then untouched).
bool set_spherical_video_metadata(const std::filesystem::path& path, const PanoGrid& grid);

// The 360-degree metadata a video carries (read with libavformat; V1 from the MP4/MOV boxes).
struct SphericalVideoInfo {
  std::string container;      // libavformat's name ("mov,mp4,m4a,3gp,3g2,mj2", "matroska,webm")
  std::string codec;          // the first video stream's codec ("h264", "vp9")
  int width = 0, height = 0;  // its frame size, pixels
  bool v2 = false;            // Spherical Video V2 (st3d/sv3d, Matroska Projection)
  std::string projection;     // V2: "equirectangular", "tiled equirectangular", "cubemap", ...
  // V2 bounds in pixels of the frame (what is cut off the full sphere on each side; 0 unless tiled).
  int64_t bound_left = 0, bound_top = 0, bound_right = 0, bound_bottom = 0;
  double yaw = 0, pitch = 0, roll = 0;           // V2 pose, degrees
  std::string stereo;                            // V2 st3d: "2D", "top and bottom", ... ("" if none)
  bool v1 = false;                               // a V1 uuid box
  std::map<std::string, std::string> v1_fields;  // its GSpherical elements, name -> text
  nlohmann::json to_json() const;
};
// Throws IoError if `path` does not open as a video with a video stream.
SphericalVideoInfo read_spherical_video_metadata(const std::filesystem::path& path);

}  // namespace omma::io
