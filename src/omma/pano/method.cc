#include "omma/pano/method.h"

#include <stdexcept>

namespace omma::pano {

Method parse_method(const std::string& name) {
  for (Method m : all_methods())
    if (to_string(m) == name) return m;
  throw std::invalid_argument("unknown method '" + name +
                              "' (use nn, linear, gaussian, mrf, mrf-spherical or sad)");
}

std::string to_string(Method m) {
  switch (m) {
    case Method::kNearest:
      return "nn";
    case Method::kLinear:
      return "linear";
    case Method::kGaussian:
      return "gaussian";
    case Method::kMrf:
      return "mrf";
    case Method::kMrfSpherical:
      return "mrf-spherical";
    case Method::kSad:
      return "sad";
  }
  return "?";
}

const std::vector<Method>& all_methods() {
  static const std::vector<Method> v = {Method::kNearest, Method::kLinear,       Method::kGaussian,
                                        Method::kMrf,     Method::kMrfSpherical, Method::kSad};
  return v;
}

}  // namespace omma::pano
