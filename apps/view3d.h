// omma view3d: a self-contained page (three.js, works from file://) showing a PLY point cloud as a
// 3D view one can turn and zoom; shared by `omma view3d` and the Giga-Eye demo.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>

namespace omma::app {

struct View3dPage {
  std::filesystem::path index, ply;  // DIR/index.html and the PLY copied beside it
  long long points = 0, points_in_file = 0, stride = 1;
  size_t page_bytes = 0;
};

// Writes DIR/index.html (the cloud inlined, every stride-th point when it holds more than max_points)
// and copies the PLY beside it. Throws std::invalid_argument / IoError on bad input.
View3dPage write_view3d_page(const std::filesystem::path& ply, const std::filesystem::path& dir,
                             long long max_points = 2000000, double point_size = 2,
                             const std::string& title = "");

}  // namespace omma::app
