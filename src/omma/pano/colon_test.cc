// The six methods on the simulated colon (near field, parallax) seen by the 24-camera prototype,
// with the simulator's default sensor effects (vignetting, +-10 % colour gains, shot and read noise,
// 10-bit quantisation) at one ray per pixel to keep the test short.
#include <cstdio>
#include <map>

#include <gtest/gtest.h>

#include "omma/design/prototype.h"
#include "omma/pano/maps.h"
#include "omma/pano/quality.h"
#include "omma/pano/stitch.h"
#include "omma/sim/simulate.h"

namespace omma::pano {
namespace {

struct Simulated {
  std::vector<cv::Mat> frames;
  cv::Mat truth;
};

Simulated simulate(const Rig& rig, const sim::Scene& scene, const PanoGrid& grid) {
  sim::SimulateOptions so;
  so.effects.supersample = 1;
  so.truth_grid = grid;
  so.truth_supersample = 1;
  so.progress = false;
  const auto r = sim::simulate(rig, scene, so);
  Simulated s;
  for (const auto& f : r.frames) s.frames.push_back(f.image);
  s.truth = r.truth;
  return s;
}

TEST(PanoColon, AllMethodsAgainstTheTruth) {
  const Rig rig = design::thesis_prototype_rig();
  const PanoGrid grid{Projection::kVr180, 270, 270};
  const Simulated colon = simulate(rig, *sim::make_colon_scene(), grid);
  const Simulated photo =
      simulate(rig, *sim::make_photo_scene(std::string(OMMA_DATA_DIR) + "/louvre.jpg"), grid);
  const cv::Mat seam = seam_mask(coverage_map(rig, grid), false);
  std::map<Method, EvalSummary> r;
  for (Method m : all_methods()) {
    StitchOptions opt;
    opt.method = m;
    opt.grid = grid;
    opt.progress = false;
    r[m] = evaluate(stitch(rig, colon.frames, opt), colon.truth, seam);
    std::printf("colon vr180 270x270  %-14s PSNR %6.2f dB  SSIM %.4f  seam PSNR %6.2f dB\n",
                to_string(m).c_str(), r[m].psnr_db, r[m].ssim, r[m].seam_psnr_db);
  }
  const double icp_colon = inter_camera_psnr(rig, colon.frames, grid);
  const double icp_photo = inter_camera_psnr(rig, photo.frames, grid);
  const cv::Mat b_colon = boundary_map(rig, colon.frames, grid),
                b_photo = boundary_map(rig, photo.frames, grid);
  const double above_colon =
      cv::countNonZero(boundary_binary(b_colon, 0.2)) / double(grid.width * grid.height);
  const double above_photo =
      cv::countNonZero(boundary_binary(b_photo, 0.2)) / double(grid.width * grid.height);
  std::printf(
      "inter-camera PSNR: colon %.2f dB, louvre %.2f dB; L_ob > 0.2 on %.2f %% (colon), %.2f %% (louvre)\n",
      icp_colon, icp_photo, 100 * above_colon, 100 * above_photo);
  // Measured (seed 1): PSNR 27.36 (nn) .. 27.94 (gaussian) dB, SSIM 0.647 .. 0.684 (one ray per
  // pixel: noise and aliasing keep SSIM low at this size). Thresholds ~0.8 dB / 0.03 below.
  for (const auto& [m, e] : r) {
    EXPECT_GT(e.psnr_db, 26.5) << to_string(m);
    EXPECT_GT(e.ssim, 0.62) << to_string(m);
  }
  // Blending beats picking one camera (nn) by 0.3-0.6 dB in this near-field scene; MRF is not
  // better than linear or Gaussian here (the thesis's visual claim does not show in dB).
  EXPECT_GT(r.at(Method::kMrf).psnr_db, r.at(Method::kNearest).psnr_db + 0.2);
  EXPECT_GT(r.at(Method::kGaussian).psnr_db, r.at(Method::kNearest).psnr_db + 0.3);
  EXPECT_GT(r.at(Method::kGaussian).ssim, r.at(Method::kMrf).ssim);
  // eq. 4.19-4.21: parallax of the near colon wall adds inter-camera error to the sensor effects
  // both scenes share (measured 25.8 vs 28.0 dB; the thesis reports 23.55 dB for its colon model).
  EXPECT_LT(icp_colon, icp_photo - 1.0);
  EXPECT_GT(icp_colon, 22.0);
  EXPECT_LT(icp_colon, 30.0);
}

}  // namespace
}  // namespace omma::pano
