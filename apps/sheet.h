// Pictures side by side for reports: labelled tiles on a white sheet (focal stacks, crops).
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace omma::app {

// `images` (8-bit, 3 channels) in rows of `columns`, left to right, each scaled down to at most
// `max_width` pixels wide (0: as they are) under a white strip holding its label; cells as large as
// the largest tile, empty cells white. Throws std::invalid_argument if the counts differ, there is no
// image or columns < 1.
cv::Mat labelled_sheet(const std::vector<cv::Mat>& images, const std::vector<std::string>& labels,
                       int columns, int max_width = 0);

}  // namespace omma::app
