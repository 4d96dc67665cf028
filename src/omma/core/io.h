// File helpers: atomic writes (never leave a half-written output), image I/O with clear errors.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

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
// Removes `tmp`, a temporary file that an earlier run writing `target` left behind (killed before it
// could finish), naming it in a warning; nothing if there is none.
void remove_leftover(const std::filesystem::path& tmp, const std::filesystem::path& target);

// Reads an image (any OpenCV format) with its stored depth and channels (IMREAD_UNCHANGED unless
// flags given); throws IoError naming the path if it is missing or unreadable.
cv::Mat read_image(const std::filesystem::path& path, int flags = -1 /*cv::IMREAD_UNCHANGED*/);
// The extension of `path` in lower case, with its dot (".jpg" for "a/B.JPG"; "" without one): how
// every format-by-extension choice reads a file name.
std::string lower_extension(const std::filesystem::path& path);

// Writes an image atomically; the format comes from the extension. `finish`, if given, is called with
// the encoded temporary file before it is renamed onto `path` (to add metadata OpenCV does not
// write). Throws IoError on failure.
void write_image(const std::filesystem::path& path, const cv::Mat& image,
                 const std::function<void(const std::filesystem::path& tmp)>& finish = {});
// Can write_image write a width x height image to `path`? Throws IoError naming the path unless
// OpenCV has a writer for the extension and the format holds the size (JPEG at most 65500 pixels a
// side, WebP 16383). Call it before the work that makes the image.
void check_image_format(const std::filesystem::path& path, std::int64_t width, std::int64_t height);

// Upper bounds on the files omma reads whole (a rig of kMaxCameras cameras is about 3 MB; Hugin
// projects with 10^5 control points about 8 MB; a compiled map of a 16384 x 16384 panorama a few GB).
inline constexpr std::uintmax_t kMaxTextFileBytes = std::uintmax_t(64) << 20;  // rig JSON, PTO
inline constexpr std::uintmax_t kMaxDataFileBytes = std::uintmax_t(8) << 30;   // link streams, maps

// Reads a whole file of at most max_bytes. Refuses, before reading anything, a path that is missing
// or is not a regular file (a folder, a device such as /dev/zero, a FIFO or socket; symbolic links
// are followed) and a file larger than max_bytes; a file that grows while it is read is cut off at
// max_bytes + 1 and refused. Throws IoError naming `what` (e.g. "rig file") and the path.
std::vector<uint8_t> read_file(const std::filesystem::path& path, std::uintmax_t max_bytes,
                               const std::string& what = "file");
// read_file as text.
std::string read_text_file(const std::filesystem::path& path, std::uintmax_t max_bytes = kMaxTextFileBytes,
                           const std::string& what = "file");

}  // namespace omma
