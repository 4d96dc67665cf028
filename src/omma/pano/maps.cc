#include "omma/pano/maps.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <tbb/parallel_for.h>

#include "omma/pano/stitch.h"
#include "omma/pano/surface.h"

namespace omma::pano {

cv::Mat coverage_map(const Rig& rig, const PanoGrid& grid, const SearchOptions& search,
                     const cv::Mat& depth) {
  check_depth(depth, grid);
  cv::Mat out(grid.height, grid.width, CV_8UC1);
  tbb::parallel_for(0, grid.height, [&](int row) {
    for (int col = 0; col < grid.width; ++col) {
      const size_t n =
          find_contributors(rig, grid.pixel_direction(col, row), depth_at(depth, col, row), search).size();
      out.at<unsigned char>(row, col) = static_cast<unsigned char>(std::min<size_t>(n, 255));
    }
  });
  return out;
}

cv::Mat single_camera_map(const cv::Mat& coverage) {
  if (coverage.type() != CV_8UC1) throw std::invalid_argument("single_camera_map: coverage must be CV_8UC1");
  cv::Mat out(coverage.size(), CV_8UC1);
  for (int r = 0; r < coverage.rows; ++r)
    for (int c = 0; c < coverage.cols; ++c) {
      const int n = coverage.at<unsigned char>(r, c);
      out.at<unsigned char>(r, c) = n == 0 ? kNoCamera : n == 1 ? kSingleCamera : kMultiCamera;
    }
  return out;
}

cv::Mat seam_mask(const cv::Mat& map, bool is_single_camera_map) {
  cv::Mat gray = map;
  if (gray.channels() != 1) throw std::invalid_argument("seam mask: the map must have one channel");
  if (gray.depth() != CV_8U) throw std::invalid_argument("seam mask: the map must be 8-bit");
  cv::Mat out;
  if (is_single_camera_map)
    out = gray == kMultiCamera;
  else
    out = gray >= 2;
  return out;
}

cv::Mat boundary_map(const Rig& rig, const std::vector<cv::Mat>& frames_in, const PanoGrid& grid,
                     const SearchOptions& search, const cv::Mat& depth) {
  check_frames(rig, frames_in);
  check_depth(depth, grid);
  const std::vector<cv::Mat> frames = frames_to_float(frames_in);
  cv::Mat out(grid.height, grid.width, CV_32FC1, cv::Scalar(0));
  tbb::parallel_for(0, grid.height, [&](int row) {
    for (int col = 0; col < grid.width; ++col) {
      const auto cs = find_contributors(rig, grid.pixel_direction(col, row), depth_at(depth, col, row),
                                        search);  // eq. 4.12
      if (cs.size() < 2) continue;
      auto by_r = [](const Contributor& a, const Contributor& b) { return a.r < b.r; };
      const Contributor& j = *std::min_element(cs.begin(), cs.end(), by_r);  // eq. 4.13
      const Contributor& k = *std::max_element(cs.begin(), cs.end(), by_r);  // eq. 4.14
      const double lj = luma(sample_bilinear(frames[j.camera], j.px));
      const double lk = luma(sample_bilinear(frames[k.camera], k.px));
      out.at<float>(row, col) = static_cast<float>(std::abs(lk - lj));  // eq. 4.15
    }
  });
  return out;
}

cv::Mat boundary_binary(const cv::Mat& boundary, double threshold) {
  if (boundary.type() != CV_32FC1) throw std::invalid_argument("boundary map must be CV_32FC1");
  cv::Mat out = boundary > threshold;  // eq. 4.16
  return out;
}

cv::Mat boundary_overlay(const cv::Mat& pano, const cv::Mat& boundary, double threshold) {
  if (pano.size() != boundary.size()) throw std::invalid_argument("boundary overlay: sizes differ");
  if (pano.channels() != 3) throw std::invalid_argument("boundary overlay: panorama must have 3 channels");
  cv::Mat out = pano.clone();
  const double full = pano.depth() == CV_8U ? 255 : pano.depth() == CV_16U ? 65535 : 1.0;
  out.setTo(cv::Scalar(0, full, 0), boundary_binary(boundary, threshold));  // BGR green
  return out;
}

double inter_camera_psnr(const Rig& rig, const std::vector<cv::Mat>& frames_in, const PanoGrid& grid,
                         const SearchOptions& search, const cv::Mat& depth) {
  check_frames(rig, frames_in);
  check_depth(depth, grid);
  const std::vector<cv::Mat> frames = frames_to_float(frames_in);
  std::vector<double> row_sum(grid.height, 0.0);
  tbb::parallel_for(0, grid.height, [&](int row) {
    double sum = 0;
    std::vector<double> y;
    for (int col = 0; col < grid.width; ++col) {
      const auto cs =
          find_contributors(rig, grid.pixel_direction(col, row), depth_at(depth, col, row), search);
      if (cs.size() < 2) continue;  // MSE_w = 0 for a single contributor
      y.clear();
      for (const auto& c : cs) y.push_back(luma(sample_bilinear(frames[c.camera], c.px)));
      double mse = 0;  // eq. 4.19
      for (size_t j = 0; j < y.size(); ++j)
        for (size_t i = j + 1; i < y.size(); ++i) mse += (y[i] - y[j]) * (y[i] - y[j]);
      sum += mse / static_cast<double>(y.size());
    }
    row_sum[row] = sum;
  });
  double total = 0;
  for (double s : row_sum) total += s;
  const double mse_pan = total / (static_cast<double>(grid.width) * grid.height);  // eq. 4.20
  if (mse_pan <= 0) return std::numeric_limits<double>::infinity();
  return 20 * std::log10(1.0) - 10 * std::log10(mse_pan);  // eq. 4.21
}

}  // namespace omma::pano
