// One panorama split by bands across the ranks (`omma render --split tiles`): for a single giant
// panorama (82.3 MP and beyond) rather than many frame sets.
//
// Every rank holds the developed frames (render::PanoRenderer::set_frames) and the band maps it
// needs (from the map cache when maps are not resident). Rank 0 hands out bands in row order as
// ranks ask (dynamic, like job.h); each rank renders its band (render::PanoRenderer::render_band) and sends
// the pixels to rank 0, which appends them to ONE streaming BigTIFF (io/tiff_writer.h) in row
// order. Bands that arrive ahead of their turn wait at rank 0, and no band beyond the next one to
// write plus `window` is handed out, so rank 0 holds at most `window` bands and no rank ever holds
// the whole image.
//
// Why a single writer rather than every rank writing its strips into a shared file: the panorama is
// one file, so its bandwidth is one stream to the file system either way; one writer keeps the file
// an ordinary libtiff-written BigTIFF (optionally compressed: strip sizes unknown in advance rule
// out precomputed offsets), needs no parallel file system (MPI-IO) and keeps the atomic rename
// (the file appears complete or not at all). The cost is that the pixels cross the network once
// more (rank -> rank 0), 3 bytes per pixel, which the model in docs/results/mpi_bench.md accounts for.
#pragma once

#include <filesystem>
#include <vector>

#include "omma/dist/comm.h"
#include "omma/dist/job.h"
#include "omma/render/pano_render.h"

namespace omma::dist {

struct SplitOptions {
  int window = 0;               // bands rank 0 may hold; 0: 2 x ranks
  Rank0 rank0 = Rank0::kWorks;  // rank 0 renders bands too (on a second thread) or only writes
  bool IsValid(std::string* why = nullptr) const;
};

struct SplitSummary {
  int bands = 0;
  double seconds = 0;               // wall time, rank 0
  double render_seconds = 0;        // summed over the ranks
  double write_seconds = 0;         // rank 0's TIFF writing
  int max_held = 0;                 // most bands rank 0 held at once (waiting for their turn)
  std::vector<int> bands_per_rank;  // rank 0 only
};

// Every rank calls it with the same renderer options and frames set. Writes `path` (.tif or .tiff:
// a BigTIFF) atomically from rank 0. Throws JobError like run_job (one message on rank 0).
SplitSummary render_split(Comm& comm, render::PanoRenderer& renderer, const std::filesystem::path& path,
                          const SplitOptions& options = {});

}  // namespace omma::dist
