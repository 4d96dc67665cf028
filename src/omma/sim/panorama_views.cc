#include "omma/sim/panorama_views.h"

#include <opencv2/imgproc.hpp>

#include "omma/core/geometry.h"
#include "omma/core/grid.h"

namespace omma::sim {

std::vector<cv::Mat> panorama_to_camera_maps(const Rig& rig, cv::Size pano_size, double yaw_rad) {
  std::vector<cv::Mat> maps;
  for (const auto& cam : rig.cameras) {
    const CameraModel m = cam.model();
    cv::Mat map(cam.in.height, cam.in.width, CV_32FC2);
    for (int y = 0; y < cam.in.height; ++y)
      for (int x = 0; x < cam.in.width; ++x) {
        const Vec3 w = m.unproject(Vec2(x + 0.5, y + 0.5));
        const Spherical s = spherical_from_direction(w);
        // The panorama is an equirect-full grid (conventions.h (G1)), turned by yaw about +z.
        map.at<cv::Vec2f>(y, x) = cv::Vec2f(float(equirect_x(s.phi + yaw_rad, pano_size.width) - 0.5),
                                            float(s.theta / kPi * pano_size.height - 0.5));
      }
    maps.push_back(map);
  }
  return maps;
}

std::vector<cv::Mat> views_of_panorama(const Rig& rig, const cv::Mat& pano, double yaw_rad) {
  std::vector<cv::Mat> out;
  for (const cv::Mat& map : panorama_to_camera_maps(rig, pano.size(), yaw_rad)) {
    cv::Mat v;
    cv::remap(pano, v, map, cv::noArray(), cv::INTER_LINEAR, cv::BORDER_WRAP);
    out.push_back(v);
  }
  return out;
}

}  // namespace omma::sim
