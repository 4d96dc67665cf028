#include "omma/core/io.h"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <random>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <spdlog/spdlog.h>

namespace omma {
namespace fs = std::filesystem;

void write_atomically(const fs::path& path, const std::function<void(const fs::path&)>& write) {
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  if (!fs::is_directory(dir))
    throw IoError("cannot write '" + path.string() + "': folder '" + dir.string() + "' does not exist");
  std::random_device rd;
  // Keep the extension so that format-by-extension writers (OpenCV) still work.
  const fs::path tmp = dir / ("." + path.stem().string() + ".tmp" + std::to_string(rd() % 1000000) +
                              path.extension().string());
  try {
    write(tmp);
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) throw IoError("cannot write '" + path.string() + "': " + ec.message());
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
}

void write_text_atomically(const fs::path& path, const std::string& text) {
  write_atomically(path, [&](const fs::path& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    out << text;
    out.close();
    if (!out) throw IoError("cannot write '" + path.string() + "'");
  });
}

cv::Mat read_image(const fs::path& path, int flags) {
  if (!fs::exists(path)) throw IoError("image '" + path.string() + "' does not exist");
  if (fs::is_directory(path)) throw IoError("'" + path.string() + "' is a folder, not an image");
  cv::Mat m;
  try {
    m = cv::imread(path.string(), flags);
  } catch (const cv::Exception& e) {
    throw IoError("cannot read image '" + path.string() + "': " + e.what());
  }
  if (m.empty()) throw IoError("cannot read image '" + path.string() + "' (not an image, or damaged)");
  return m;
}

void remove_leftover(const fs::path& tmp, const fs::path& target) {
  std::error_code ec;
  if (!fs::exists(tmp, ec)) return;
  fs::remove(tmp, ec);
  spdlog::warn("{} the temporary file {} of an interrupted earlier run writing {}",
               ec ? "could not remove" : "removed", tmp.string(), target.string());
}

void write_image(const fs::path& path, const cv::Mat& image,
                 const std::function<void(const fs::path& tmp)>& finish) {
  if (image.empty()) throw IoError("refusing to write empty image '" + path.string() + "'");
  write_atomically(path, [&](const fs::path& tmp) {
    bool ok = false;
    try {
      ok = cv::imwrite(tmp.string(), image);
    } catch (const cv::Exception& e) {
      throw IoError("cannot write image '" + path.string() + "': " + e.what());
    }
    if (!ok)
      throw IoError("cannot write image '" + path.string() +
                    "' (disk full, a file-size limit, or no permission?)");
    if (finish) finish(tmp);
  });
}

std::string lower_extension(const fs::path& path) {
  std::string ext = path.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

void check_image_format(const fs::path& path, std::int64_t width, std::int64_t height) {
  const std::string ext = lower_extension(path);
  bool known = false;
  try {
    known = !ext.empty() && cv::haveImageWriter(path.string());
  } catch (const cv::Exception&) {
  }
  if (!known)
    throw IoError("cannot write an image to '" + path.string() +
                  "': unknown image format (use .png, .jpg, .tif, ... by the extension)");
  const std::int64_t side = std::max(width, height);
  const std::int64_t limit = ext == ".jpg" || ext == ".jpeg" || ext == ".jpe" ? 65500
                             : ext == ".webp"                                 ? 16383
                                                                              : 0;
  if (limit && side > limit)
    throw IoError(
        fmt::format("'{}': a {} image holds at most {} pixels a side, not {}x{} (write a .tif or .png)",
                    path.string(), ext.substr(1), limit, width, height));
}

namespace {

// The checks of read_file; calls `sink(buffer, n)` for every chunk read.
template <class Sink>
void read_bounded(const fs::path& path, std::uintmax_t max_bytes, const std::string& what, Sink&& sink) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || st.type() == fs::file_type::not_found)
    throw IoError(what + " '" + path.string() + "' does not exist");
  if (st.type() == fs::file_type::directory)
    throw IoError("'" + path.string() + "' is a folder, not a " + what);
  if (st.type() != fs::file_type::regular)
    throw IoError(what + " '" + path.string() + "' is not a regular file (a device, FIFO or socket)");
  const std::uintmax_t size = fs::file_size(path, ec);
  auto too_large = [&](std::uintmax_t n) {
    return IoError(fmt::format("{} '{}' is too large ({}{} bytes; the limit is {} bytes)", what,
                               path.string(), n > max_bytes ? "" : "more than ", n, max_bytes));
  };
  if (!ec && size > max_bytes) throw too_large(size);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot open " + what + " '" + path.string() + "'");
  char buf[1 << 16];
  std::uintmax_t total = 0;
  while (in) {
    in.read(buf, sizeof buf);
    const std::streamsize n = in.gcount();
    if (n <= 0) break;
    total += std::uintmax_t(n);
    if (total > max_bytes) throw too_large(max_bytes);
    sink(buf, size_t(n));
  }
  if (in.bad()) throw IoError("cannot read " + what + " '" + path.string() + "'");
}

}  // namespace

std::vector<uint8_t> read_file(const fs::path& path, std::uintmax_t max_bytes, const std::string& what) {
  std::vector<uint8_t> out;
  read_bounded(path, max_bytes, what, [&](const char* b, size_t n) { out.insert(out.end(), b, b + n); });
  return out;
}

std::string read_text_file(const fs::path& path, std::uintmax_t max_bytes, const std::string& what) {
  std::string out;
  read_bounded(path, max_bytes, what, [&](const char* b, size_t n) { out.append(b, n); });
  return out;
}

}  // namespace omma
