// 360-degree metadata of omma's outputs as outside tools read it: exiftool
// (Debian libimage-exiftool-perl) on `omma stitch` JPEG/PNG/TIFF and `omma render` JPEG/PNG/TIFF/
// BigTIFF panoramas and `omma run` PNG frames, ffprobe (Debian ffmpeg) on `omma run` MP4 videos.
// Layout facts and the square-pixel rule: omma/io/metadata.h.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <utility>

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

// The grid's angular span (width, height) in degrees.
std::pair<double, double> span_deg(const std::string& projection) {
  if (projection == "vr180") return {180, 180};
  if (projection == "equirect") return {360, 90};
  if (projection == "equirect-100") return {360, 100};
  return {360, 180};
}

// The GPano figures exiftool reads from `j` (one file of `exiftool -j -n`), checked against the
// file's own pixels and the grid's span (io/metadata.h): a 2:1 full panorama, the crop = the image,
// crop / full = span / (360 x 180 deg) within a pixel, and no -validate warning.
void expect_truthful_gpano(const nlohmann::json& j, const std::string& projection) {
  SCOPED_TRACE(projection + ": " + j.dump());
  const int w = j.value("ImageWidth", 0), h = j.value("ImageHeight", 0);
  const int full_w = j.value("FullPanoWidthPixels", 0), full_h = j.value("FullPanoHeightPixels", 0);
  ASSERT_GT(w, 0);
  ASSERT_GT(full_h, 0);
  EXPECT_EQ(j.value("ProjectionType", ""), "equirectangular");
  EXPECT_TRUE(j.contains("UsePanoramaViewer"));
  EXPECT_EQ(full_w, 2 * full_h);
  EXPECT_EQ(j.value("CroppedAreaImageWidthPixels", 0), w);
  EXPECT_EQ(j.value("CroppedAreaImageHeightPixels", 0), h);
  const auto [sw, sh] = span_deg(projection);
  EXPECT_NEAR(full_w * sw / 360.0, w, 1.0);
  EXPECT_NEAR(full_h * sh / 180.0, h, 1.0);
  EXPECT_EQ(j.value("CroppedAreaLeftPixels", -1), (full_w - w) / 2);  // vr180 centred, else 0
  EXPECT_EQ(j.value("CroppedAreaTopPixels", -1), 0);                  // every grid starts at the top
  EXPECT_EQ(j.value("Validate", ""), "0 0 0");                        // -n: errors, warnings, minor warnings
  EXPECT_FALSE(j.contains("Warning"));
}

// exiftool -validate and the GPano fields of `files` (one JSON object per file, in order).
nlohmann::json exiftool(const std::string& files) {
  return nlohmann::json::parse(capture(
      "exiftool -j -n -validate -warning -a -FileType -ImageWidth -ImageHeight -XMP-GPano:All" + files));
}

TEST(MetadataCli, StitchedJpegPngAndTiffCarryGPanoForExiftool) {
  if (!have("exiftool")) GTEST_SKIP() << "exiftool not installed (scripts/install-deps.sh --test)";
  const fs::path dir = frames_dir().parent_path();
  std::string files;
  for (const Case& c : kCases)
    for (const std::string ext : {".jpg", ".png", ".tif"}) {
      const fs::path out = dir / (c.projection + ext);
      const RunResult r = run_omma("stitch --rig " + (frames_dir() / "rig.json").string() + " --frames " +
                                   frames_dir().string() + " --method nn --projection " + c.projection +
                                   " --size " + c.size + " --out " + out.string() + " --json");
      ASSERT_EQ(r.exit_code, 0) << r.err;
      EXPECT_EQ(r.err.find("non-square"), std::string::npos) << r.err;
      files.append(" ").append(out.string());
    }
  // One exiftool run for every file: the GPano fields, and -validate's warnings about the file's
  // structure (PNG CRCs, JPEG segments, TIFF's required tags) if it finds any.
  const auto all = exiftool(files);
  ASSERT_EQ(all.size(), 3 * std::size(kCases));
  for (size_t i = 0; i < all.size(); ++i) {
    const Case& c = kCases[i / 3];
    const auto& j = all[i];
    SCOPED_TRACE(c.projection + ": " + j.dump());
    const int w = std::stoi(c.size), h = std::stoi(c.size.substr(c.size.find('x') + 1));
    EXPECT_EQ(j.value("FileType", ""), std::string(i % 3 == 0 ? "JPEG" : i % 3 == 1 ? "PNG" : "TIFF"));
    EXPECT_EQ(j.value("ImageWidth", 0), w);
    EXPECT_EQ(j.value("ImageHeight", 0), h);
    EXPECT_EQ(j.value("FullPanoWidthPixels", 0), c.full_w);
    EXPECT_EQ(j.value("FullPanoHeightPixels", 0), c.full_h);
    EXPECT_EQ(j.value("CroppedAreaLeftPixels", -1), c.left);
    EXPECT_EQ(j.value("CroppedAreaTopPixels", -1), c.top);
    expect_truthful_gpano(j, c.projection);
  }
}

