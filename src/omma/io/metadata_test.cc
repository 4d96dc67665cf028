// 360-degree metadata (metadata.h): layouts, XMP in JPEG, PNG and TIFF, Spherical Video V2 in MP4.
// exiftool and ffprobe read the same files in tests/cli/metadata_cli_test.cc.
#include "omma/io/metadata.h"

#include <fstream>
#include <stdexcept>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "omma/core/io.h"

namespace omma::io {
namespace {
namespace fs = std::filesystem;

std::string read_all(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

fs::path temp_dir(const std::string& tag) {
  const fs::path d = fs::temp_directory_path() / ("omma-metadata-" + tag + "-" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

cv::Mat test_image(int w, int h) {
  cv::Mat m(h, w, CV_8UC3);
  cv::randu(m, 0, 255);
  return m;
}

TEST(SphericalLayout, EachGridIsItsPartOfTheSphere) {
  // equirect 360x90: the top half of the sphere (dome axis = zenith).
  auto l = spherical_layout({Projection::kEquirect, 1920, 512});
  EXPECT_EQ(l.full_width, 1920);
  EXPECT_EQ(l.full_height, 1024);
  EXPECT_EQ(l.left, 0);
  EXPECT_EQ(l.top, 0);
  // vr180: the middle half of the longitudes, every latitude.
  l = spherical_layout({Projection::kVr180, 1080, 1080});
  EXPECT_EQ(l.full_width, 2160);
  EXPECT_EQ(l.full_height, 1080);
  EXPECT_EQ(l.left, 540);
  EXPECT_EQ(l.top, 0);
  l = spherical_layout({Projection::kEquirectFull, 2048, 1024});
  EXPECT_EQ(l.full_width, 2048);
  EXPECT_EQ(l.full_height, 1024);
  EXPECT_EQ(l.width, 2048);
  EXPECT_EQ(l.height, 1024);
  // equirect-100 (Giga-Eye): 100 of the sphere's 180 degrees, from the zenith down.
  l = spherical_layout({Projection::kEquirect100, 9000, 2500});
  EXPECT_EQ(l.full_width, 9000);
  EXPECT_EQ(l.full_height, 4500);
  EXPECT_EQ(l.left, 0);
  EXPECT_EQ(l.top, 0);
  EXPECT_EQ(l.height, 2500);
}

TEST(SphericalLayout, AgreesWithTheGridsDirections) {
  // A pixel's direction, converted to the full sphere's equirectangular coordinates with the
  // layout's axes (zenith at the top for equirect; forward = image centre for vr180), lands on
  // the layout's pixel.
  const PanoGrid eq{Projection::kEquirect, 360, 90};
  const SphericalLayout le = spherical_layout(eq);
  for (int row : {0, 44, 89}) {
    const Vec3 w = eq.pixel_direction(10, row);
    const double theta = std::acos(w.z());  // from the zenith
    EXPECT_NEAR(theta / kPi * le.full_height, le.top + row + 0.5, 1e-9);
  }
  const PanoGrid vr{Projection::kVr180, 200, 200};
  const SphericalLayout lv = spherical_layout(vr);
  for (int col : {0, 100, 199}) {
    const Vec3 w = vr.pixel_direction(col, 100);
    // The full sphere's yaw: 0 = forward (+z, its centre column), growing to the viewer's right,
    // which is -x when looking along +z with +y up (conventions.h (G2)).
    const double yaw = std::atan2(-w.x(), w.z());
    EXPECT_NEAR((yaw / (2 * kPi) + 0.5) * lv.full_width, lv.left + col + 0.5, 1e-9);
  }
  // equirect-100: the rows are the full sphere's first rows.
  const PanoGrid g100{Projection::kEquirect100, 360, 100};
  const SphericalLayout l100 = spherical_layout(g100);
  for (int row : {0, 50, 99}) {
    const double theta = std::acos(g100.pixel_direction(7, row).z());
    EXPECT_NEAR(theta / kPi * l100.full_height, l100.top + row + 0.5, 1e-9);
  }
}

TEST(PhotoSphereLayout, SquarePixelsGetA2To1FullPanorama) {
  // equirect 360 x 90 at W x W/4: the full sphere W x W/2, the image its top half.
  auto l = photo_sphere_layout({Projection::kEquirect, 1920, 480});
  ASSERT_TRUE(l);
  EXPECT_EQ(l->full_width, 1920);
  EXPECT_EQ(l->full_height, 960);
  EXPECT_EQ(l->height, 480);
  EXPECT_EQ(l->left, 0);
  EXPECT_EQ(l->top, 0);
  // vr180 at W x W: the front half of a 2W x W sphere.
  l = photo_sphere_layout({Projection::kVr180, 1080, 1080});
  ASSERT_TRUE(l);
  EXPECT_EQ(l->full_width, 2160);
  EXPECT_EQ(l->full_height, 1080);
  EXPECT_EQ(l->left, 540);
  l = photo_sphere_layout({Projection::kEquirectFull, 2048, 1024});
  ASSERT_TRUE(l);
  EXPECT_EQ(l->full_width, 2048);
  EXPECT_EQ(l->full_height, 1024);
  // equirect-100 at W x W 100/360 (9000 x 2500): 100 of 180 degrees.
  l = photo_sphere_layout({Projection::kEquirect100, 9000, 2500});
  ASSERT_TRUE(l);
  EXPECT_EQ(l->full_width, 9000);
  EXPECT_EQ(l->full_height, 4500);
  // Within half a pixel: 1000 x 100/360 = 277.8 -> 278 is square, 277 is not.
  EXPECT_TRUE(photo_sphere_layout({Projection::kEquirect100, 1000, 278}));
  EXPECT_FALSE(photo_sphere_layout({Projection::kEquirect100, 1000, 277}));
  // The crop over the full panorama is the grid's angular span over 360 x 180 deg, for every grid.
  for (const PanoGrid g :
       {PanoGrid{Projection::kEquirect, 1024, 256}, PanoGrid{Projection::kVr180, 300, 300},
        PanoGrid{Projection::kEquirectFull, 1000, 500}, PanoGrid{Projection::kEquirect100, 3600, 1000}}) {
    const auto p = photo_sphere_layout(g);
    ASSERT_TRUE(p) << to_string(g.projection);
    const AngularSpan span = angular_span(g.projection);
    EXPECT_EQ(p->full_width, 2 * p->full_height) << to_string(g.projection);
    EXPECT_NEAR(double(p->width) / p->full_width, span.width / (2 * kPi), 1e-12);
    EXPECT_NEAR(double(p->height) / p->full_height, span.height / kPi, 1e-12);
  }
}

TEST(PhotoSphereLayout, NonSquarePixelsGetNoneAndSayWhy) {
  // The thesis's equirect default: 1920 px for 360 deg but 512 px for 90 deg.
  std::string why;
  EXPECT_FALSE(photo_sphere_layout({Projection::kEquirect, 1920, 512}, &why));
  EXPECT_EQ(why,
            "1920x512 equirect has non-square pixels (5.33 x 5.69 px/deg); no GPano written; use --size "
            "1920x480 for a viewer-ready panorama");
  // The Giga-Eye's 21.6 MP default: 25 x 24 px/deg.
  EXPECT_FALSE(photo_sphere_layout({Projection::kEquirect100, 9000, 2400}, &why));
  EXPECT_NE(why.find("(25.00 x 24.00 px/deg)"), std::string::npos) << why;
  EXPECT_NE(why.find("--size 9000x2500"), std::string::npos) << why;
  EXPECT_FALSE(photo_sphere_layout({Projection::kVr180, 64, 32}, &why));
  EXPECT_NE(why.find("--size 64x64"), std::string::npos) << why;
  EXPECT_THROW(gpano_xmp({Projection::kEquirect, 1920, 512}), std::invalid_argument);
  EXPECT_EQ(panorama_xmp({Projection::kEquirect, 1920, 512}), "");
}

TEST(Xmp, GPanoFields) {
  const std::string x = gpano_xmp({Projection::kEquirect, 1920, 480});
  EXPECT_NE(x.find("<GPano:ProjectionType>equirectangular</GPano:ProjectionType>"), std::string::npos);
  EXPECT_NE(x.find("<GPano:FullPanoWidthPixels>1920</GPano:FullPanoWidthPixels>"), std::string::npos);
  EXPECT_NE(x.find("<GPano:FullPanoHeightPixels>960</GPano:FullPanoHeightPixels>"), std::string::npos);
  EXPECT_NE(x.find("<GPano:CroppedAreaImageHeightPixels>480</GPano:CroppedAreaImageHeightPixels>"),
            std::string::npos);
  EXPECT_NE(x.find("<GPano:CroppedAreaTopPixels>0</GPano:CroppedAreaTopPixels>"), std::string::npos);
  EXPECT_EQ(panorama_xmp({Projection::kEquirect, 1920, 480}), x);
}

TEST(Xmp, JpegPngAndTiffStillDecodeToTheSamePixels) {
  const fs::path d = temp_dir("xmp");
  const cv::Mat img = test_image(64, 64);
  const PanoGrid grid{Projection::kVr180, 64, 64};
  for (const std::string ext : {".png", ".jpg", ".JPEG"}) {
    const fs::path plain = d / ("plain" + ext), meta = d / ("meta" + ext);
    write_image(plain, img);
    write_panorama(meta, img, grid);
    const std::string bytes = read_all(meta);
    EXPECT_NE(bytes.find("<GPano:CroppedAreaLeftPixels>32</GPano:CroppedAreaLeftPixels>"), std::string::npos)
        << ext;
    EXPECT_EQ(bytes.size(),
              read_all(plain).size() + (ext == ".png" ? 12 + 22 : 4 + 29) + gpano_xmp(grid).size());
    const cv::Mat a = cv::imread(plain.string()), b = cv::imread(meta.string());
    ASSERT_FALSE(b.empty()) << ext;
    EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0) << ext;
  }
  // The JPEG's XMP follows the JFIF APP0 segment; the PNG's iTXt follows IHDR.
  const std::string jpg = read_all(d / "meta.jpg");
  EXPECT_EQ(jpg.substr(2, 2), "\xFF\xE0");
  const size_t app1 = 4 + ((uint8_t(jpg[4]) << 8) | uint8_t(jpg[5]));
  EXPECT_EQ(jpg.substr(app1, 2), "\xFF\xE1");
  EXPECT_EQ(jpg.substr(app1 + 4, 29), std::string("http://ns.adobe.com/xap/1.0/\0", 29));
  EXPECT_EQ(read_all(d / "meta.png").substr(37, 4), "iTXt");
  // TIFF (OpenCV's, 8 and 16 bit): the packet in tag 700, the pixels unchanged.
  cv::Mat img16;
  img.convertTo(img16, CV_16UC3, 257);
  for (const cv::Mat& m : {img, img16}) {
    write_panorama(d / "meta.tif", m, grid);
    const std::string bytes = read_all(d / "meta.tif");
    EXPECT_NE(bytes.find(gpano_xmp(grid)), std::string::npos);
    EXPECT_EQ(cv::norm(cv::imread((d / "meta.tif").string(), cv::IMREAD_UNCHANGED), m, cv::NORM_INF), 0);
  }
  // Other formats are written without XMP; XMP into bytes of the wrong format is refused.
  write_panorama(d / "p.bmp", img, grid);
  EXPECT_EQ(cv::norm(cv::imread((d / "p.bmp").string()), img, cv::NORM_INF), 0);
  EXPECT_THROW(embed_xmp("not a jpeg", ".jpg", "x"), IoError);
  EXPECT_THROW(embed_xmp(read_all(d / "meta.jpg"), ".png", "x"), IoError);
  EXPECT_THROW(write_panorama(d / "wrong.png", img, {Projection::kVr180, 10, 10}), IoError);
  fs::remove_all(d);
}

TEST(Xmp, NonSquarePixelsAreWrittenWithoutGPano) {
  const fs::path d = temp_dir("nonsquare");
  const cv::Mat img = test_image(64, 20);  // equirect: 64 px for 360 deg would be 16 rows for 90
  const PanoGrid grid{Projection::kEquirect, 64, 20};
  for (const std::string ext : {".png", ".jpg", ".tif"}) {
    write_panorama(d / ("p" + ext), img, grid);
    EXPECT_EQ(read_all(d / ("p" + ext)).find("GPano"), std::string::npos) << ext;
    const cv::Mat back = cv::imread((d / ("p" + ext)).string());
    ASSERT_EQ(back.size(), img.size()) << ext;
    if (ext != ".jpg") {
      EXPECT_EQ(cv::norm(back, img, cv::NORM_INF), 0) << ext;
    }
  }
  fs::remove_all(d);
}

// The payload of the first box `type` found anywhere below the top level (depth-first over the
// containers omma's writer uses), or "" if there is none.
std::string find_box(const std::string& s, size_t from, size_t to, const std::string& type) {
  for (size_t at = from; at + 8 <= to;) {
    const size_t size =
        (uint8_t(s[at]) << 24) | (uint8_t(s[at + 1]) << 16) | (uint8_t(s[at + 2]) << 8) | uint8_t(s[at + 3]);
    if (size < 8 || at + size > to) return "";
    const std::string t = s.substr(at + 4, 4);
    if (t == type) return s.substr(at + 8, size - 8);
    size_t skip = 0;
    if (t == "stsd")
      skip = 8;
    else if (t == "mp4v" || t == "avc1")
      skip = 78;
    if (t == "moov" || t == "trak" || t == "mdia" || t == "minf" || t == "stbl" || t == "stsd" ||
        t == "mp4v" || t == "avc1" || t == "sv3d" || t == "proj") {
      const std::string r = find_box(s, at + 8 + skip, at + size, type);
      if (!r.empty()) return r;
    }
    at += size;
  }
  return "";
}

TEST(SphericalVideo, Mp4GetsSv3dAndStillPlays) {
  const fs::path d = temp_dir("mp4");
  const fs::path mp4 = d / "v.mp4";
  {
    cv::VideoWriter w(mp4.string(), cv::CAP_FFMPEG, cv::VideoWriter::fourcc('m', 'p', '4', 'v'), 10,
                      {128, 32});
    ASSERT_TRUE(w.isOpened());
    for (int i = 0; i < 5; ++i) w.write(test_image(128, 32));
  }
  const std::string before = read_all(mp4);
  add_spherical_video_metadata(mp4, {Projection::kEquirect, 128, 32});
  const std::string after = read_all(mp4);
  EXPECT_EQ(find_box(before, 0, before.size(), "sv3d"), "");
  ASSERT_NE(find_box(after, 0, after.size(), "sv3d"), "");
  EXPECT_EQ(find_box(after, 0, after.size(), "st3d"), std::string(5, '\0'));  // version, flags, mono
  // equi: version/flags, then bounds top, bottom, left, right in 0.32 fixed point: the bottom half
  // of the sphere is cut off.
  const std::string equi = find_box(after, 0, after.size(), "equi");
  ASSERT_EQ(equi.size(), 20u);
  EXPECT_EQ(equi.substr(4, 16), std::string("\0\0\0\0\x80\0\0\0\0\0\0\0\0\0\0\0", 16));
  // The frames still decode, and a second call changes nothing.
  cv::VideoCapture cap(mp4.string());
  int n = 0;
  for (cv::Mat f; cap.read(f);) ++n;
  EXPECT_EQ(n, 5);
  add_spherical_video_metadata(mp4, {Projection::kEquirect, 128, 32});
  EXPECT_EQ(read_all(mp4), after);
  // Not an MP4: a clear error, the file untouched.
  std::ofstream(d / "x.mp4") << "hello";
  EXPECT_THROW(add_spherical_video_metadata(d / "x.mp4", {}), IoError);
  EXPECT_EQ(read_all(d / "x.mp4"), "hello");
  EXPECT_THROW(add_spherical_video_metadata(d / "missing.mp4", {}), IoError);
  fs::remove_all(d);
}

}  // namespace
}  // namespace omma::io
