// The smallest program built against an installed omma (CMakeLists.txt beside it): the thesis's
// 24-camera dome looks at a textured sphere 10 m away in the simulator, the reference stitcher blends the
// frames into a small vr180 panorama, and the panorama is judged against the simulator's truth.
// Prints one line; exits 1 if the panorama is not close to the truth.
#include <cstdio>

#include "omma/core/version.h"
#include "omma/design/prototype.h"
#include "omma/pano/quality.h"
#include "omma/pano/stitch.h"
#include "omma/sim/scene.h"
#include "omma/sim/simulate.h"

int main() {
  const omma::Rig rig = omma::design::thesis_prototype_rig();
  const auto scene = omma::sim::make_checker_scene(10000.0);
  omma::sim::SimulateOptions sim;
  sim.effects = omma::sim::CameraEffects::ideal(3);
  sim.truth_grid = {omma::Projection::kVr180, 270, 270};
  sim.progress = false;
  const omma::sim::SimulateSummary frames = omma::sim::simulate(rig, *scene, sim);

  std::vector<cv::Mat> images;
  for (const auto& f : frames.frames) images.push_back(f.image);
  omma::pano::StitchOptions stitch;
  stitch.method = omma::pano::Method::kLinear;
  stitch.grid = sim.truth_grid;
  stitch.progress = false;
  cv::Mat pano;
  omma::pano::stitch(rig, images, stitch).convertTo(pano, CV_8UC3, 255.0);

  const double db = omma::pano::psnr_db(pano, frames.truth);
  std::printf("omma %s: %zu cameras, %dx%d vr180 panorama, %.2f dB against the truth\n",
              omma::version().c_str(), rig.cameras.size(), pano.cols, pano.rows, db);
  return db > 25 ? 0 : 1;
}
