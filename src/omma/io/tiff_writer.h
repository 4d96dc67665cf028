// Streaming TIFF writer (libtiff): panoramas of any size (no 32767- or 65535-pixel limit of other
// formats; BigTIFF beyond classic TIFF's 4 GiB), written band by band so that memory holds one band
// only. 8-bit RGB, contiguous, in strips of `rows_per_strip` rows, optionally deflate-compressed,
// with XResolution = YResolution = 72 per inch (the tags TIFF 6.0 requires) and, if given, an XMP
// packet in tag 700 (XMLPacket; metadata.h's GPano). Classic TIFF when the uncompressed image and
// its strip tables fit in 4 GiB with a margin (what every reader and `exiftool -validate` accept),
// BigTIFF above that or when the name ends in .btf (BigTIFF's own extension; exiftool warns about
// a BigTIFF named .tif). Written to a temporary name in the same folder and renamed by finish()
// (core/io.h's rule: no half-written output under the final name).
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include <opencv2/core.hpp>

namespace omma::io {

class BigTiffWriter {
 public:
  // Writes to PATH.tmpPID, renamed onto PATH by finish(); first removes the PATH.tmpPID files of
  // processes that have ended (a render killed mid-write). Throws IoError if the file cannot be
  // created. width, height >= 1. `xmp`: the XMP packet to store (none if empty).
  BigTiffWriter(const std::filesystem::path& path, int width, int height, bool deflate = false,
                int rows_per_strip = 16, const std::string& xmp = {});
  // True if the file is a BigTIFF (see above), false for a classic TIFF.
  bool big() const { return big_; }
  ~BigTiffWriter();  // without finish(): the temporary file is removed
  BigTiffWriter(const BigTiffWriter&) = delete;
  BigTiffWriter& operator=(const BigTiffWriter&) = delete;
  // Appends rows (CV_8UC3 BGR, `width` columns); bands must come in order, top to bottom.
  void write_rows(const cv::Mat& band);
  int rows_written() const { return next_row_; }
  // All rows written: closes and renames onto the final path. Throws IoError otherwise.
  void finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  int width_ = 0, height_ = 0, next_row_ = 0;
  bool big_ = true;
};

// Would BigTiffWriter write `path` (width x height, 8-bit RGB) as a BigTIFF?
bool needs_bigtiff(const std::filesystem::path& path, int width, int height);

// Rewrites the first directory of the TIFF file at `path` (any TIFF libtiff reads, e.g. OpenCV's)
// in place with `xmp` in tag 700 (none if empty) and, where they are missing, XResolution =
// YResolution = 72 and ResolutionUnit inch. The image data are not touched. Throws IoError.
void add_tiff_metadata(const std::filesystem::path& path, const std::string& xmp);

// Reads a whole 8-bit RGB TIFF (classic or BigTIFF, strips or tiles) as CV_8UC3 BGR, or the band of
// rows [row0, row0 + rows) (for tests and quality checks of panoramas too large for OpenCV).
cv::Mat read_tiff_rows(const std::filesystem::path& path, int row0 = 0, int rows = -1);
cv::Size tiff_size(const std::filesystem::path& path);

}  // namespace omma::io
