#include "omma/testing/synthetic.h"

#include <cmath>

#include <opencv2/imgproc.hpp>

#include "omma/core/geometry.h"
#include "omma/design/dome.h"
#include "omma/design/prototype.h"

namespace omma::testing {

Rig test_rig_24(int width, int height, double aov_deg) {
  Rig rig = design::thesis_prototype_rig();
  const Intrinsics in = design::ideal_intrinsics(deg2rad(aov_deg), width, height);
  for (auto& cam : rig.cameras) cam.in = in;
  rig.validate();
  return rig;
}

std::vector<cv::Mat> random_frames(const Rig& rig, uint32_t seed) {
  cv::RNG rng(seed);
  std::vector<cv::Mat> out;
  for (const auto& cam : rig.cameras) {
    cv::Mat m(cam.in.height, cam.in.width, CV_8UC3);
    rng.fill(m, cv::RNG::UNIFORM, 0, 256);
    cv::GaussianBlur(m, m, cv::Size(0, 0), 1.0);
    out.push_back(m);
  }
  return out;
}

}  // namespace omma::testing
