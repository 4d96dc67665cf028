// Video files from `omma run` (io/video_writer.h), `omma meta` and the raw stdout sink, read back by
// outside tools: ffprobe and ffmpeg (codec, size, frames, rate, pixel format, keyframes, "Spherical
// Mapping", the decoded frames), exiftool (the V1 GSpherical XML, GPano) and headless Chromium (the
// files play in a <video> element).
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {
namespace fs = std::filesystem;

bool have(const std::string& tool) {
  return std::system(("command -v " + tool + " >/dev/null 2>&1").c_str()) == 0;
}

std::string lake() { return data_dir() + "/lake.jpg"; }

// `omma run` of the built-in 24-camera rig looking at the lake photograph, `frames` panoramas.
std::string run_args(const std::string& size, const std::string& projection, int frames) {
  return "run --rig thesis-24 --source pano:" + lake() + "@30 --size " + size + " --projection " +
         projection + " --frames " + std::to_string(frames) + " --fps 25 --no-cache ";
}

nlohmann::json probe_stream(const fs::path& p) {
  const RunResult r = run_command(
      "ffprobe -v error -print_format json -show_streams -count_frames "
      "-select_streams v:0 '" +
      p.string() + "'");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["streams"].size(), 1u) << r.out;
  return j["streams"].empty() ? nlohmann::json::object() : j["streams"][0];
}

nlohmann::json side_data(const nlohmann::json& stream, const std::string& type) {
  for (const auto& sd : stream.value("side_data_list", nlohmann::json::array()))
    if (sd.value("side_data_type", "") == type) return sd;
  return nullptr;
}

// The decoded frames of a video (ffmpeg, bgr24).
std::vector<cv::Mat> decode(const fs::path& video, int w, int h) {
  const RunResult r = run_command("ffmpeg -v error -i '" + video.string() + "' -f rawvideo -pix_fmt bgr24 -");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  std::vector<cv::Mat> frames;
  const size_t bytes = size_t(w) * h * 3;
  for (size_t at = 0; at + bytes <= r.out.size(); at += bytes)
    frames.push_back(cv::Mat(h, w, CV_8UC3, const_cast<char*>(r.out.data() + at)).clone());
  return frames;
}

// `omma run --sink out.mp4 --sink out.webm --sink png:DIR`: H.264 in a fast-start MP4 and VP9 in
// WebM, both with the 360-degree metadata, holding the panoramas the PNG sink wrote; and both play in
// Chromium (Debian's Chromium plays H.264 as well as VP9).
TEST(VideoCli, RunWritesPlayableSphericalMp4AndWebm) {
  if (!have("ffprobe") || !have("ffmpeg"))
    GTEST_SKIP() << "ffmpeg not installed (scripts/install-deps.sh --test)";
  const fs::path dir = temp_dir("video-run");
  const fs::path mp4 = dir / "pano.mp4", webm = dir / "pano.webm";
  const RunResult r = run_omma(run_args("256x128", "equirect", 25) + "--sink " + mp4.string() + " --sink " +
                                   webm.string() + " --sink png:" + (dir / "png").string() + " --json",
                               120);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.json()["frames"].get<long>(), 25);
  std::vector<cv::Mat> pngs;
  for (int i = 0; i < 25; ++i)
    pngs.push_back(cv::imread((dir / "png" / cv::format("frame_%06d.png", i)).string()));
  ASSERT_FALSE(pngs.back().empty());
  for (const auto& [video, codec] : {std::pair{mp4, "h264"}, std::pair{webm, "vp9"}}) {
    SCOPED_TRACE(video.string());
    const auto st = probe_stream(video);
    EXPECT_EQ(st.value("codec_name", ""), codec);
    EXPECT_EQ(st.value("width", 0), 256);
    EXPECT_EQ(st.value("height", 0), 128);
    EXPECT_EQ(st.value("pix_fmt", ""), "yuv420p");
    EXPECT_EQ(st.value("r_frame_rate", ""), "25/1");
    EXPECT_EQ(st.value("nb_read_frames", ""), "25");
    // equirect 256x128: the top half of a 256x256 sphere.
    const auto sph = side_data(st, "Spherical Mapping");
    ASSERT_FALSE(sph.is_null()) << st.dump();
    EXPECT_EQ(sph.value("projection", ""), "tiled equirectangular");
    EXPECT_NEAR(sph.value("bound_bottom", -9), 128, 1);
    EXPECT_EQ(sph.value("bound_top", -9), 0);
    // The frames are the panoramas (PSNR against the PNG sink's frames, the same renders).
    const auto frames = decode(video, 256, 128);
    ASSERT_EQ(frames.size(), 25u);
    double worst = 1e9;
    for (size_t i = 0; i < frames.size(); ++i) worst = std::min(worst, cv::PSNR(frames[i], pngs[i]));
    EXPECT_GT(worst, 30.0);  // default CRF (h264 20, vp9 31) on a detailed photograph
    std::printf("%s: worst frame PSNR against the PNG frames %.1f dB\n", codec, worst);
  }
  // MP4: the movie box first (plays while it downloads) and the V1 XML for exiftool.
  const std::string bytes = slurp(mp4);
  EXPECT_LT(bytes.find("moov"), bytes.find("mdat"));
  if (have("exiftool")) {
    const RunResult e = run_command("exiftool -j -XMP-GSpherical:all '" + mp4.string() + "'");
    const auto j = nlohmann::json::parse(e.out)[0];
    EXPECT_EQ(j.value("ProjectionType", ""), "equirectangular") << e.out;
    EXPECT_EQ(j.value("FullPanoHeightPixels", 0), 256) << e.out;
    EXPECT_EQ(j.value("CroppedAreaImageHeightPixels", 0), 128) << e.out;
  }
  // Chromium plays both: a decoded frame that is not black, time advancing.
  const std::string web = std::string(OMMA_SOURCE_DIR) + "/web";
  if (!have("chromium") || !have("node") || !fs::exists(web + "/node_modules/playwright-core")) {
    fs::remove_all(dir);
    GTEST_SKIP() << "chromium, node or web/node_modules (playwright-core) missing";
  }
  const RunResult c =
      run_command("timeout 60 node " + std::string(OMMA_SOURCE_DIR) + "/tests/cli/video_player.cjs " + web +
                      " " + mp4.string() + " " + webm.string(),
                  90);
  ASSERT_EQ(c.exit_code, 0) << c.err;
  const auto played = nlohmann::json::parse(c.out);
  EXPECT_FALSE(played.contains("failure")) << c.out;
  for (const std::string name : {"pano.mp4", "pano.webm"}) {
    SCOPED_TRACE(name + ": " + c.out);
    const auto& v = played[name];
    EXPECT_GE(v.value("readyState", 0), 2);
    EXPECT_NEAR(v.value("duration", 0.0), 1.0, 0.05);  // 25 frames at 25 frames/s
    EXPECT_EQ(v.value("width", 0), 256);
    EXPECT_GT(v.value("currentTime", 0.0), 0.2);
    double mean = 0;
    for (const auto& m : v.value("meanRGB", nlohmann::json::array())) mean += m.get<double>() / 3;
    EXPECT_GT(mean, 30.0);  // the lake, not black
  }
  fs::remove_all(dir);
}