TEST(MetadataCli, RenderedJpegTiffAndBigTiffCarryGPanoForExiftool) {
  if (!have("exiftool")) GTEST_SKIP() << "exiftool not installed (scripts/install-deps.sh --test)";
  const fs::path dir = frames_dir().parent_path() / "render";
  fs::create_directories(dir);
  // equirect 256x64 (square: 360 x 90 deg) as JPEG, TIFF (band by band, classic under 4 GiB) and
  // BigTIFF (.btf); vr180 128x128 as PNG.
  const std::pair<std::string, std::string> outs[] = {{"equirect", "256x64.jpg"},
                                                      {"equirect", "256x64.tif"},
                                                      {"equirect", "256x64.btf"},
                                                      {"vr180", "128x128.png"}};
  std::string files;
  for (const auto& [projection, name] : outs) {
    const fs::path out = dir / (projection + "_" + name);
    const RunResult r = run_omma("render " + frames_dir().string() + " --method nn --no-cache --projection " +
                                 projection + " --size " + name.substr(0, name.find('.')) + " --out " +
                                 out.string() + " --manifest " + out.string() + ".manifest.json --json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    files.append(" ").append(out.string());
  }
  const auto all = exiftool(files);
  ASSERT_EQ(all.size(), std::size(outs));
  const char* types[] = {"JPEG", "TIFF", "BTF", "PNG"};
  for (size_t i = 0; i < all.size(); ++i) {
    EXPECT_EQ(all[i].value("FileType", ""), types[i]);
    expect_truthful_gpano(all[i], outs[i].first);
  }
  EXPECT_EQ(all[0].value("FullPanoHeightPixels", 0), 128);
  EXPECT_EQ(all[3].value("CroppedAreaLeftPixels", 0), 64);
}

TEST(MetadataCli, NonSquarePixelsGetNoGPanoAndOneWarning) {
  if (!have("exiftool")) GTEST_SKIP() << "exiftool not installed (scripts/install-deps.sh --test)";
  const fs::path dir = frames_dir().parent_path() / "nonsquare";
  fs::create_directories(dir);
  // equirect 256x80: 256 px for 360 deg is 64 rows for 90 deg (as the thesis's 1920x512 is not
  // 1920x480); equirect-100 360x96 (100 rows would be square).
  const RunResult s = run_omma(
      "stitch --rig " + (frames_dir() / "rig.json").string() + " --frames " + frames_dir().string() +
      " --method nn --projection equirect --size 256x80 --out " + (dir / "s.jpg").string() + " --json");
  ASSERT_EQ(s.exit_code, 0) << s.err;
  EXPECT_NE(s.err.find("256x80 equirect has non-square pixels (0.71 x 0.89 px/deg); no GPano written; use "
                       "--size 256x64 for a viewer-ready panorama"),
            std::string::npos)
      << s.err;
  const RunResult r = run_omma("render " + frames_dir().string() +
                               " --method nn --no-cache --projection equirect-100 --size 360x96 --out " +
                               (dir / "r.tif").string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("360x96 equirect-100 has non-square pixels (1.00 x 0.96 px/deg)"), std::string::npos)
      << r.err;
  // The engine's PNG frames of a run: one warning for all of them.
  const RunResult p = run_omma("run --rig " + (frames_dir() / "rig.json").string() +
                                   " --source frames:" + frames_dir().string() +
                                   " --method nn --projection equirect --size 256x80 --frames 3 --fps 50 "
                                   "--no-cache --sink png:" +
                                   (dir / "png").string() + " --json",
                               60);
  ASSERT_EQ(p.exit_code, 0) << p.err;
  const size_t first = p.err.find("non-square pixels");
  ASSERT_NE(first, std::string::npos) << p.err;
  EXPECT_EQ(p.err.find("non-square pixels", first + 1), std::string::npos) << p.err;
  const auto all = exiftool(" " + (dir / "s.jpg").string() + " " + (dir / "r.tif").string() + " " +
                            (dir / "png" / "frame_000002.png").string());
  ASSERT_EQ(all.size(), 3u);
  for (const auto& j : all) {
    SCOPED_TRACE(j.dump());
    EXPECT_FALSE(j.contains("FullPanoWidthPixels"));  // no false claim
    EXPECT_FALSE(j.contains("ProjectionType"));
    EXPECT_GT(j.value("ImageWidth", 0), 0);
    EXPECT_EQ(j.value("Validate", ""), "0 0 0");  // -n: errors, warnings, minor warnings
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
