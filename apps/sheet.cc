#include "apps/sheet.h"

#include <algorithm>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

namespace omma::app {

cv::Mat labelled_sheet(const std::vector<cv::Mat>& images, const std::vector<std::string>& labels,
                       int columns, int max_width) {
  if (images.empty() || images.size() != labels.size() || columns < 1)
    throw std::invalid_argument("labelled_sheet: one label per image, at least one image and one column");
  std::vector<cv::Mat> tiles;
  cv::Size cell(0, 0);
  for (size_t i = 0; i < images.size(); ++i) {
    cv::Mat t = images[i];
    if (max_width > 0 && t.cols > max_width) {
      const double s = double(max_width) / t.cols;
      cv::resize(images[i], t, cv::Size(), s, s, cv::INTER_AREA);
    }
    cv::copyMakeBorder(t, t, 30, 4, 4, 4, cv::BORDER_CONSTANT, cv::Scalar::all(255));
    cv::putText(t, labels[i], cv::Point(8, 22), cv::FONT_HERSHEY_SIMPLEX, 0.7, cv::Scalar::all(0), 2,
                cv::LINE_AA);
    cell.width = std::max(cell.width, t.cols);
    cell.height = std::max(cell.height, t.rows);
    tiles.push_back(t);
  }
  const int cols = std::min<int>(columns, int(tiles.size()));
  const int rows = (int(tiles.size()) + cols - 1) / cols;
  cv::Mat sheet(rows * cell.height, cols * cell.width, tiles[0].type(), cv::Scalar::all(255));
  for (size_t i = 0; i < tiles.size(); ++i)
    tiles[i].copyTo(sheet(
        cv::Rect(int(i % cols) * cell.width, int(i / cols) * cell.height, tiles[i].cols, tiles[i].rows)));
  return sheet;
}

}  // namespace omma::app
