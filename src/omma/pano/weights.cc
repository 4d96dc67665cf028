#include "omma/pano/weights.h"

#include <algorithm>
#include <stdexcept>

namespace omma::pano {
namespace {

std::vector<Tap> normalised(const std::vector<Contributor>& cs, const std::vector<double>& w) {
  double sum = 0;
  for (double x : w) sum += x;
  std::vector<Tap> taps;
  if (sum <= 0) return taps;
  for (size_t i = 0; i < cs.size(); ++i)
    if (w[i] > 0) taps.push_back({cs[i].camera, cs[i].px, w[i] / sum});
  return taps;
}

}  // namespace

std::vector<Tap> static_taps(const Rig& rig, const PanoGrid& grid, int col, int row, Method method,
                             const BlendParams& params) {
  const Vec3 w = grid.pixel_direction(col, row);
  const std::vector<Contributor> cs = find_contributors(rig, w, params.search);
  if (cs.empty()) return {};
  std::vector<double> weight(cs.size(), 0.0);
  switch (method) {
    case Method::kNearest: {  // eq. 2.6-2.7
      const auto best = std::min_element(cs.begin(), cs.end(),
                                         [](const auto& a, const auto& b) { return a.r < b.r; });
      weight[best - cs.begin()] = 1;
      break;
    }
    case Method::kLinear:  // eq. 2.8
    case Method::kSad:
      for (size_t i = 0; i < cs.size(); ++i) weight[i] = 1.0 / cs[i].r;
      break;
    default:
      throw std::logic_error("method " + to_string(method) + " is not implemented yet");
  }
  return normalised(cs, weight);
}

}  // namespace omma::pano
