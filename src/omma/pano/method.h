// The six blending methods of the thesis (§2.4.2, ch. 4).
#pragma once

#include <string>
#include <vector>

namespace omma::pano {

enum class Method {
  kNearest,       // nn: nearest projected camera centre, MLE (eq. 2.6-2.7)
  kLinear,        // linear: expected value with 1/|r| weights (eq. 2.5, 2.8)
  kGaussian,      // gaussian: Gaussian-weighted (eq. 2.9)
  kMrf,           // mrf: MRF posterior over the 4-connected neighbourhood (eq. 4.8-4.9)
  kMrfSpherical,  // mrf-spherical: MRF with the spherical prior correction (eq. 4.10-4.11)
  kSad            // sad: inter-camera SAD evidence (eq. 4.17-4.18), per-frame weights
};

Method parse_method(const std::string& name);  // throws std::invalid_argument listing the names
std::string to_string(Method m);
const std::vector<Method>& all_methods();
// True for the methods whose weights depend only on the geometry (all but sad).
inline bool is_static(Method m) { return m != Method::kSad; }
// True for the MRF family (mrf, mrf-spherical, and sad on the mrf prior): their weights at a
// direction depend on the contributors of its 4-connected neighbours (eq. 4.8).
inline bool uses_neighbours(Method m) {
  return m == Method::kMrf || m == Method::kMrfSpherical || m == Method::kSad;
}

}  // namespace omma::pano
