#include "omma/core/rig.h"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "omma/core/io.h"
#include "omma/core/limits.h"

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

// The RigError message for the two-camera rig's JSON after `edit`.
template <class F>
std::string with(F edit) {
  nlohmann::json j = rig_to_json(two_camera_rig());
  edit(j);
  return expect_rig_error(j);
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
  EXPECT_NE(with([](auto& j) { j["cameras"][0]["t"] = {0, 0, 2}; }).find("unit"), std::string::npos);
  EXPECT_NE(with([](auto& j) { j["cameras"][0]["u"] = j["cameras"][0]["t"]; }).find("orthogonal"),
            std::string::npos);
  EXPECT_NE(with([](auto& j) { j["cameras"][1]["intrinsics"]["fu"] = -3; }).find("focal"), std::string::npos);
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

// Rig files with integers that wrap, tiny focal lengths, wrong types and versions, or bad camera
// counts are refused with a message naming the problem.
TEST(Rig, RejectsOutOfRangeNumbersWrongTypesAndVersions) {
  auto has = [](const std::string& msg, const char* part) { return msg.find(part) != std::string::npos; };
  // 4294967546 = 2^32 + 250 used to become 250, 4294967297 -> 1, 4294967296 -> 0.
  EXPECT_TRUE(
      has(with([](auto& j) { j["cameras"][0]["intrinsics"]["width"] = 4294967546ull; }), "out of range"));
  EXPECT_TRUE(
      has(with([](auto& j) { j["cameras"][0]["intrinsics"]["height"] = 4294967297ll; }), "out of range"));
  EXPECT_TRUE(has(with([](auto& j) { j["cameras"][1]["id"] = 4294967296ll; }), "out of range"));
  EXPECT_TRUE(has(with([](auto& j) { j["cameras"][1]["id"] = 18446744073709551615ull; }), "out of range"));
  EXPECT_TRUE(has(with([](auto& j) { j["cameras"][1]["id"] = -1; }), "out of range"));
  EXPECT_TRUE(has(with([](auto& j) { j["cameras"][0]["intrinsics"]["width"] = 16385; }), "out of range"));
  EXPECT_TRUE(
      has(with([](auto& j) { j["cameras"][0]["intrinsics"]["width"] = 250.5; }), "must be an integer"));
  // Integers beyond 64 bits are parsed as floating point: not an integer.
  EXPECT_TRUE(
      has(with([](auto& j) { j["cameras"][0]["id"] = nlohmann::json::parse("100000000000000000000000"); }),
          "must be an integer"));
  // Focal lengths: 1e-320 (a denormal) made 1/f infinite and crashed the simulator.
  for (double f : {1e-320, 0.0, -200.0, 0.2, 1e300})
    EXPECT_TRUE(has(with([f](auto& j) { j["cameras"][1]["intrinsics"]["fv"] = f; }), "focal")) << f;
  EXPECT_TRUE(has(with([](auto& j) { j["cameras"][1]["intrinsics"]["cu"] = 1e300; }), "principal point"));
  EXPECT_TRUE(has(with([](auto& j) { j["cameras"][1]["intrinsics"]["k"][0] = 1e300; }), "distortion"));
  EXPECT_TRUE(has(with([](auto& j) { j["cameras"][1]["position_mm"][2] = 1e300; }), "position_mm"));
  EXPECT_TRUE(has(with([](auto& j) { j["dome"]["radius_mm"] = 1e300; }), "radius_mm"));
  // Wrong types are errors, not silently dropped; unknown versions are refused.
  EXPECT_TRUE(has(with([](auto& j) { j["name"] = 5; }), "'name' must be a string"));
  EXPECT_TRUE(
      has(with([](auto& j) { j["dome"]["method"] = nlohmann::json::array(); }), "'method' must be a string"));
  EXPECT_TRUE(has(with([](auto& j) { j["format"] = 1; }), "'format' must be a string"));
  EXPECT_TRUE(has(with([](auto& j) { j["version"] = 99; }), "version 99 is not supported"));
  EXPECT_TRUE(has(with([](auto& j) { j["version"] = "1"; }), "'version' must be an integer"));
  // The accepted extremes still load.
  nlohmann::json edge = rig_to_json(two_camera_rig());
  edge["cameras"][0]["intrinsics"]["fu"] = 1.0;  // >= 1e-3 x 250 px
  edge.erase("version");
  EXPECT_NO_THROW(rig_from_json(edge));
}

TEST(Rig, CameraCountIsBoundedAndDuplicatesFoundInLinearTime) {
  Rig rig = two_camera_rig();
  rig.cameras.resize(kMaxCameras, rig.cameras[0]);
  for (int i = 0; i < kMaxCameras; ++i) rig.cameras[i].id = 7 * i;
  EXPECT_NO_THROW(rig.validate());
  rig.cameras.back().id = 7 * 1234;
  EXPECT_THROW(rig.validate(), RigError);
  rig.cameras.back().id = -5;
  rig.cameras.push_back(rig.cameras[0]);
  rig.cameras.back().id = 1;
  try {
    rig.validate();
    ADD_FAILURE() << "no RigError for " << rig.cameras.size() << " cameras";
  } catch (const RigError& e) {
    EXPECT_NE(std::string(e.what()).find("limit is 4096"), std::string::npos) << e.what();
  }
}

TEST(Rig, LoadRefusesDevicesFoldersAndHugeFiles) {
  for (const char* path : {"/dev/zero", "/dev/urandom", "/tmp"}) {
    try {
      load_rig(path);
      ADD_FAILURE() << path;
    } catch (const RigError& e) {
      EXPECT_TRUE(std::string(e.what()).find("not a regular file") != std::string::npos ||
                  std::string(e.what()).find("folder") != std::string::npos)
          << e.what();
    }
  }
  const auto big = std::filesystem::temp_directory_path() / "omma-huge-rig.json";
  std::filesystem::remove(big);
  std::ofstream(big).close();
  std::filesystem::resize_file(big, kMaxTextFileBytes + 1);  // sparse: nothing is written
  try {
    load_rig(big);
    ADD_FAILURE() << "huge rig file loaded";
  } catch (const RigError& e) {
    EXPECT_NE(std::string(e.what()).find("too large"), std::string::npos) << e.what();
  }
  std::filesystem::remove(big);
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
