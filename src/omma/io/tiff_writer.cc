#include "omma/io/tiff_writer.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <tiffio.h>

#include "omma/core/io.h"

namespace omma::io {

namespace {

// Temporaries "NAME.tmpPID" of `path` whose process has ended (killed mid-write: SIGKILL, a power
// cut) are removed; a live process's (another render of the same file) is left alone.
void remove_dead_temporaries(const std::filesystem::path& path) {
  const std::filesystem::path dir = path.has_parent_path() ? path.parent_path() : ".";
  const std::string prefix = path.filename().string() + ".tmp";
  std::error_code ec;
  for (auto it = std::filesystem::directory_iterator(dir, ec);
       !ec && it != std::filesystem::directory_iterator(); it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string digits = name.substr(prefix.size());
    if (digits.size() > 9 ||
        !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
      continue;
    const pid_t pid = static_cast<pid_t>(std::stol(digits));
    if (pid <= 0 || pid == ::getpid() || ::kill(pid, 0) == 0 || errno != ESRCH) continue;
    std::error_code rm;
    if (std::filesystem::remove(it->path(), rm))
      spdlog::info("removed {} (left by an interrupted render, process {} has ended)", it->path().string(),
                   pid);
  }
}

// The resolution TIFF 6.0 requires (a panorama has no physical size: the customary 72 per inch).
void set_resolution(TIFF* t) {
  TIFFSetField(t, TIFFTAG_XRESOLUTION, 72.0f);
  TIFFSetField(t, TIFFTAG_YRESOLUTION, 72.0f);
  TIFFSetField(t, TIFFTAG_RESOLUTIONUNIT, RESUNIT_INCH);
}

}  // namespace

bool needs_bigtiff(const std::filesystem::path& path, int width, int height) {
  if (lower_extension(path) == ".btf") return true;
  // The pixels (deflate may grow them by a fraction of a percent), the strip tables (16 bytes a row
  // at most) and the directory, XMP included, within classic TIFF's 32-bit offsets with a margin.
  const double bytes = double(width) * height * 3 * 1.01 + 16.0 * height + (1 << 20);
  return bytes > double(uint64_t(1) << 32) - double(64 << 20);
}

void add_tiff_metadata(const std::filesystem::path& path, const std::string& xmp) {
  TIFFSetWarningHandler(nullptr);
  TIFF* t = TIFFOpen(path.c_str(), "r+");
  if (!t) throw IoError("cannot open TIFF '" + path.string() + "' to add its metadata");
  if (!xmp.empty()) TIFFSetField(t, TIFFTAG_XMLPACKET, uint32_t(xmp.size()), xmp.data());
  float res = 0;
  uint16_t unit = 0;
  if (!TIFFGetField(t, TIFFTAG_XRESOLUTION, &res) || !TIFFGetField(t, TIFFTAG_YRESOLUTION, &res) ||
      !TIFFGetField(t, TIFFTAG_RESOLUTIONUNIT, &unit))
    set_resolution(t);
  const bool ok = TIFFRewriteDirectory(t) == 1;
  TIFFClose(t);
  if (!ok) throw IoError("cannot add metadata to TIFF '" + path.string() + "' (disk full?)");
}

struct BigTiffWriter::Impl {
  std::filesystem::path final_path, tmp_path;
  TIFF* tif = nullptr;
  std::vector<uint8_t> row;
};

BigTiffWriter::BigTiffWriter(const std::filesystem::path& path, int width, int height, bool deflate,
                             int rows_per_strip, const std::string& xmp)
    : impl_(std::make_unique<Impl>()), width_(width), height_(height) {
  if (width < 1 || height < 1) throw IoError(fmt::format("TIFF size {}x{} must be positive", width, height));
  big_ = needs_bigtiff(path, width, height);
  impl_->final_path = path;
  remove_dead_temporaries(path);
  impl_->tmp_path = path;
  impl_->tmp_path += fmt::format(".tmp{}", ::getpid());
  TIFFSetWarningHandler(nullptr);
  impl_->tif = TIFFOpen(impl_->tmp_path.c_str(), big_ ? "w8" : "w");  // "8": BigTIFF
  if (!impl_->tif) throw IoError("cannot create '" + impl_->tmp_path.string() + "'");
  TIFF* t = impl_->tif;
  TIFFSetField(t, TIFFTAG_IMAGEWIDTH, uint32_t(width));
  TIFFSetField(t, TIFFTAG_IMAGELENGTH, uint32_t(height));
  TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, 3);
  TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, 8);
  TIFFSetField(t, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_RGB);
  TIFFSetField(t, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  TIFFSetField(t, TIFFTAG_ORIENTATION, ORIENTATION_TOPLEFT);
  TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, uint32_t(std::max(1, rows_per_strip)));
  TIFFSetField(t, TIFFTAG_COMPRESSION, deflate ? COMPRESSION_ADOBE_DEFLATE : COMPRESSION_NONE);
  if (deflate) TIFFSetField(t, TIFFTAG_PREDICTOR, PREDICTOR_HORIZONTAL);
  TIFFSetField(t, TIFFTAG_SOFTWARE, "omma render");
  set_resolution(t);
  if (!xmp.empty()) TIFFSetField(t, TIFFTAG_XMLPACKET, uint32_t(xmp.size()), xmp.data());
  impl_->row.resize(size_t(width) * 3);
}

BigTiffWriter::~BigTiffWriter() {
  if (impl_ && impl_->tif) {
    TIFFClose(impl_->tif);
    std::error_code ec;
    std::filesystem::remove(impl_->tmp_path, ec);
  }
}

