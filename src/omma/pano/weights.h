// Blending weights per output pixel: the taps that both the reference stitcher (pano/) and the
// compiled maps of the engine (engine/) use.
//
// Static (geometry-only) methods, thesis §2.4.2 and §4.2.2. For a direction w_u with contributing
// cameras I (eq. 2.3) and orthographic distances |r_i| (eq. 2.5), the weights are
//   nn            p_i = 1 for i = argmin |r_i|, else 0                          (eq. 2.6-2.7)
//   linear        p_i = 1/|r_i|                                               (eq. 2.8 / 4.7)
//   gaussian      p_i = 1/|r_i| * exp(-d_i^2 / (2 sigma_d^2))                  (eq. 2.9)
//                 d_i = distance (px) of the candidate pixel from camera i's principal point
//   mrf           p_iu = phi_iu * prod_{v in N_u} phi_iv,  phi = 1/|r|         (eq. 4.8-4.9)
//                 N_u = the 4-connected neighbours of pixel u on the output grid (left/right wrap
//                 around on the 360-degree equirect grids; neighbours off the grid are skipped).
//                 phi_iv = 0 when camera i does not see neighbour v (its probability there is 0).
//                 If that leaves every p_iu = 0 (only possible at a camera's border), the
//                 prior phi_iu is used alone.
//   mrf-spherical as mrf with phi = 1/a, a_i = r_max * (pi/2 - acos(|r_i|/r_max)),
//                 r_max = max_i |r_i| over the cameras of that node                 (eq. 4.10-4.11)
// All weights are normalised to sum to 1 (the 1/Z of eq. 4.8). Where only one camera sees w every
// method reduces to that camera with weight 1.
//
// The sad method (eq. 4.17-4.18) is per frame: its geometric prior p_iu is the mrf posterior
// (static_taps(..., kSad, ...) returns exactly the mrf taps), and sad_weights() multiplies it with
// the per-frame evidence 1/SAD_i computed from the sampled gray intensities of those taps.
#pragma once

#include <array>
#include <vector>

#include "omma/core/grid.h"
#include "omma/pano/contributors.h"
#include "omma/pano/method.h"

namespace omma::pano {

struct BlendParams {
  SearchOptions search;
  // sigma_d of eq. 2.9 as a fraction of the camera's cone radius in pixels, fu * tan(aov/2).
  // 0.5 gives a candidate pixel at the cone edge exp(-2) = 0.135 of the centre's confidence.
  double gaussian_sigma_rel = 0.5;
  // eq. 4.18: the SAD evidence is 1 / (SAD_i + sad_epsilon); intensities are gray (Y) in [0, 1].
  double sad_epsilon = 1.0 / 255;
};

struct Tap {
  int camera = 0;          // index into rig.cameras
  Vec2 px = Vec2::Zero();  // continuous pixel coordinate in that camera (centres at integer + 0.5)
  double weight = 0;
};

// Taps of output pixel (col, row) for a static method (nn, linear, gaussian, mrf, mrf-spherical);
// the weights sum to 1; empty if no camera sees the direction. Taps with weight 0 are left out.
// For sad this returns the geometric prior of eq. 4.18, i.e. the mrf taps.
std::vector<Tap> static_taps(const Rig& rig, const PanoGrid& grid, int col, int row, Method method,
                             const BlendParams& params = {});

// The same computation from contributors already found (the stitcher computes them once per
// output pixel): `centre` are the contributors of u, `neighbours` those of its 4-connected
// neighbours (nullptr where the neighbour is off the grid). Neighbours are only used by mrf,
// mrf-spherical and sad. Returns one weight per entry of `centre`, summing to 1 (all 0 if
// `centre` is empty).
std::vector<double> method_weights(const Rig& rig, Method method, const std::vector<Contributor>& centre,
                                   const std::array<const std::vector<Contributor>*, 4>& neighbours,
                                   const BlendParams& params = {});

// eq. 4.8: the potential phi_i of every contributor of one node, 1/|r_i| (mrf, sad) or 1/a_i
// (mrf-spherical, eq. 4.10), normalised over the node's cameras (a per-node constant, absorbed by Z
// of eq. 4.8; it keeps the product of five factors in range).
std::vector<double> node_potentials(const std::vector<Contributor>& cs, bool spherical);

// One node of the 4-neighbourhood for mrf_posterior: its contributors and their potentials
// (node_potentials); cs == nullptr where the neighbour is off the grid.
struct MrfNode {
  const std::vector<Contributor>* cs = nullptr;
  const std::vector<double>* phi = nullptr;
};

// eq. 4.8-4.9: p_i = phi_i(u) * prod over the neighbours v of phi_i(v) (0 where camera i does not
// see v), normalised; the prior phi(u) alone if no camera sees the whole neighbourhood. This is
// what method_weights computes for mrf, mrf-spherical and sad; callers that visit every node
// (the engine's map compiler) compute each node's potentials once and call this directly.
std::vector<double> mrf_posterior(const std::vector<Contributor>& centre,
                                  const std::vector<double>& phi_centre,
                                  const std::array<MrfNode, 4>& neighbours);

// The 4-connected neighbours (left, right, up, down) of (col, row) on `grid`, as (col, row) pairs;
// {-1, -1} where there is none. Equirect grids wrap around horizontally (phi is periodic).
std::array<std::array<int, 2>, 4> grid_neighbours(const PanoGrid& grid, int col, int row);

// eq. 4.10: arc distance a_i = r_max * (pi/2 - acos(|r_i| / r_max)) of the spherical prior.
double spherical_arc_distance(double r, double r_max);

// eq. 4.17-4.18, per frame: taps = the geometric prior (static_taps(..., kSad) or the engine's
// compiled equivalent), gray = the gray (Y, [0,1]) intensity each tap samples in the current frame.
// SAD_i = sum_j |I_i - I_j| over the taps; returns p_i / (SAD_i + eps), normalised to sum to 1.
// With one tap it returns {1}; with two taps SAD_1 = SAD_2 and the prior is unchanged.
std::vector<double> sad_weights(const std::vector<Tap>& taps, const std::vector<double>& gray,
                                double sad_epsilon = 1.0 / 255);

}  // namespace omma::pano
