// Streaming BigTIFF writer (libtiff): panoramas of any size (no 32767- or 65535-pixel limit of
// other formats, no 4 GiB limit of classic TIFF), written band by band so that memory holds one
// band only. 8-bit RGB, contiguous, in strips of `rows_per_strip` rows, optionally deflate-
// compressed. Written to a temporary name in the same folder and renamed by finish() (core/io.h's
// rule: no half-written output under the final name).
#pragma once

#include <filesystem>
#include <memory>

#include <opencv2/core.hpp>

namespace omma::io {

class BigTiffWriter {
 public:
  // Writes to PATH.tmpPID, renamed onto PATH by finish(); first removes the PATH.tmpPID files of
  // processes that have ended (a render killed mid-write). Throws IoError if the file cannot be
  // created. width, height >= 1.
  BigTiffWriter(const std::filesystem::path& path, int width, int height, bool deflate = false,
                int rows_per_strip = 16);
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
};

// Reads a whole 8-bit RGB TIFF (classic or BigTIFF, strips or tiles) as CV_8UC3 BGR, or the band of
// rows [row0, row0 + rows) (for tests and quality checks of panoramas too large for OpenCV).
cv::Mat read_tiff_rows(const std::filesystem::path& path, int row0 = 0, int rows = -1);
cv::Size tiff_size(const std::filesystem::path& path);

}  // namespace omma::io
