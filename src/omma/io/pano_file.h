// Panoramas written to files band by band, and the offline renderer's unit of work: one frame set
// read, developed, rendered and written.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include "omma/isp/isp.h"
#include "omma/render/frame_reader.h"
#include "omma/render/pano_render.h"

namespace omma::io {

// Writes a panorama to `path` band by band: .tif/.tiff/.btf with BigTiffWriter (any size, memory =
// one band; classic TIFF up to 4 GiB, BigTIFF above or for .btf), other extensions through OpenCV
// (the whole image in memory; JPEG is limited to 65500 pixels per side). JPEG, PNG and TIFF carry
// the GPano XMP of the renderer's grid (metadata.h: none for non-square pixels). Atomic. Returns
// the seconds spent rendering (without writing).
double render_to_file(render::PanoRenderer& renderer, const std::filesystem::path& path);

// Frame set `set` of `reader` -> developed frames (render::develop_frame_set) -> the panorama at
// `path` (render_to_file: atomic). This is the unit of work a distributed renderer hands out: it
// reads only its frame set, writes only its file. Returns the seconds spent in each step.
render::FrameSetTimes render_frame_set(const render::FrameSetReader& reader, int64_t set,
                                       render::PanoRenderer& renderer, isp::IspOptions iso,
                                       const std::filesystem::path& path);

// The file of frame set `set` for an output pattern: "pano_{set}.tif" -> "pano_00012.tif"; a name
// without {set} gets "_00012" before the extension when several sets are rendered (`many`), and is
// used as it is otherwise (`omma render -o`, omma.render_files).
std::filesystem::path frame_set_path(const std::string& pattern, int64_t set, bool many);

}  // namespace omma::io
