#include "omma/core/rig.h"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace omma {
namespace {

Rig two_camera_rig() {
  Rig rig;
  rig.name = "two";
  rig.dome.radius_mm = 5;
  for (int i = 0; i < 2; ++i) {
    RigCamera c;
    c.id = i;
    c.frame = frame_from_ypr({deg2rad(40.0 * i), deg2rad(60), deg2rad(10)});
    c.position_mm = 5 * c.frame.t;
    c.in.k = {0.01, -0.002, 0, 0, 0};
    rig.cameras.push_back(c);
  }
  return rig;
}

std::string expect_rig_error(const nlohmann::json& j) {
  try {
    rig_from_json(j);
  } catch (const RigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no RigError for " << j.dump();
  return "";
}

TEST(Rig, JsonRoundTripIsLossless) {
  const Rig rig = two_camera_rig();
  const Rig back = rig_from_json(rig_to_json(rig));
  ASSERT_EQ(back.cameras.size(), 2u);
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR((back.cameras[i].frame.t - rig.cameras[i].frame.t).norm(), 0, 1e-15);
    EXPECT_NEAR((back.cameras[i].frame.v - rig.cameras[i].frame.v).norm(), 0, 1e-15);
    EXPECT_DOUBLE_EQ(back.cameras[i].in.aov, rig.cameras[i].in.aov);
    EXPECT_DOUBLE_EQ(back.cameras[i].in.k[0], 0.01);
  }
}

TEST(Rig, FieldOfViewIsConeUnlessTheFileSaysImage) {
  Rig rig = two_camera_rig();
  nlohmann::json j = rig_to_json(rig);
  EXPECT_FALSE(j["cameras"][0]["intrinsics"].contains("field"));  // cone files stay as they were
  EXPECT_EQ(rig_from_json(j).cameras[0].in.field, Intrinsics::Field::kCone);
  rig.cameras[1].in.field = Intrinsics::Field::kImage;
  j = rig_to_json(rig);
  EXPECT_EQ(j["cameras"][1]["intrinsics"]["field"], "image");
  // aov_deg is optional for an image field and recomputed as the image's bounding cone.
  j["cameras"][1]["intrinsics"].erase("aov_deg");
  const Rig back = rig_from_json(j);
  EXPECT_EQ(back.cameras[1].in.field, Intrinsics::Field::kImage);
  EXPECT_NEAR(back.cameras[1].in.aov, back.cameras[1].in.bounding_aov(), 1e-15);
  j["cameras"][1]["intrinsics"]["field"] = "square";
  EXPECT_NE(expect_rig_error(j).find("unknown field of view 'square'"), std::string::npos);
  j["cameras"][1]["intrinsics"]["field"] = 3;
  EXPECT_NE(expect_rig_error(j).find("field"), std::string::npos);
  j["cameras"][0]["intrinsics"].erase("aov_deg");  // a cone camera still needs its aov
  j["cameras"][1]["intrinsics"]["field"] = "image";
  EXPECT_NE(expect_rig_error(j).find("aov_deg"), std::string::npos);
}

TEST(Rig, YawPitchRollInputMatchesVectors) {
  nlohmann::json j = rig_to_json(two_camera_rig());
  for (auto& c : j["cameras"]) {
    c.erase("t");
    c.erase("u");
    c.erase("v");
  }
  const Rig back = rig_from_json(j);
  EXPECT_NEAR((back.cameras[1].frame.u - two_camera_rig().cameras[1].frame.u).norm(), 0, 1e-12);
}

TEST(Rig, RejectsBadInputWithClearMessages) {
  const nlohmann::json good = rig_to_json(two_camera_rig());
  auto with = [&](auto edit) {
    nlohmann::json j = good;
    edit(j);
    return expect_rig_error(j);
  };
  EXPECT_NE(with([](auto& j) { j["cameras"][0]["t"] = {0, 0, 2}; }).find("unit"), std::string::npos);
  EXPECT_NE(with([](auto& j) { j["cameras"][0]["u"] = j["cameras"][0]["t"]; }).find("orthogonal"),
            std::string::npos);
  EXPECT_NE(with([](auto& j) { j["cameras"][1]["intrinsics"]["fu"] = -3; }).find("focal"),
            std::string::npos);
  EXPECT_NE(with([](auto& j) { j["cameras"][1]["intrinsics"]["aov_deg"] = 180; }).find("angle of view"),
            std::string::npos);
  EXPECT_NE(with([](auto& j) { j["cameras"][1]["intrinsics"].erase("cv"); }).find("missing field 'cv'"),
            std::string::npos);
  EXPECT_NE(with([](auto& j) { j["cameras"][0]["position_mm"][1] = NAN; }).find("position_mm"),
            std::string::npos);
  EXPECT_NE(with([](auto& j) { j["cameras"] = nlohmann::json::array(); }).find("no cameras"),
            std::string::npos);
  EXPECT_NE(with([](auto& j) { j["cameras"][1]["id"] = 0; }).find("twice"), std::string::npos);
  // A left-handed frame (v flipped).
  EXPECT_NE(with([](auto& j) {
              for (auto& x : j["cameras"][0]["v"]) x = -x.template get<double>();
            }).find("right-handed"),
            std::string::npos);
}

TEST(Rig, LoadReportsPathAndJsonErrors) {
  const auto dir = std::filesystem::temp_directory_path();
  EXPECT_THROW(load_rig(dir / "no-such-rig.json"), RigError);
  const auto bad = dir / "omma-bad-rig.json";
  std::ofstream(bad) << "{ not json";
  try {
    load_rig(bad);
    FAIL();
  } catch (const RigError& e) {
    EXPECT_NE(std::string(e.what()).find("omma-bad-rig.json"), std::string::npos);
  }
  const auto good = dir / "omma-good-rig.json";
  save_rig(two_camera_rig(), good);
  EXPECT_EQ(load_rig(good).cameras.size(), 2u);
}

}  // namespace
}  // namespace omma
