// File helpers: atomic writes (never leave a half-written output), image I/O with clear errors.
#pragma once

#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>

namespace omma {

class IoError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Calls write(tmp_path) with a temporary path in the same folder, then renames it onto `path`.
// On any exception the temporary file is removed and the exception propagates; `path` is untouched.
void write_atomically(const std::filesystem::path& path,
                      const std::function<void(const std::filesystem::path& tmp)>& write);
void write_text_atomically(const std::filesystem::path& path, const std::string& text);

// Reads an image (any OpenCV format) with its stored depth and channels (IMREAD_UNCHANGED unless
// flags given); throws IoError naming the path if it is missing or unreadable.
cv::Mat read_image(const std::filesystem::path& path, int flags = -1 /*cv::IMREAD_UNCHANGED*/);
// Writes an image atomically; the format comes from the extension. Throws IoError on failure.
void write_image(const std::filesystem::path& path, const cv::Mat& image);

std::string read_text_file(const std::filesystem::path& path);

}  // namespace omma
