// Video files (video_writer.h) and their 360-degree metadata (spherical_video.h), read back by the
// outside tools: ffprobe (codec, size, frames, rate, pixel format, "Spherical Mapping"), ffmpeg
// (the decoded frames), exiftool (the V1 XML) and the MP4 box structure itself.
#include "omma/io/video_writer.h"

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <stdexcept>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "omma/core/io.h"
#include "omma/io/spherical_video.h"

namespace omma::io {
namespace {
namespace fs = std::filesystem;

fs::path temp_dir(const std::string& tag) {
  const fs::path d = fs::temp_directory_path() / ("omma-video-" + tag + "-" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// stdout of a shell command (binary), and its exit status.
std::string capture(const std::string& cmd, int* status = nullptr) {
  std::string out;
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return out;
  char buf[1 << 16];
  for (size_t n; (n = fread(buf, 1, sizeof buf, p)) > 0;) out.append(buf, n);
  const int st = pclose(p);
  if (status) *status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return out;
}

bool have(const std::string& tool) {
  return std::system(("command -v " + tool + " >/dev/null").c_str()) == 0;
}

// A smooth moving test picture: gradients and a soft disc (what a panorama's sky and walls are).
cv::Mat smooth_frame(int w, int h, int i) {
  cv::Mat m(h, w, CV_8UC3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double dx = x - (w / 3.0 + 2 * i), dy = y - h / 2.0;
      const double disc = 80 * std::exp(-(dx * dx + dy * dy) / (0.05 * w * w));
      m.at<cv::Vec3b>(y, x) = cv::Vec3b(cv::saturate_cast<uchar>(40 + 150.0 * x / w),
                                        cv::saturate_cast<uchar>(60 + 120.0 * y / h + disc),
                                        cv::saturate_cast<uchar>(200 - 100.0 * x / w + disc / 2));
    }
  return m;
}

nlohmann::json probe(const fs::path& p) {
  return nlohmann::json::parse(
      capture("ffprobe -v error -print_format json -show_streams -show_format "
              "-count_frames -select_streams v:0 '" +
              p.string() + "'"));
}

nlohmann::json side_data(const nlohmann::json& stream, const std::string& type) {
  for (const auto& sd : stream.value("side_data_list", nlohmann::json::array()))
    if (sd.value("side_data_type", "") == type) return sd;
  return nullptr;
}

// Top-level box types of an MP4 file, in order.
std::vector<std::string> top_level_boxes(const fs::path& p) {
  const std::string s = read_text_file(p, kMaxDataFileBytes);
  std::vector<std::string> types;
  for (size_t at = 0; at + 8 <= s.size();) {
    uint64_t size = 0;
    for (int i = 0; i < 4; ++i) size = (size << 8) | uint8_t(s[at + i]);
    types.push_back(s.substr(at + 4, 4));
    if (size < 8) break;
    at += size;
  }
  return types;
}

double psnr_of_decoded(const fs::path& video, const std::vector<cv::Mat>& source) {
  const int w = source[0].cols, h = source[0].rows;
  const std::string raw = capture("ffmpeg -v error -i '" + video.string() + "' -f rawvideo -pix_fmt bgr24 -");
  EXPECT_EQ(raw.size(), source.size() * size_t(w * h * 3));
  double worst = 1e9;
  for (size_t i = 0; i < source.size() && (i + 1) * size_t(w * h * 3) <= raw.size(); ++i) {
    const cv::Mat decoded(h, w, CV_8UC3, const_cast<char*>(raw.data() + i * w * h * 3));
    worst = std::min(worst, cv::PSNR(decoded, source[i]));
  }
  return worst;
}

TEST(VideoOptions, BadValuesAreRefused) {
  std::string why;
  EXPECT_TRUE(VideoOptions{}.IsValid(&why)) << why;
  VideoOptions o;
  o.fps = 0;
  EXPECT_FALSE(o.IsValid(&why));
  o = {};
  o.gop_s = -1;
  EXPECT_FALSE(o.IsValid(&why));
  o = {};
  o.codec = VideoCodec::kH264;
  o.crf = 52;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("0..51"), std::string::npos) << why;
  o.codec = VideoCodec::kVp9;
  o.crf = 63;
  EXPECT_TRUE(o.IsValid(&why)) << why;
  o = {};
  o.preset = VideoPreset(42);
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(parse_video_preset("veryslow"), VideoPreset::kVeryslow);
  EXPECT_THROW(parse_video_preset("quick"), std::invalid_argument);
  EXPECT_EQ(parse_video_codec("vp9"), VideoCodec::kVp9);
  EXPECT_THROW(parse_video_codec("mpeg2"), std::invalid_argument);
  EXPECT_EQ(resolve_video_codec("a.webm", VideoCodec::kAuto), VideoCodec::kVp9);
  EXPECT_EQ(resolve_video_codec("a.MP4", VideoCodec::kAuto), VideoCodec::kH264);
  EXPECT_THROW(resolve_video_codec("a.webm", VideoCodec::kH264), std::invalid_argument);
  EXPECT_THROW(resolve_video_codec("a.gif", VideoCodec::kAuto), std::invalid_argument);
}

TEST(VideoWriter, BadInputIsAClearErrorAndLeavesNothing) {
  const fs::path d = temp_dir("bad");
  EXPECT_THROW(VideoWriter(d / "odd.mp4", {101, 50}), std::invalid_argument);
  EXPECT_THROW(VideoWriter(d / "no" / "such.mp4", {100, 50}), IoError);
  {
    std::ofstream(d / "keep.mp4") << "old";
    VideoWriter w(d / "keep.mp4", {64, 32});
    EXPECT_THROW(w.write(cv::Mat(32, 32, CV_8UC3)), std::invalid_argument);
    EXPECT_THROW(w.write(cv::Mat(32, 64, CV_32FC3)), std::invalid_argument);
    w.write(smooth_frame(64, 32, 0));
    EXPECT_TRUE(fs::exists(partial_path(d / "keep.mp4")));
  }  // destroyed without close(): the target is untouched, the temporary file gone
  EXPECT_EQ(read_text_file(d / "keep.mp4"), "old");
  EXPECT_FALSE(fs::exists(partial_path(d / "keep.mp4")));
  {
    VideoWriter w(d / "empty.mp4", {64, 32});
    EXPECT_THROW(w.close(), IoError);  // no frames
  }
  EXPECT_FALSE(fs::exists(d / "empty.mp4"));
  EXPECT_EQ(std::distance(fs::directory_iterator(d), fs::directory_iterator()), 1);  // keep.mp4 only
  fs::remove_all(d);
}

// H.264 in MP4: what ffprobe reads back, fast start, both spherical standards, and the frames.
TEST(VideoWriter, H264Mp4IsFastStartSphericalAndFaithful) {
  if (!have("ffprobe") || !have("ffmpeg")) GTEST_SKIP() << "ffmpeg/ffprobe not installed";
  const fs::path d = temp_dir("h264");
  const fs::path mp4 = d / "pano.mp4";
  std::vector<cv::Mat> frames;
  for (int i = 0; i < 24; ++i) frames.push_back(smooth_frame(192, 96, i));
  VideoOptions o;
  o.fps = 24;
  o.gop_s = 0.5;
  VideoWriter w(mp4, {192, 96}, o, Projection::kVr180);
  for (const auto& f : frames) w.write(f);
  const VideoSummary s = w.close();
  EXPECT_EQ(s.codec, "h264");
  EXPECT_EQ(s.crf, 20);
  EXPECT_TRUE(s.spherical);
  EXPECT_FALSE(fs::exists(partial_path(mp4)));
  const auto j = probe(mp4);
  ASSERT_EQ(j["streams"].size(), 1u) << j.dump();
  const auto& st = j["streams"][0];
  EXPECT_EQ(st.value("codec_name", ""), "h264");
  EXPECT_EQ(st.value("width", 0), 192);
  EXPECT_EQ(st.value("height", 0), 96);
  EXPECT_EQ(st.value("pix_fmt", ""), "yuv420p");
  EXPECT_EQ(st.value("r_frame_rate", ""), "24/1");
  EXPECT_EQ(st.value("nb_read_frames", ""), "24");
  EXPECT_EQ(st.value("color_space", ""), "bt709");
  // vr180 192x96: the front half of a 384x96 sphere, 96 px cut off left and right.
  const auto sph = side_data(st, "Spherical Mapping");
  ASSERT_FALSE(sph.is_null()) << st.dump();
  EXPECT_EQ(sph.value("projection", ""), "tiled equirectangular");
  // (ffprobe turns the 0.32 fractions into pixels with 2^32 - 1 as one: +-1 pixel)
  EXPECT_NEAR(sph.value("bound_left", -1), 96, 1);
  EXPECT_NEAR(sph.value("bound_right", -1), 96, 1);
  EXPECT_EQ(sph.value("bound_top", -1), 0);
  EXPECT_EQ(sph.value("bound_bottom", -1), 0);
  EXPECT_EQ(side_data(st, "Stereo 3D").value("type", ""), "2D");
  // Keyframes every 0.5 s = 12 frames: frames 0 and 12.
  const auto fr = nlohmann::json::parse(capture(
      "ffprobe -v error -select_streams v:0 -show_entries frame=key_frame -of json '" + mp4.string() + "'"));
  std::vector<int> keys;
  for (size_t i = 0; i < fr["frames"].size(); ++i)
    if (fr["frames"][i].value("key_frame", 0)) keys.push_back(int(i));
  EXPECT_EQ(keys, (std::vector<int>{0, 12}));
  // Fast start: the movie box before the media data.
  const auto boxes = top_level_boxes(mp4);
  const auto moov = std::find(boxes.begin(), boxes.end(), "moov"),
             mdat = std::find(boxes.begin(), boxes.end(), "mdat");
  ASSERT_NE(moov, boxes.end());
  ASSERT_NE(mdat, boxes.end());
  EXPECT_LT(moov - boxes.begin(), mdat - boxes.begin());
  // V1: the uuid box with the GSpherical XML, as read by our reader and by exiftool.
  const SphericalVideoInfo info = read_spherical_video_metadata(mp4);
  EXPECT_TRUE(info.v1);
  EXPECT_EQ(info.v1_fields.at("ProjectionType"), "equirectangular");
  EXPECT_EQ(info.v1_fields.at("FullPanoWidthPixels"), "384");
  EXPECT_EQ(info.v1_fields.at("CroppedAreaLeftPixels"), "96");
  if (have("exiftool")) {
    const auto e =
        nlohmann::json::parse(capture("exiftool -j -XMP-GSpherical:all '" + mp4.string() + "'"))[0];
    EXPECT_EQ(e.value("ProjectionType", ""), "equirectangular") << e.dump();
    EXPECT_EQ(e.value("FullPanoWidthPixels", 0), 384) << e.dump();
    EXPECT_EQ(e.value("CroppedAreaImageWidthPixels", 0), 192) << e.dump();
  }
  // The decoded frames are the frames written (a smooth picture at CRF 20).
  const double psnr = psnr_of_decoded(mp4, frames);
  EXPECT_GT(psnr, 38.0);
  std::printf("decoded frames: worst PSNR %.1f dB\n", psnr);
  fs::remove_all(d);
}

TEST(VideoWriter, Vp9WebmCarriesTheProjection) {
  if (!have("ffprobe") || !have("ffmpeg")) GTEST_SKIP() << "ffmpeg/ffprobe not installed";
  const fs::path d = temp_dir("vp9");
  const fs::path webm = d / "pano.webm";
  std::vector<cv::Mat> frames;
  for (int i = 0; i < 12; ++i) frames.push_back(smooth_frame(128, 64, i));
  VideoOptions o;
  o.fps = 12.5;
  o.preset = VideoPreset::kUltrafast;
  VideoWriter w(webm, {128, 64}, o, Projection::kEquirectFull);
  for (const auto& f : frames) w.write(f);
  EXPECT_EQ(w.close().codec, "vp9");
  const auto st = probe(webm)["streams"][0];
  EXPECT_EQ(st.value("codec_name", ""), "vp9");
  EXPECT_EQ(st.value("width", 0), 128);
  EXPECT_EQ(st.value("height", 0), 64);
  EXPECT_EQ(st.value("r_frame_rate", ""), "25/2");
  EXPECT_EQ(st.value("nb_read_frames", ""), "12");
  EXPECT_EQ(side_data(st, "Spherical Mapping").value("projection", ""), "equirectangular") << st.dump();
  EXPECT_GT(psnr_of_decoded(webm, frames), 33.0);
  // Tagged again for a crop: the Projection is replaced (the file remuxed), the frames unchanged.
  const std::string before = capture("ffmpeg -v error -i '" + webm.string() + "' -f framemd5 -");
  EXPECT_TRUE(set_spherical_video_metadata(webm, PanoGrid{Projection::kEquirect, 128, 64}));
  EXPECT_FALSE(set_spherical_video_metadata(webm, PanoGrid{Projection::kEquirect, 128, 64}));
  const auto sph = side_data(probe(webm)["streams"][0], "Spherical Mapping");
  EXPECT_EQ(sph.value("projection", ""), "tiled equirectangular");
  EXPECT_EQ(sph.value("bound_bottom", -1), 64);
  EXPECT_EQ(capture("ffmpeg -v error -i '" + webm.string() + "' -f framemd5 -"), before);
  fs::remove_all(d);
}

TEST(VideoWriter, TenBitH264InMatroska) {
  if (!have("ffprobe")) GTEST_SKIP() << "ffprobe not installed";
  const fs::path d = temp_dir("10bit");
  const fs::path mkv = d / "pano.mkv";
  VideoOptions o;
  o.ten_bit = true;
  o.crf = 18;
  o.preset = VideoPreset::kUltrafast;
  VideoWriter w(mkv, {64, 64}, o, Projection::kVr180);
  for (int i = 0; i < 5; ++i) {
    cv::Mat f16;
    smooth_frame(64, 64, i).convertTo(f16, CV_16UC3, 257.0);
    w.write(f16);
  }
  EXPECT_EQ(w.close().pix_fmt, "yuv420p10le");
  const auto st = probe(mkv)["streams"][0];
  EXPECT_EQ(st.value("codec_name", ""), "h264");
  EXPECT_EQ(st.value("pix_fmt", ""), "yuv420p10le");
  EXPECT_EQ(st.value("profile", ""), "High 10");
  EXPECT_EQ(st.value("nb_read_frames", ""), "5");
  EXPECT_NEAR(side_data(st, "Spherical Mapping").value("bound_left", -1), 32, 1) << st.dump();
  fs::remove_all(d);
}

// The MP4 boxes are replaced, not added twice, and the file still decodes after each edit.
TEST(SphericalVideo, Mp4MetadataIsReplacedAsAWhole) {
  if (!have("ffprobe")) GTEST_SKIP() << "ffprobe not installed";
  const fs::path d = temp_dir("retag");
  const fs::path mp4 = d / "v.mp4";
  VideoOptions o;
  o.preset = VideoPreset::kUltrafast;
  VideoWriter w(mp4, {128, 64}, o, Projection::kVr180);
  for (int i = 0; i < 6; ++i) w.write(smooth_frame(128, 64, i));
  w.close();
  EXPECT_FALSE(set_spherical_video_metadata(mp4, PanoGrid{Projection::kVr180, 128, 64}));  // already so
  EXPECT_TRUE(set_spherical_video_metadata(mp4, PanoGrid{Projection::kEquirectFull, 128, 64}));
  const std::string s = read_text_file(mp4, kMaxDataFileBytes);
  auto count = [&](const std::string& what) {
    int n = 0;
    for (size_t at = s.find(what); at != std::string::npos; at = s.find(what, at + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count("sv3d"), 1);
  EXPECT_EQ(count("st3d"), 1);
  EXPECT_EQ(count("GSpherical:Spherical>"), 2);  // one element, opening and closing tag
  const auto st = probe(mp4)["streams"][0];
  EXPECT_EQ(side_data(st, "Spherical Mapping").value("projection", ""), "equirectangular");
  EXPECT_EQ(st.value("nb_read_frames", ""), "6");
  const SphericalVideoInfo info = read_spherical_video_metadata(mp4);
  EXPECT_EQ(info.v1_fields.at("FullPanoWidthPixels"), "128");
  EXPECT_EQ(info.v1_fields.at("CroppedAreaLeftPixels"), "0");
  // Not a video: a clear error, the file untouched.
  std::ofstream(d / "x.mp4") << "hello";
  EXPECT_THROW(set_spherical_video_metadata(d / "x.mp4", {}), IoError);
  EXPECT_EQ(read_text_file(d / "x.mp4"), "hello");
  EXPECT_THROW(read_spherical_video_metadata(d / "x.mp4"), IoError);
  fs::remove_all(d);
}

}  // namespace
}  // namespace omma::io
