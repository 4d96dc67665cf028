// Panoramas written to files band by band, and the offline renderer's unit of work: one frame set
// read, developed, rendered and written.
#pragma once

#include <cstdint>
#include <filesystem>

#include "omma/isp/isp.h"
#include "omma/render/frame_reader.h"
#include "omma/render/pano_render.h"

namespace omma::io {

// Writes a panorama to `path` band by band: .tif/.tiff as BigTIFF (any size, memory = one band),
// other extensions through OpenCV (the whole image in memory; JPEG is limited to 65535 pixels per
// side). Atomic. Returns the seconds spent rendering (without writing).
double render_to_file(render::PanoRenderer& renderer, const std::filesystem::path& path);

// Frame set `set` of `reader` -> developed frames (render::develop_frame_set) -> the panorama at
// `path` (render_to_file: atomic). This is the unit of work a distributed renderer hands out: it
// reads only its frame set, writes only its file. Returns the seconds spent in each step.
render::FrameSetTimes render_frame_set(const render::FrameSetReader& reader, int64_t set,
                                       render::PanoRenderer& renderer, isp::IspOptions iso,
                                       const std::filesystem::path& path);

}  // namespace omma::io
