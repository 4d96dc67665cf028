#include "omma/core/io.h"

#include <fstream>
#include <random>
#include <sstream>

#include <opencv2/imgcodecs.hpp>

namespace omma {
namespace fs = std::filesystem;

void write_atomically(const fs::path& path, const std::function<void(const fs::path&)>& write) {
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  if (!fs::is_directory(dir)) throw IoError("cannot write '" + path.string() + "': folder '" +
                                            dir.string() + "' does not exist");
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

void write_image(const fs::path& path, const cv::Mat& image) {
  if (image.empty()) throw IoError("refusing to write empty image '" + path.string() + "'");
  write_atomically(path, [&](const fs::path& tmp) {
    bool ok = false;
    try {
      ok = cv::imwrite(tmp.string(), image);
    } catch (const cv::Exception& e) {
      throw IoError("cannot write image '" + path.string() + "': " + e.what());
    }
    if (!ok) throw IoError("cannot write image '" + path.string() + "' (unknown extension?)");
  });
}

std::string read_text_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot open '" + path.string() + "'");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace omma