// --codec, --crf, --gop, --10bit, --preset reach the file; wrong combinations are clear errors.
TEST(VideoCli, CodecOptionsReachTheFile) {
  if (!have("ffprobe")) GTEST_SKIP() << "ffprobe not installed (scripts/install-deps.sh --test)";
  const fs::path dir = temp_dir("video-opts");
  const fs::path mkv = dir / "p.mkv";
  RunResult r =
      run_omma(run_args("128x128", "vr180", 10) +
                   "--codec vp9 --crf 40 --gop 0.2 --10bit --preset ultrafast " + "--sink " + mkv.string(),
               120);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto st = probe_stream(mkv);
  EXPECT_EQ(st.value("codec_name", ""), "vp9");
  EXPECT_EQ(st.value("pix_fmt", ""), "yuv420p10le");
  EXPECT_EQ(st.value("profile", ""), "Profile 2");
  EXPECT_EQ(st.value("nb_read_frames", ""), "10");
  EXPECT_NEAR(side_data(st, "Spherical Mapping").value("bound_left", -9), 64, 1) << st.dump();
  // Keyframes every 0.2 s at 25 frames/s: frames 0 and 5.
  r = run_command("ffprobe -v error -select_streams v:0 -show_entries frame=key_frame -of json '" +
                  mkv.string() + "'");
  const auto fr = nlohmann::json::parse(r.out)["frames"];
  std::vector<int> keys;
  for (size_t i = 0; i < fr.size(); ++i)
    if (fr[i].value("key_frame", 0)) keys.push_back(int(i));
  EXPECT_EQ(keys, (std::vector<int>{0, 5}));
  expect_error(run_omma(run_args("128x128", "vr180", 2) + "--codec h264 --sink " + (dir / "x.webm").string()),
               "WebM", "h264 in webm");
  expect_error(
      run_omma(run_args("128x128", "vr180", 2) + "--codec h264 --crf 60 --sink " + (dir / "x.mp4").string()),
      "crf", "crf out of range");
  expect_error(
      run_omma(run_args("128x128", "vr180", 2) + "--preset quick --sink " + (dir / "x.mp4").string()),
      "preset", "unknown preset");
  expect_error(run_omma(run_args("129x128", "vr180", 2) + "--sink " + (dir / "x.mp4").string()), "even",
               "odd width");
  EXPECT_FALSE(fs::exists(dir / "x.webm"));
  EXPECT_FALSE(fs::exists(dir / "x.mp4"));
  fs::remove_all(dir);
}

