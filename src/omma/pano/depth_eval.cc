#include "omma/pano/depth_eval.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <opencv2/imgproc.hpp>

namespace omma::pano {

cv::Mat clamp_depth(const cv::Mat& depth, double max_mm) {
  if (depth.type() != CV_32FC1) throw std::invalid_argument("clamp_depth: CV_32FC1 needed");
  cv::Mat out = depth.clone();
  out.setTo(static_cast<float>(max_mm), ~(depth <= max_mm));  // also +inf (and NaN)
  return out;
}

DepthError depth_error(const cv::Mat& est, const cv::Mat& truth, double max_mm, const cv::Mat& mask) {
  if (est.type() != CV_32FC1 || truth.type() != CV_32FC1 || est.size() != truth.size())
    throw std::invalid_argument("depth_error: two CV_32FC1 maps of the same size needed");
  std::vector<double> rel;
  for (int r = 0; r < truth.rows; ++r)
    for (int c = 0; c < truth.cols; ++c) {
      const double t = truth.at<float>(r, c);
      if (!(t <= max_mm) || (!mask.empty() && mask.at<uint8_t>(r, c) == 0)) continue;
      rel.push_back(std::abs(est.at<float>(r, c) - t) / t);
    }
  DepthError e;
  e.pixels = static_cast<long>(rel.size());
  if (rel.empty()) return e;
  double sum = 0;
  long within = 0;
  for (double x : rel) {
    sum += x;
    within += x < 0.1;
  }
  e.mean_rel = sum / rel.size();
  e.within_10 = double(within) / rel.size();
  std::nth_element(rel.begin(), rel.begin() + rel.size() / 2, rel.end());
  e.median_rel = rel[rel.size() / 2];
  return e;
}

cv::Mat depth_jump_map(const cv::Mat& depth) {
  if (depth.type() != CV_32FC1) throw std::invalid_argument("depth_jump_map: CV_32FC1 needed");
  cv::Mat out(depth.size(), CV_32FC1, cv::Scalar(0));
  auto mark = [&](int r, int c, int r2, int c2) {
    const float a = depth.at<float>(r, c), b = depth.at<float>(r2, c2);
    if (std::isinf(a) && std::isinf(b)) return;
    float& near = a <= b ? out.at<float>(r, c) : out.at<float>(r2, c2);
    const float jump =
        std::isinf(std::max(a, b)) ? 10.f : std::min(10.f, std::max(a, b) / std::min(a, b) - 1);
    near = std::max(near, jump);
  };
  for (int r = 0; r < depth.rows; ++r)
    for (int c = 0; c < depth.cols; ++c) {
      if (c + 1 < depth.cols) mark(r, c, r, c + 1);
      if (r + 1 < depth.rows) mark(r, c, r + 1, c);
    }
  return out;
}

cv::Mat depth_discontinuities(const cv::Mat& depth, double ratio) {
  cv::Mat out = depth_jump_map(depth) > ratio - 1;
  return out;
}

BoundaryScore boundary_score(const cv::Mat& pred, const cv::Mat& truth, int tol, const cv::Mat& mask) {
  if (pred.type() != CV_8UC1 || truth.type() != CV_8UC1 || pred.size() != truth.size())
    throw std::invalid_argument("boundary_score: two CV_8UC1 maps of the same size needed");
  cv::Mat m = mask.empty() ? cv::Mat(pred.size(), CV_8UC1, cv::Scalar(255)) : (mask != 0);
  cv::Mat p = (pred != 0) & m, t = (truth != 0) & m;
  const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * tol + 1, 2 * tol + 1));
  cv::Mat p_grown, t_grown;
  cv::dilate(p, p_grown, kernel);
  cv::dilate(t, t_grown, kernel);
  BoundaryScore s;
  s.predicted = cv::countNonZero(p);
  s.truth = cv::countNonZero(t);
  s.precision = s.predicted ? double(cv::countNonZero(p & t_grown)) / s.predicted : 0;
  s.recall = s.truth ? double(cv::countNonZero(t & p_grown)) / s.truth : 0;
  s.f1 = s.precision + s.recall > 0 ? 2 * s.precision * s.recall / (s.precision + s.recall) : 0;
  return s;
}

BoundaryScore best_boundary_score(const cv::Mat& boundary, const cv::Mat& truth, int tol, double* threshold,
                                  const cv::Mat& mask) {
  if (boundary.type() != CV_32FC1)
    throw std::invalid_argument("best_boundary_score: CV_32FC1 boundary map needed");
  BoundaryScore best;
  double best_th = 0;
  for (int i = 1; i <= 100; ++i) {
    const double th = 0.005 * i;
    const BoundaryScore s = boundary_score(boundary > th, truth, tol, mask);  // eq. 4.16
    if (s.f1 > best.f1) {
      best = s;
      best_th = th;
    }
  }
  if (threshold) *threshold = best_th;
  return best;
}

}  // namespace omma::pano
