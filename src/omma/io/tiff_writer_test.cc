// The streaming TIFF writer (tiff_writer.h): classic TIFF or BigTIFF, the XMP packet and the
// resolution tags, read back with libtiff.
#include "omma/io/tiff_writer.h"

#include <unistd.h>

#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <tiffio.h>

#include "omma/core/io.h"

namespace omma::io {
namespace {
namespace fs = std::filesystem;

std::string head(const fs::path& p, size_t n) {
  std::ifstream in(p, std::ios::binary);
  std::string s(n, '\0');
  in.read(s.data(), std::streamsize(n));
  return s;
}

TEST(TiffWriter, ClassicUnder4GiBBigTiffForBtfOrAbove) {
  const fs::path d = fs::temp_directory_path() / ("omma-tiff-" + std::to_string(::getpid()));
  fs::create_directories(d);
  cv::Mat img(20, 30, CV_8UC3);
  cv::randu(img, 0, 255);
  const std::string xmp = "<x:xmpmeta xmlns:x=\"adobe:ns:meta/\"/>";
  for (const std::string name : {"a.tif", "a.btf"}) {
    BigTiffWriter w(d / name, 30, 20, false, 16, xmp);
    EXPECT_EQ(w.big(), name == "a.btf");
    w.write_rows(img.rowRange(0, 7));
    w.write_rows(img.rowRange(7, 20));
    w.finish();
    // Classic: "II" 42; BigTIFF: "II" 43 (little-endian byte order on this machine).
    EXPECT_EQ(uint8_t(head(d / name, 4)[2]), name == "a.btf" ? 43 : 42) << name;
    EXPECT_EQ(cv::norm(read_tiff_rows(d / name), img, cv::NORM_INF), 0) << name;
    TIFF* t = TIFFOpen((d / name).c_str(), "r");
    ASSERT_NE(t, nullptr);
    uint32_t n = 0;
    const char* data = nullptr;
    ASSERT_EQ(TIFFGetField(t, TIFFTAG_XMLPACKET, &n, &data), 1) << name;
    EXPECT_EQ(std::string(data, n), xmp);
    float xres = 0, yres = 0;
    uint16_t unit = 0;
    EXPECT_EQ(TIFFGetField(t, TIFFTAG_XRESOLUTION, &xres), 1);
    EXPECT_EQ(TIFFGetField(t, TIFFTAG_YRESOLUTION, &yres), 1);
    EXPECT_EQ(TIFFGetField(t, TIFFTAG_RESOLUTIONUNIT, &unit), 1);
    EXPECT_EQ(xres, 72.0f);
    EXPECT_EQ(yres, 72.0f);
    EXPECT_EQ(unit, RESUNIT_INCH);
    TIFFClose(t);
  }
  // Above 4 GiB of pixels: BigTIFF (decided from the size; nothing written).
  EXPECT_FALSE(needs_bigtiff(d / "x.tif", 9000, 2400));
  EXPECT_FALSE(needs_bigtiff(d / "x.tif", 32768, 32768));  // 3 GiB
  EXPECT_TRUE(needs_bigtiff(d / "x.tif", 40000, 40000));   // 4.5 GiB
  EXPECT_TRUE(needs_bigtiff(d / "x.BTF", 10, 10));
  fs::remove_all(d);
}

}  // namespace
}  // namespace omma::io
