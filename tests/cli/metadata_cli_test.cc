// 360-degree metadata of omma's outputs as outside tools read it: exiftool
// (Debian libimage-exiftool-perl) on `omma stitch` JPEG/PNG panoramas, ffprobe (Debian ffmpeg) on
// `omma run` MP4 videos. Layout facts: omma/io/metadata.h.
#include <cstdio>
#include <filesystem>
#include <memory>

#include <gtest/gtest.h>

#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {
namespace fs = std::filesystem;

bool have(const std::string& tool) {
  return std::system(("command -v " + tool + " >/dev/null 2>&1").c_str()) == 0;
}

std::string capture(const std::string& cmd) {
  std::unique_ptr<FILE, int (*)(FILE*)> p(popen(cmd.c_str(), "r"), pclose);
  std::string out;
  char buf[4096];
  for (size_t n; p && (n = fread(buf, 1, sizeof buf, p.get())) > 0;) out.append(buf, n);
  return out;
}

// A small frames folder of the thesis rig (ideal cameras, no truth), made once.
const fs::path& frames_dir() {
  static const fs::path dir = [] {
    const fs::path d = temp_dir("metadata") / "frames";
    const RunResult r = run_omma("simulate --scene checker --ideal --supersample 1 --no-truth --out " +
                                 d.string() + " --json");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return d;
  }();
  return dir;
}

struct Case {
  std::string projection, size;
  int full_w, full_h, left, top;
};
const Case kCases[] = {{"equirect", "256x64", 256, 128, 0, 0},  // the top half of the sphere
                       {"vr180", "128x128", 256, 128, 64, 0},   // the front half
                       {"equirect-full", "256x128", 256, 128, 0, 0},
                       {"equirect-100", "360x100", 360, 180, 0, 0}};  // 100 of 180 deg from the zenith

TEST(MetadataCli, StitchedJpegAndPngCarryGPanoForExiftool) {
  if (!have("exiftool")) GTEST_SKIP() << "exiftool not installed (scripts/install-deps.sh --test)";
  const fs::path dir = frames_dir().parent_path();
  std::string files;
  for (const Case& c : kCases) {
    const fs::path out = dir / (c.projection + (c.projection == "vr180" ? ".png" : ".jpg"));
    const RunResult r = run_omma("stitch --rig " + (frames_dir() / "rig.json").string() + " --frames " +
                                 frames_dir().string() + " --method nn --projection " + c.projection +
                                 " --size " + c.size + " --out " + out.string() + " --json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    files += " " + out.string();
  }
  // One exiftool run for every file: the GPano fields, and -validate's warnings about the file's
  // structure (PNG CRCs, JPEG segments) if it finds any.
  const auto all = nlohmann::json::parse(capture("exiftool -j -n -validate -warning -XMP-GPano:All" + files));
  ASSERT_EQ(all.size(), std::size(kCases));
  for (size_t i = 0; i < all.size(); ++i) {
    const Case& c = kCases[i];
    const auto& j = all[i];
    SCOPED_TRACE(c.projection + ": " + j.dump());
    const int w = std::stoi(c.size), h = std::stoi(c.size.substr(c.size.find('x') + 1));
    EXPECT_EQ(j.value("ProjectionType", ""), "equirectangular");
    EXPECT_EQ(j.value("FullPanoWidthPixels", 0), c.full_w);
    EXPECT_EQ(j.value("FullPanoHeightPixels", 0), c.full_h);
    EXPECT_EQ(j.value("CroppedAreaImageWidthPixels", 0), w);
    EXPECT_EQ(j.value("CroppedAreaImageHeightPixels", 0), h);
    EXPECT_EQ(j.value("CroppedAreaLeftPixels", -1), c.left);
    EXPECT_EQ(j.value("CroppedAreaTopPixels", -1), c.top);
    EXPECT_TRUE(j.contains("UsePanoramaViewer"));
    EXPECT_FALSE(j.contains("Warning"));
  }
}

TEST(MetadataCli, RunMp4CarriesSphericalVideoForFfprobe) {
  if (!have("ffprobe"))
    GTEST_SKIP() << "ffprobe not installed (Debian ffmpeg; scripts/install-deps.sh --test)";
  const fs::path dir = frames_dir().parent_path();
  for (const Case& c : kCases) {
    const fs::path mp4 = dir / (c.projection + ".mp4");
    const RunResult r = run_omma("run --rig " + (frames_dir() / "rig.json").string() +
                                     " --source frames:" + frames_dir().string() +
                                     " --method nn --projection " + c.projection + " --size " + c.size +
                                     " --frames 4 --fps 50 --no-cache --sink " + mp4.string() + " --json",
                                 60);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto j =
        nlohmann::json::parse(capture("ffprobe -v error -print_format json -show_streams -count_frames "
                                      "-select_streams v:0 " +
                                      mp4.string()));
    SCOPED_TRACE(c.projection + ": " + j.dump());
    ASSERT_EQ(j["streams"].size(), 1u);
    const auto& s = j["streams"][0];
    EXPECT_EQ(s.value("nb_read_frames", ""), "4");  // the video still decodes whole
    nlohmann::json spherical, stereo;
    for (const auto& sd : s.value("side_data_list", nlohmann::json::array())) {
      if (sd.value("side_data_type", "") == "Spherical Mapping") spherical = sd;
      if (sd.value("side_data_type", "") == "Stereo 3D") stereo = sd;
    }
    ASSERT_FALSE(spherical.is_null());
    EXPECT_EQ(stereo.value("type", ""), "2D");
    const int w = std::stoi(c.size), h = std::stoi(c.size.substr(c.size.find('x') + 1));
    if (c.full_w == w && c.full_h == h) {
      EXPECT_EQ(spherical.value("projection", ""), "equirectangular");
    } else {
      // A crop of the sphere: the bounds are the pixels cut off on each side.
      EXPECT_EQ(spherical.value("projection", ""), "tiled equirectangular");
      EXPECT_NEAR(spherical.value("bound_left", -9), c.left, 1);
      EXPECT_NEAR(spherical.value("bound_right", -9), c.full_w - c.left - w, 1);
      EXPECT_NEAR(spherical.value("bound_top", -9), c.top, 1);
      EXPECT_NEAR(spherical.value("bound_bottom", -9), c.full_h - c.top - h, 1);
    }
    EXPECT_EQ(spherical.value("yaw", -1), 0);
  }
}

}  // namespace
}  // namespace omma::test
