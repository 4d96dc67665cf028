#include "omma/testing/synthetic.h"

#include <cmath>

#include <opencv2/imgproc.hpp>

#include "omma/core/geometry.h"

namespace omma::testing {

Rig ring_rig_24(int width, int height, double aov_deg) {
  Rig rig;
  rig.name = "ring-24";
  rig.dome.radius_mm = 5.0;
  rig.dome.sphere = false;
  rig.dome.method = "ring (engine test rig)";
  const struct { int n; double polar_deg; double phase_deg; } rings[] = {{3, 12, 0}, {9, 38, 20}, {12, 70, 0}};
  int id = 0;
  for (const auto& ring : rings)
    for (int k = 0; k < ring.n; ++k) {
      const double phi = deg2rad(ring.phase_deg + 360.0 * k / ring.n);
      const Vec3 t = direction_from_spherical(deg2rad(ring.polar_deg), phi);
      // "down" in the image: away from the dome axis (towards larger theta).
      const Vec3 down = direction_from_spherical(deg2rad(ring.polar_deg + 90), phi);
      RigCamera cam;
      cam.id = id++;
      cam.frame = frame_looking_at(t, down);
      cam.position_mm = rig.dome.radius_mm * t;
      cam.in.width = width;
      cam.in.height = height;
      cam.in.aov = deg2rad(aov_deg);
      cam.in.fu = cam.in.fv = Intrinsics::focal_for_aov(width, cam.in.aov);
      cam.in.cu = width / 2.0;
      cam.in.cv = height / 2.0;
      rig.cameras.push_back(cam);
    }
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
