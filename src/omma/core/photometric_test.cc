// The photometric model (photometric.h): its falloff, its minimum over the image, its validation
// and its place in the rig file.
#include "omma/core/photometric.h"

#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "omma/core/rig.h"

namespace omma {
namespace {

TEST(Photometric, FalloffIsHuginsRadialPolynomial) {
  Photometric p;
  p.vignetting = {-0.4, 0.1, -0.05};
  const int W = 200, H = 100;
  // Centre of the image: V = 1; a corner (pixel-centre convention: corner point (0, 0)): r = 1.
  EXPECT_DOUBLE_EQ(vignetting_falloff(p, W, H, 100, 50), 1.0);
  EXPECT_NEAR(vignetting_falloff(p, W, H, 0, 0), 1 - 0.4 + 0.1 - 0.05, 1e-12);
  EXPECT_NEAR(vignetting_radius(p, W, H, 200, 100), 1.0, 1e-12);
  // Half way to the right edge: r^2 = 50^2 / (100^2 + 50^2) = 0.2.
  const double s = 0.2;
  EXPECT_NEAR(vignetting_falloff(p, W, H, 150, 50), 1 - 0.4 * s + 0.1 * s * s - 0.05 * s * s * s, 1e-12);
  // The centre offset moves the optical centre (x right, y down, pixels).
  p.center_px = Vec2(10, -5);
  EXPECT_DOUBLE_EQ(vignetting_falloff(p, W, H, 110, 45), 1.0);
}

TEST(Photometric, MinimumFalloffFindsInteriorMinimum) {
  Photometric p;
  // V(s) = 1 - 2 s + 1.5 s^2: minimum at s = 2/3 inside the image (s reaches 1 at the corners).
  p.vignetting = {-2, 1.5, 0};
  const double lo = min_vignetting_falloff(p, 100, 100);
  EXPECT_NEAR(lo, 1 - 2 * (2.0 / 3) + 1.5 * (4.0 / 9), 1e-12);
  // Brute force over pixel centres agrees (to the grid's resolution).
  double brute = 10;
  for (int r = 0; r < 100; ++r)
    for (int c = 0; c < 100; ++c) brute = std::min(brute, vignetting_falloff(p, 100, 100, c + 0.5, r + 0.5));
  EXPECT_NEAR(brute, lo, 1e-3);
  EXPECT_GE(brute, lo - 1e-12);
}

TEST(Photometric, ValidationRejectsWhatCannotBeDividedOut) {
  Photometric ok;
  ok.vignetting = {-0.5, 0, 0};
  EXPECT_NO_THROW(validate_photometric(ok, 250, 250, "camera 3"));
  Photometric zero_gain = ok;
  zero_gain.gains = {1, 0, 1};
  EXPECT_THROW(validate_photometric(zero_gain, 250, 250, "camera 3"), std::invalid_argument);
  Photometric neg_gain = ok;
  neg_gain.gains = {-1, 1, 1};
  EXPECT_THROW(validate_photometric(neg_gain, 250, 250, "camera 3"), std::invalid_argument);
  Photometric nan = ok;
  nan.vignetting[1] = std::nan("");
  EXPECT_THROW(validate_photometric(nan, 250, 250, "camera 3"), std::invalid_argument);
  // V = 1 - 1.2 r^2 reaches zero at r = 0.91, inside the image (corners at r = 1).
  Photometric to_zero;
  to_zero.vignetting = {-1.2, 0, 0};
  try {
    validate_photometric(to_zero, 250, 250, "camera 3");
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("camera 3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("inside the image"), std::string::npos) << e.what();
  }
  // An interior zero that both ends hide: V(s) = 1 - 4 s + 4 s^2 = (1 - 2 s)^2 touches 0 at s = 1/2.
  Photometric dip;
  dip.vignetting = {-4, 4, 0};
  EXPECT_THROW(validate_photometric(dip, 250, 250, "camera 3"), std::invalid_argument);
}

Rig one_camera_rig() {
  Rig rig;
  rig.name = "one";
  RigCamera c;
  c.id = 4;
  c.position_mm = 5 * c.frame.t;
  rig.cameras.push_back(c);
  return rig;
}

TEST(Photometric, RigFileRoundTripAndErrors) {
  Rig rig = one_camera_rig();
  Photometric p;
  p.vignetting = {-0.41, 0.07, -0.01};
  p.center_px = Vec2(1.5, -2.25);
  p.gains = {0.93, 1.0, 1.07};
  rig.cameras[0].photometric = p;
  const nlohmann::json j = rig_to_json(rig);
  const Rig back = rig_from_json(j);
  ASSERT_TRUE(back.cameras[0].photometric.has_value());
  EXPECT_TRUE(*back.cameras[0].photometric == p);
  EXPECT_TRUE(has_photometric(back));
  // No model: none after the round trip either.
  EXPECT_FALSE(rig_from_json(rig_to_json(one_camera_rig())).cameras[0].photometric.has_value());

  auto error_of = [](nlohmann::json j) -> std::string {
    try {
      rig_from_json(j);
    } catch (const RigError& e) {
      return e.what();
    }
    return "";
  };
  nlohmann::json bad = j;
  bad["cameras"][0]["photometric"]["gains_bgr"] = {1, 0, 1};
  EXPECT_NE(error_of(bad).find("gain"), std::string::npos) << error_of(bad);
  bad = j;
  bad["cameras"][0]["photometric"]["vignetting"] = {-1.5, 0, 0};
  EXPECT_NE(error_of(bad).find("inside the image"), std::string::npos) << error_of(bad);
  bad = j;
  bad["cameras"][0]["photometric"]["vignetting"] = {-0.1, 0};
  EXPECT_NE(error_of(bad).find("array of 3 numbers"), std::string::npos) << error_of(bad);
  bad = j;
  bad["cameras"][0]["photometric"]["gain"] = {1, 1, 1};
  EXPECT_NE(error_of(bad).find("unknown field 'gain'"), std::string::npos) << error_of(bad);
  bad = j;
  bad["cameras"][0]["photometric"] = 3;
  EXPECT_NE(error_of(bad).find("expected a JSON object"), std::string::npos) << error_of(bad);
}

}  // namespace
}  // namespace omma