void BigTiffWriter::write_rows(const cv::Mat& band) {
  if (band.type() != CV_8UC3 || band.cols != width_)
    throw std::invalid_argument(fmt::format("TIFF rows must be CV_8UC3 with {} columns", width_));
  if (next_row_ + band.rows > height_) throw std::invalid_argument("more TIFF rows than the image has");
  for (int r = 0; r < band.rows; ++r, ++next_row_) {
    const uint8_t* s = band.ptr<uint8_t>(r);
    uint8_t* d = impl_->row.data();
    for (int c = 0; c < width_; ++c) {  // BGR -> RGB
      d[3 * c] = s[3 * c + 2];
      d[3 * c + 1] = s[3 * c + 1];
      d[3 * c + 2] = s[3 * c];
    }
    if (TIFFWriteScanline(impl_->tif, d, uint32_t(next_row_), 0) < 0)
      throw IoError(
          fmt::format("cannot write row {} of '{}' (disk full?)", next_row_, impl_->tmp_path.string()));
  }
}

void BigTiffWriter::finish() {
  if (next_row_ != height_)
    throw IoError(fmt::format("'{}': {} of {} rows written", impl_->final_path.string(), next_row_, height_));
  TIFF* t = impl_->tif;
  impl_->tif = nullptr;
  const bool ok = TIFFFlush(t) == 1;
  TIFFClose(t);
  std::error_code ec;
  if (!ok) {
    std::filesystem::remove(impl_->tmp_path, ec);
    throw IoError("cannot finish '" + impl_->final_path.string() + "' (disk full?)");
  }
  std::filesystem::rename(impl_->tmp_path, impl_->final_path, ec);
  if (ec) {
    std::filesystem::remove(impl_->tmp_path, ec);
    throw IoError("cannot rename onto '" + impl_->final_path.string() + "'");
  }
}

namespace {
struct TiffIn {
  TIFF* t;
  explicit TiffIn(const std::filesystem::path& p) : t(TIFFOpen(p.c_str(), "r")) {
    if (!t) throw IoError("cannot read TIFF '" + p.string() + "'");
  }
  ~TiffIn() { TIFFClose(t); }
};
}  // namespace

cv::Size tiff_size(const std::filesystem::path& path) {
  TIFFSetWarningHandler(nullptr);
  TiffIn in(path);
  uint32_t w = 0, h = 0;
  TIFFGetField(in.t, TIFFTAG_IMAGEWIDTH, &w);
  TIFFGetField(in.t, TIFFTAG_IMAGELENGTH, &h);
  return {int(w), int(h)};
}

cv::Mat read_tiff_rows(const std::filesystem::path& path, int row0, int rows) {
  TIFFSetWarningHandler(nullptr);
  TiffIn in(path);
  uint32_t w = 0, h = 0;
  uint16_t spp = 0, bps = 0, planar = PLANARCONFIG_CONTIG;
  TIFFGetField(in.t, TIFFTAG_IMAGEWIDTH, &w);
  TIFFGetField(in.t, TIFFTAG_IMAGELENGTH, &h);
  TIFFGetFieldDefaulted(in.t, TIFFTAG_SAMPLESPERPIXEL, &spp);
  TIFFGetFieldDefaulted(in.t, TIFFTAG_BITSPERSAMPLE, &bps);
  TIFFGetFieldDefaulted(in.t, TIFFTAG_PLANARCONFIG, &planar);
  if (rows < 0) rows = int(h) - row0;
  if (row0 < 0 || rows < 0 || row0 + rows > int(h))
    throw IoError(
        fmt::format("'{}': rows {}..{} outside the image of {} rows", path.string(), row0, row0 + rows, h));
  cv::Mat out(rows, int(w), CV_8UC3);
  if (bps == 8 && spp >= 3 && planar == PLANARCONFIG_CONTIG && !TIFFIsTiled(in.t)) {
    std::vector<uint8_t> line(TIFFScanlineSize64(in.t));
    // Strips must be decoded from their start: read from the first row of row0's strip.
    uint32_t rps = 0;
    TIFFGetFieldDefaulted(in.t, TIFFTAG_ROWSPERSTRIP, &rps);
    const int first = rps ? int(row0 / rps * rps) : 0;
    for (int r = first; r < row0 + rows; ++r) {
      if (TIFFReadScanline(in.t, line.data(), uint32_t(r), 0) < 0)
        throw IoError(fmt::format("'{}': cannot read row {}", path.string(), r));
      if (r < row0) continue;
      uint8_t* d = out.ptr<uint8_t>(r - row0);
      for (uint32_t c = 0; c < w; ++c) {
        d[3 * c] = line[spp * c + 2];
        d[3 * c + 1] = line[spp * c + 1];
        d[3 * c + 2] = line[spp * c];
      }
    }
    return out;
  }
  // Anything else: libtiff's RGBA reader (whole image).
  std::vector<uint32_t> rgba(size_t(w) * h);
  if (!TIFFReadRGBAImageOriented(in.t, w, h, rgba.data(), ORIENTATION_TOPLEFT, 0))
    throw IoError("cannot decode TIFF '" + path.string() + "'");
  for (int r = 0; r < rows; ++r)
    for (uint32_t c = 0; c < w; ++c) {
      const uint32_t p = rgba[size_t(row0 + r) * w + c];
      out.at<cv::Vec3b>(r, int(c)) = {uint8_t(TIFFGetB(p)), uint8_t(TIFFGetG(p)), uint8_t(TIFFGetR(p))};
    }
  return out;
}

}  // namespace omma::io
