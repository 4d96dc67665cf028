#include "omma/pano/surface.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "omma/core/io.h"

namespace omma::pano {

void check_depth(const cv::Mat& depth, const PanoGrid& grid, const std::string& what) {
  if (depth.empty()) return;
  if (depth.type() != CV_32FC1) throw std::invalid_argument(what + ": must be one-channel 32-bit float (mm)");
  if (depth.cols != grid.width || depth.rows != grid.height)
    throw std::invalid_argument(fmt::format("{} is {}x{}, the panorama is {}x{}", what, depth.cols,
                                            depth.rows, grid.width, grid.height));
  for (int r = 0; r < depth.rows; ++r) {
    const float* p = depth.ptr<float>(r);
    for (int c = 0; c < depth.cols; ++c)
      if (!(p[c] > 0))
        throw std::invalid_argument(fmt::format(
            "{}: value {} at pixel ({}, {}); depths must be > 0 mm (+inf = infinity)", what, p[c], c, r));
  }
}

namespace {

// The distance of the farthest camera centre from the dome centre: a surface must lie beyond it.
double farthest_camera_mm(const Rig& rig) {
  double d = 0;
  for (const auto& cam : rig.cameras) d = std::max(d, cam.position_mm.norm());
  return d;
}

}  // namespace

void check_depth_outside_dome(const cv::Mat& depth, const Rig& rig, const PanoGrid& grid, const Vec3& q,
                              const std::string& what) {
  check_depth(depth, grid, what);
  const double inner = farthest_camera_mm(rig);
  for (int r = 0; r < depth.rows; ++r) {
    const float* p = depth.ptr<float>(r);
    for (int c = 0; c < depth.cols; ++c)
      if (std::isfinite(p[c]) && (q + double(p[c]) * grid.pixel_direction(c, r)).norm() <= inner)
        throw std::invalid_argument(fmt::format(
            "{}: depth {} mm at pixel ({}, {}) puts the surface inside the dome (it must lie farther than "
            "{:.2f} mm from the dome centre, the farthest camera centre)",
            what, p[c], c, r, inner));
  }
}

cv::Mat sphere_depth(const Rig& rig, const PanoGrid& grid, double radius_mm, const Vec3& q) {
  if (!(radius_mm > 0) || !std::isfinite(radius_mm))
    throw std::invalid_argument(
        fmt::format("sphere radius must be a positive number of mm, got {}", radius_mm));
  const double inner = std::max(q.norm(), farthest_camera_mm(rig));
  if (radius_mm <= inner)
    throw std::invalid_argument(fmt::format(
        "sphere radius {} mm is inside the dome: it must exceed {:.2f} mm (the farthest camera centre)",
        radius_mm, inner));
  cv::Mat out(grid.height, grid.width, CV_32FC1);
  for (int r = 0; r < grid.height; ++r)
    for (int c = 0; c < grid.width; ++c) {
      const double qw = q.dot(grid.pixel_direction(c, r));
      out.at<float>(r, c) =
          static_cast<float>(-qw + std::sqrt(qw * qw - q.squaredNorm() + radius_mm * radius_mm));
    }
  return out;
}

cv::Mat read_depth(const std::filesystem::path& path, const PanoGrid& grid) {
  cv::Mat raw = read_image(path);
  if (raw.channels() != 1)
    throw std::invalid_argument(
        fmt::format("depth file {} has {} channels (need 1)", path.string(), raw.channels()));
  cv::Mat depth;
  if (raw.depth() == CV_32F) {
    depth = raw;
  } else if (raw.depth() == CV_16U) {  // 1/100 mm, 0 = infinity
    raw.convertTo(depth, CV_32F, 0.01);
    depth.setTo(std::numeric_limits<float>::infinity(), raw == 0);
  } else {
    throw std::invalid_argument(
        fmt::format("depth file {}: need 32-bit float (mm) or 16-bit (1/100 mm) values", path.string()));
  }
  check_depth(depth, grid, "depth file " + path.string());
  return depth;
}

void write_depth(const std::filesystem::path& path, const cv::Mat& depth) {
  if (depth.type() != CV_32FC1) throw std::invalid_argument("write_depth: depth must be CV_32FC1 (mm)");
  write_image(path, depth);
}

namespace {

std::pair<double, double> percentile_range(const cv::Mat& depth) {
  std::vector<float> v;
  v.reserve(depth.total());
  for (int r = 0; r < depth.rows; ++r)
    for (int c = 0; c < depth.cols; ++c) {
      const float d = depth.at<float>(r, c);
      if (std::isfinite(d) && d > 0) v.push_back(d);
    }
  if (v.empty()) return {1, 2};
  const auto at = [&](double q) {
    auto it = v.begin() + static_cast<long>(q * (v.size() - 1));
    std::nth_element(v.begin(), it, v.end());
    return static_cast<double>(*it);
  };
  const double lo = at(0.02), hi = at(0.98);
  return {lo, std::max(hi, lo * 1.01)};
}

}  // namespace

cv::Mat depth_colormap(const cv::Mat& depth, double near_mm, double far_mm, const std::string& title) {
  if (depth.empty() || depth.type() != CV_32FC1)
    throw std::invalid_argument("depth_colormap: CV_32FC1 needed");
  if (near_mm <= 0 || far_mm <= near_mm) std::tie(near_mm, far_mm) = percentile_range(depth);
  // Inverse depth in [1/far, 1/near] -> 0..255 (255 = near), turbo colours.
  const double s0 = 1 / far_mm, s1 = 1 / near_mm;
  cv::Mat index(depth.size(), CV_8UC1);
  for (int r = 0; r < depth.rows; ++r)
    for (int c = 0; c < depth.cols; ++c) {
      const double s = 1 / static_cast<double>(depth.at<float>(r, c));
      index.at<uint8_t>(r, c) =
          static_cast<uint8_t>(std::lround(255 * std::clamp((s - s0) / (s1 - s0), 0.0, 1.0)));
    }
  cv::Mat colour;
  cv::applyColorMap(index, colour, cv::COLORMAP_TURBO);
  colour.setTo(cv::Scalar(0, 0, 0), depth == std::numeric_limits<float>::infinity());
  // Legend: a colour bar with ticks in mm underneath.
  const int W = std::max(depth.cols, 360);
  const double font = std::clamp(W / 1400.0, 0.4, 1.0);
  const int line = static_cast<int>(std::lround(30 * font / 0.6));
  cv::Mat out(depth.rows + 3 * line, W, CV_8UC3, cv::Scalar(40, 40, 40));
  colour.copyTo(out(cv::Rect(0, 0, depth.cols, depth.rows)));
  const int y0 = depth.rows;
  cv::putText(out, fmt::format("{} (mm, colour = 1/depth; black = infinity)", title),
              {line / 2, y0 + line - 6}, cv::FONT_HERSHEY_SIMPLEX, font, cv::Scalar(255, 255, 255), 1,
              cv::LINE_AA);
  const int bx0 = line / 2, bx1 = W - line / 2, by = y0 + line + 2, bh = line / 2;
  for (int x = bx0; x < bx1; ++x) {
    // left = far, right = near (inverse depth grows to the right)
    const int i = static_cast<int>(std::lround(255.0 * (x - bx0) / std::max(1, bx1 - bx0 - 1)));
    cv::Mat one(1, 1, CV_8UC1, cv::Scalar(i)), col;
    cv::applyColorMap(one, col, cv::COLORMAP_TURBO);
    const cv::Vec3b v = col.at<cv::Vec3b>(0, 0);
    cv::line(out, {x, by}, {x, by + bh}, cv::Scalar(v[0], v[1], v[2]));
  }
  for (int k = 0; k <= 4; ++k) {
    const double s = s0 + (s1 - s0) * k / 4.0;
    const int x = bx0 + static_cast<int>(std::lround((bx1 - bx0 - 1) * k / 4.0));
    cv::line(out, {x, by + bh}, {x, by + bh + 4}, cv::Scalar(255, 255, 255));
    const std::string label = fmt::format("{:.1f}", 1 / s);
    int base = 0;
    const cv::Size ts = cv::getTextSize(label, cv::FONT_HERSHEY_SIMPLEX, font, 1, &base);
    const int tx = std::clamp(x - ts.width / 2, 0, W - ts.width);
    cv::putText(out, label, {tx, by + bh + 6 + ts.height}, cv::FONT_HERSHEY_SIMPLEX, font,
                cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  }
  return out;
}

}  // namespace omma::pano
