#include "omma/pano/weights.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace omma::pano {
namespace {

std::vector<double> normalise(std::vector<double> w) {
  double sum = 0;
  for (double x : w) sum += x;
  if (sum <= 0 || !std::isfinite(sum)) return std::vector<double>(w.size(), 0.0);
  for (double& x : w) x /= sum;
  return w;
}

double potential_of_camera(const std::vector<Contributor>& cs, const std::vector<double>& phi, int camera) {
  for (size_t k = 0; k < cs.size(); ++k)
    if (cs[k].camera == camera) return phi[k];
  return 0.0;  // camera does not see this neighbour: probability 0
}

}  // namespace

std::vector<double> node_potentials(const std::vector<Contributor>& cs, bool spherical) {
  std::vector<double> phi(cs.size());
  double r_max = 0;
  for (const auto& c : cs) r_max = std::max(r_max, c.r);
  for (size_t i = 0; i < cs.size(); ++i)
    phi[i] = 1.0 / (spherical ? spherical_arc_distance(cs[i].r, r_max) : cs[i].r);
  return normalise(phi);
}

std::vector<double> mrf_posterior(const std::vector<Contributor>& cs, const std::vector<double>& phi_u,
                                  const std::array<MrfNode, 4>& neighbours) {
  std::vector<double> weight = phi_u;
  for (const MrfNode& nb : neighbours) {
    if (nb.cs == nullptr) continue;
    for (size_t i = 0; i < cs.size(); ++i) weight[i] *= potential_of_camera(*nb.cs, *nb.phi, cs[i].camera);
  }
  double sum = 0;
  for (double x : weight) sum += x;
  if (!(sum > 0)) weight = phi_u;  // no camera sees the whole neighbourhood: prior alone
  return normalise(weight);
}

double spherical_arc_distance(double r, double r_max) {
  if (r_max <= 0) return r;
  return r_max * (kPi / 2 - std::acos(std::clamp(r / r_max, 0.0, 1.0)));  // eq. 4.10
}

std::array<std::array<int, 2>, 4> grid_neighbours(const PanoGrid& grid, int col, int row) {
  const bool wrap = grid.projection != Projection::kVr180;
  auto at = [&](int c, int r) -> std::array<int, 2> {
    if (r < 0 || r >= grid.height) return {-1, -1};
    if (c < 0 || c >= grid.width) {
      if (!wrap) return {-1, -1};
      c = (c + grid.width) % grid.width;
    }
    return {c, r};
  };
  return {at(col - 1, row), at(col + 1, row), at(col, row - 1), at(col, row + 1)};
}

std::vector<double> method_weights(const Rig& rig, Method method, const std::vector<Contributor>& cs,
                                   const std::array<const std::vector<Contributor>*, 4>& neighbours,
                                   const BlendParams& params) {
  std::vector<double> weight(cs.size(), 0.0);
  if (cs.empty()) return weight;
  switch (method) {
    case Method::kNearest: {  // eq. 2.6-2.7
      const auto best =
          std::min_element(cs.begin(), cs.end(), [](const auto& a, const auto& b) { return a.r < b.r; });
      weight[best - cs.begin()] = 1;
      break;
    }
    case Method::kLinear:  // eq. 2.8
      for (size_t i = 0; i < cs.size(); ++i) weight[i] = 1.0 / cs[i].r;
      break;
    case Method::kGaussian:  // eq. 2.9
      for (size_t i = 0; i < cs.size(); ++i) {
        const Intrinsics& in = rig.cameras[cs[i].camera].in;
        const double sigma = params.gaussian_sigma_rel * in.fu * std::tan(std::min(in.aov / 2, 1.5));
        const double d = (cs[i].px - Vec2(in.cu, in.cv)).norm();
        weight[i] = std::exp(-d * d / (2 * sigma * sigma)) / cs[i].r;
      }
      break;
    case Method::kMrf:           // eq. 4.8-4.9
    case Method::kMrfSpherical:  // eq. 4.10-4.11 combined with 4.8
    case Method::kSad: {         // prior of eq. 4.18 = the mrf posterior of §4.2.2
      const bool spherical = method == Method::kMrfSpherical;
      std::array<std::vector<double>, 4> phi_v;
      std::array<MrfNode, 4> nodes;
      for (int k = 0; k < 4; ++k)
        if (neighbours[k] != nullptr) {
          phi_v[k] = node_potentials(*neighbours[k], spherical);
          nodes[k] = {neighbours[k], &phi_v[k]};
        }
      return mrf_posterior(cs, node_potentials(cs, spherical), nodes);
    }
  }
  return normalise(weight);
}

std::vector<Tap> static_taps(const Rig& rig, const PanoGrid& grid, int col, int row, Method method,
                             const BlendParams& params) {
  const std::vector<Contributor> cs = find_contributors(rig, grid.pixel_direction(col, row), params.search);
  if (cs.empty()) return {};
  std::array<std::vector<Contributor>, 4> nb_storage;
  std::array<const std::vector<Contributor>*, 4> nb{nullptr, nullptr, nullptr, nullptr};
  if (uses_neighbours(method)) {
    const auto nbs = grid_neighbours(grid, col, row);
    for (int k = 0; k < 4; ++k) {
      if (nbs[k][0] < 0) continue;
      nb_storage[k] = find_contributors(rig, grid.pixel_direction(nbs[k][0], nbs[k][1]), params.search);
      nb[k] = &nb_storage[k];
    }
  }
  const std::vector<double> w = method_weights(rig, method, cs, nb, params);
  std::vector<Tap> taps;
  for (size_t i = 0; i < cs.size(); ++i)
    if (w[i] > 0) taps.push_back({cs[i].camera, cs[i].px, w[i]});
  return taps;
}

std::vector<double> sad_weights(const std::vector<Tap>& taps, const std::vector<double>& gray,
                                double sad_epsilon) {
  if (gray.size() != taps.size()) throw std::invalid_argument("sad_weights: one gray value per tap needed");
  std::vector<double> w(taps.size());
  for (size_t i = 0; i < taps.size(); ++i) {
    double sad = 0;  // eq. 4.17
    for (size_t j = 0; j < taps.size(); ++j) sad += std::abs(gray[i] - gray[j]);
    w[i] = taps[i].weight / (sad + sad_epsilon);  // eq. 4.18
  }
  return normalise(w);
}

}  // namespace omma::pano