// An outside re-encode drops the metadata; `omma meta` puts it back in place, frames unchanged;
// `omma meta FILE` shows it; photos get their GPano XMP back (once, however often it is run).
TEST(VideoCli, MetaRestoresTheMetadataAfterAReencode) {
  if (!have("ffprobe") || !have("ffmpeg"))
    GTEST_SKIP() << "ffmpeg not installed (scripts/install-deps.sh --test)";
  const fs::path dir = temp_dir("video-meta");
  const fs::path mp4 = dir / "pano.mp4", re = dir / "re.mp4";
  RunResult r = run_omma(run_args("256x256", "vr180", 8) + "--sink " + mp4.string(), 120);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_command("ffmpeg -v error -i '" + mp4.string() + "' -c:v libx264 -preset ultrafast '" + re.string() +
                  "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(side_data(probe_stream(re), "Spherical Mapping").is_null());  // ffmpeg dropped it
  r = run_omma("meta " + re.string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(r.json().value("spherical", true));
  const std::string frames_before = run_command("ffmpeg -v error -i '" + re.string() + "' -f framemd5 -").out;
  r = run_omma("meta " + re.string() + " --projection vr180 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = r.json();
  EXPECT_TRUE(j.value("written", false));
  EXPECT_TRUE(j.value("spherical", false));
  EXPECT_EQ(j["spherical_v1"].value("FullPanoWidthPixels", ""), "512");
  const auto sph = side_data(probe_stream(re), "Spherical Mapping");
  EXPECT_EQ(sph.value("projection", ""), "tiled equirectangular");
  EXPECT_NEAR(sph.value("bound_left", -9), 128, 1);
  EXPECT_NEAR(sph.value("bound_right", -9), 128, 1);
  EXPECT_EQ(run_command("ffmpeg -v error -i '" + re.string() + "' -f framemd5 -").out, frames_before);
  if (have("exiftool")) {
    const auto e =
        nlohmann::json::parse(run_command("exiftool -j -XMP-GSpherical:all '" + re.string() + "'").out)[0];
    EXPECT_EQ(e.value("CroppedAreaLeftPixels", -1), 128) << e.dump();
  }
  // A second run changes nothing; `omma meta FILE` shows both standards.
  r = run_omma("meta " + re.string() + " --projection vr180 --json");
  EXPECT_FALSE(r.json().value("written", true));
  r = run_omma("meta " + re.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(has(r.out, "Spherical Video V2: tiled equirectangular")) << r.out;
  EXPECT_TRUE(has(r.out, "ProjectionType=equirectangular")) << r.out;
  // A photo (a frame of the video): GPano XMP for exiftool, exactly one packet after two runs.
  const fs::path jpg = dir / "still.jpg";
  ASSERT_EQ(
      run_command("ffmpeg -v error -i '" + mp4.string() + "' -frames:v 1 '" + jpg.string() + "'").exit_code,
      0);
  for (int i = 0; i < 2; ++i)
    ASSERT_EQ(run_omma("meta " + jpg.string() + " --projection vr180").exit_code, 0);
  EXPECT_EQ(count(slurp(jpg), "<GPano:ProjectionType>"), 1);
  if (have("exiftool")) {
    const auto e =
        nlohmann::json::parse(run_command("exiftool -j -XMP-GPano:all '" + jpg.string() + "'").out)[0];
    EXPECT_EQ(e.value("FullPanoWidthPixels", 0), 512) << e.dump();
    EXPECT_EQ(e.value("CroppedAreaLeftPixels", -1), 128) << e.dump();
  }
  // Not a video or photo: a clear error, the file untouched.
  std::ofstream(dir / "x.mp4") << "hello";
  expect_error(run_omma("meta " + (dir / "x.mp4").string() + " --projection vr180"), "x.mp4", "not a video");
  EXPECT_EQ(slurp(dir / "x.mp4"), "hello");
  expect_error(run_omma("meta " + (dir / "missing.mp4").string()), "missing.mp4", "missing file");
  fs::remove_all(dir);
}

// `--sink -`: raw bgr24 frames on stdout and nothing else, for a pipe into ffmpeg.
TEST(VideoCli, StdoutSinkPipesRawFramesIntoFfmpeg) {
  if (!have("ffprobe") || !have("ffmpeg"))
    GTEST_SKIP() << "ffmpeg not installed (scripts/install-deps.sh --test)";
  const fs::path dir = temp_dir("video-pipe");
  const fs::path out = dir / "piped.mp4";
  RunResult r = run_omma(run_args("160x80", "equirect", 12) + "--sink -");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(has(r.err, "160x80 bgr24 at 25 frames/s")) << r.err;
  EXPECT_EQ(r.out.size(), 12u * 160 * 80 * 3);  // the frames, nothing else
  const cv::Mat first(80, 160, CV_8UC3, r.out.data());
  EXPECT_GT(cv::mean(first)[1], 30.0);  // the lake, not black
  r = run_command("sh -c \"" + std::string(OMMA_BINARY) + " " + run_args("160x80", "equirect", 12) +
                  "--sink - 2>/dev/null | ffmpeg -v error -f rawvideo -pix_fmt bgr24 -s 160x80 -r 25 -i - '" +
                  out.string() + "'\"");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto st = probe_stream(out);
  EXPECT_EQ(st.value("nb_read_frames", ""), "12");
  EXPECT_EQ(st.value("width", 0), 160);
  expect_error(run_omma(run_args("160x80", "equirect", 2) + "--sink - --json"), "stdout",
               "--json with --sink -");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace omma::test
