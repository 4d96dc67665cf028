#include "omma/pano/stitch.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "omma/core/frames.h"
#include "omma/core/progress.h"
#include "omma/core/valid.h"

namespace omma::pano {

bool StitchOptions::IsValid(std::string* why) const {
  if (grid.width <= 0 || grid.height <= 0) return invalid(why, "panorama size must be positive");
  if (!blend.search.IsValid(why)) return false;
  if (!(blend.gaussian_sigma_rel > 0)) return invalid(why, "gaussian_sigma_rel must be > 0");
  if (!(blend.sad_epsilon > 0)) return invalid(why, "sad_epsilon must be > 0");
  return true;
}

void check_frames(const Rig& rig, const std::vector<cv::Mat>& frames) {
  if (rig.cameras.empty()) throw std::invalid_argument("the rig has no cameras");
  if (frames.size() != rig.cameras.size())
    throw std::invalid_argument(
        fmt::format("{} frames for a rig of {} cameras", frames.size(), rig.cameras.size()));
  for (size_t i = 0; i < frames.size(); ++i) {
    const auto& f = frames[i];
    const auto& in = rig.cameras[i].in;
    if (f.empty()) throw std::invalid_argument(fmt::format("frame of camera {} is empty", rig.cameras[i].id));
    if (f.cols != in.width || f.rows != in.height)
      throw std::invalid_argument(fmt::format("frame of camera {} is {}x{}, the rig says {}x{}",
                                              rig.cameras[i].id, f.cols, f.rows, in.width, in.height));
    if (f.channels() != 1 && f.channels() != 3)
      throw std::invalid_argument(
          fmt::format("frame of camera {} has {} channels (need 1 or 3)", rig.cameras[i].id, f.channels()));
  }
}

std::vector<cv::Mat> frames_to_float(const std::vector<cv::Mat>& frames) {
  std::vector<cv::Mat> out;
  out.reserve(frames.size());
  for (const auto& f : frames) {
    cv::Mat g = to_float01(f);
    if (g.channels() == 1) cv::cvtColor(g, g, cv::COLOR_GRAY2BGR);
    out.push_back(g);
  }
  return out;
}

cv::Vec3f sample_bilinear(const cv::Mat& img, const Vec2& px) {
  // Continuous coordinate with centres at +0.5 -> index space with centres at integers.
  const double x = px.x() - 0.5, y = px.y() - 0.5;
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const float fx = static_cast<float>(x - x0), fy = static_cast<float>(y - y0);
  auto at = [&](int c, int r) {
    c = std::clamp(c, 0, img.cols - 1);
    r = std::clamp(r, 0, img.rows - 1);
    return img.at<cv::Vec3f>(r, c);
  };
  return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) +
         fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
}

void for_each_pixel_weights(const Rig& rig, const StitchOptions& opt, const PixelWeightsFn& f,
                            Progress* progress) {
  const PanoGrid& grid = opt.grid;
  std::string why;
  if (!opt.IsValid(&why)) throw std::invalid_argument(why);
  check_depth(opt.depth, grid);
  const bool needs_neighbours = uses_neighbours(opt.method);
  // Work in blocks of rows. Each block finds the contributors (eq. 2.3, 5.21-5.26) of its rows and,
  // for the MRF family, of the row above and below it (eq. 4.8's 4-neighbourhood), then weighs.
  tbb::parallel_for(tbb::blocked_range<int>(0, grid.height, 8), [&](const tbb::blocked_range<int>& block) {
    const int first = needs_neighbours ? std::max(0, block.begin() - 1) : block.begin();
    const int last = needs_neighbours ? std::min(grid.height, block.end() + 1) : block.end();
    std::vector<std::vector<std::vector<Contributor>>> rows(last - first);
    for (int r = first; r < last; ++r) {
      auto& cs = rows[r - first];
      cs.resize(grid.width);
      for (int c = 0; c < grid.width; ++c)
        cs[c] =
            find_contributors(rig, grid.pixel_direction(c, r), depth_at(opt.depth, c, r), opt.blend.search);
    }
    auto at = [&](int c, int r) -> const std::vector<Contributor>* { return &rows[r - first][c]; };
    for (int row = block.begin(); row < block.end(); ++row) {
      for (int col = 0; col < grid.width; ++col) {
        const auto& cs = *at(col, row);
        if (cs.empty()) continue;
        std::array<const std::vector<Contributor>*, 4> nb{nullptr, nullptr, nullptr, nullptr};
        if (needs_neighbours) {
          const auto n = grid_neighbours(grid, col, row);  // left, right, up, down
          for (int k = 0; k < 4; ++k)
            if (n[k][0] >= 0) nb[k] = at(n[k][0], n[k][1]);
        }
        f(col, row, cs, method_weights(rig, opt.method, cs, nb, opt.blend));
      }
      if (progress) progress->step();
    }
  });
}

cv::Mat stitch(const Rig& rig, const std::vector<cv::Mat>& frames_in, const StitchOptions& opt) {
  check_frames(rig, frames_in);
  const PanoGrid& grid = opt.grid;
  std::string why;
  if (!opt.IsValid(&why)) throw std::invalid_argument(why);
  const std::vector<cv::Mat> frames = frames_to_float(frames_in);
  cv::Mat pano(grid.height, grid.width, CV_32FC3, cv::Scalar::all(0));
  Progress progress("stitch " + to_string(opt.method), grid.height, opt.progress);
  // One output pixel: the method's weights, bilinear samples, weighted sum.
  for_each_pixel_weights(
      rig, opt,
      [&](int col, int row, const std::vector<Contributor>& cs, const std::vector<double>& weights) {
        std::vector<double> w = weights;
        std::vector<cv::Vec3f> samples(cs.size());
        for (size_t i = 0; i < cs.size(); ++i)
          if (w[i] > 0) samples[i] = sample_bilinear(frames[cs[i].camera], cs[i].px);
        if (opt.method == Method::kSad) {  // eq. 4.17-4.18 over the cameras with a non-zero prior
          std::vector<Tap> taps;
          std::vector<double> gray;
          std::vector<size_t> index;
          for (size_t i = 0; i < cs.size(); ++i) {
            if (w[i] <= 0) continue;
            taps.push_back({cs[i].camera, cs[i].px, w[i]});
            gray.push_back(luma(samples[i]));
            index.push_back(i);
          }
          const std::vector<double> ws = sad_weights(taps, gray, opt.blend.sad_epsilon);
          std::fill(w.begin(), w.end(), 0.0);
          for (size_t k = 0; k < index.size(); ++k) w[index[k]] = ws[k];
        }
        cv::Vec3d sum(0, 0, 0);
        for (size_t i = 0; i < cs.size(); ++i)
          if (w[i] > 0) sum += w[i] * cv::Vec3d(samples[i]);
        pano.at<cv::Vec3f>(row, col) = cv::Vec3f(sum);
      },
      &progress);
  progress.finish();
  return pano;
}

}  // namespace omma::pano
