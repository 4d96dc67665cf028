#include "omma/core/frames.h"

#include <algorithm>
#include <cctype>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "omma/core/io.h"

namespace omma {
namespace fs = std::filesystem;

std::string frame_filename(int id) { return fmt::format("cam_{:02d}.png", id); }
std::string raw_frame_filename(int id) { return fmt::format("cam_{:02d}_raw.png", id); }

const std::vector<std::string>& frame_extensions() {
  static const std::vector<std::string> ext = {".png", ".jpg", ".jpeg", ".tif", ".tiff"};
  return ext;
}

bool is_frame_filename(const std::string& name) {
  const std::string ext = lower_extension(name);
  const auto& all = frame_extensions();
  if (std::find(all.begin(), all.end(), ext) == all.end()) return false;
  const std::string stem = name.substr(0, name.size() - ext.size());
  if (stem.size() < 5 || stem.rfind("cam_", 0) != 0) return false;
  return std::all_of(stem.begin() + 4, stem.end(), [](unsigned char c) { return std::isdigit(c) != 0; });
}

fs::path find_frame(const fs::path& dir, int id) {
  const std::string stem = fmt::format("cam_{:02d}", id);
  std::vector<fs::path> found;
  std::error_code ec;
  if (fs::is_directory(dir, ec))
    for (const auto& e : fs::directory_iterator(dir, ec)) {
      const std::string name = e.path().filename().string();
      if (name.size() > stem.size() && name.compare(0, stem.size(), stem) == 0 && name[stem.size()] == '.' &&
          is_frame_filename(name))
        found.push_back(e.path());
    }
  if (found.size() == 1) return found[0];
  if (found.empty()) {
    // The usual name, so that read_image's error names the file a user expects.
    return dir / frame_filename(id);
  }
  std::sort(found.begin(), found.end());
  std::string names;
  for (const auto& p : found) names += (names.empty() ? "'" : ", '") + p.string() + "'";
  throw IoError(fmt::format("camera {} has several frames: {} (keep one)", id, names));
}

static void check_size(const cv::Mat& m, const RigCamera& c, const fs::path& p) {
  if (m.cols != c.in.width || m.rows != c.in.height)
    throw IoError(fmt::format("frame '{}' is {}x{} but camera {} is {}x{} in the rig", p.string(), m.cols,
                              m.rows, c.id, c.in.width, c.in.height));
}

std::vector<cv::Mat> load_frames(const fs::path& dir, const Rig& rig) {
  if (!fs::is_directory(dir)) throw IoError("frames folder '" + dir.string() + "' does not exist");
  std::vector<cv::Mat> frames;
  for (const auto& c : rig.cameras) {
    const fs::path p = find_frame(dir, c.id);
    if (!fs::exists(p))
      throw IoError(fmt::format("frame '{}' does not exist (nor cam_{:02d} with .jpg, .jpeg, .tif, .tiff)",
                                p.string(), c.id));
    // Not IMREAD_UNCHANGED: that flag skips the EXIF orientation of JPEGs. ANYDEPTH keeps 16 bits,
    // ANYCOLOR keeps gray as gray (expanded below) and drops an alpha channel.
    cv::Mat m = read_image(p, cv::IMREAD_ANYDEPTH | cv::IMREAD_ANYCOLOR);
    if (m.channels() == 1) cv::cvtColor(m, m, cv::COLOR_GRAY2BGR);
    if (m.channels() == 4) cv::cvtColor(m, m, cv::COLOR_BGRA2BGR);
    if (m.depth() != CV_8U && m.depth() != CV_16U)
      throw IoError("frame '" + p.string() + "' must be 8- or 16-bit");
    check_size(m, c, p);
    frames.push_back(m);
  }
  return frames;
}

std::vector<cv::Mat> load_raw_frames(const fs::path& dir, const Rig& rig) {
  if (!fs::is_directory(dir)) throw IoError("frames folder '" + dir.string() + "' does not exist");
  std::vector<cv::Mat> frames;
  for (const auto& c : rig.cameras) {
    const fs::path p = dir / raw_frame_filename(c.id);
    cv::Mat m = read_image(p);
    if (m.type() != CV_16UC1)
      throw IoError("raw frame '" + p.string() + "' must be a 16-bit single-channel Bayer image");
    check_size(m, c, p);
    frames.push_back(m);
  }
  return frames;
}

std::vector<fs::path> expand_shot_folders(const std::vector<fs::path>& paths) {
  std::vector<fs::path> out;
  for (const fs::path& p : paths) {
    if (!fs::is_directory(p)) throw IoError("frames folder '" + p.string() + "' does not exist");
    std::vector<fs::path> shots;
    bool has_frames = false;
    for (const auto& e : fs::directory_iterator(p)) {
      const std::string name = e.path().filename().string();
      if (e.is_directory() && name.rfind("shot_", 0) == 0) shots.push_back(e.path());
      if (e.is_regular_file() && is_frame_filename(name)) has_frames = true;
    }
    if (has_frames) {
      out.push_back(p);
    } else if (!shots.empty()) {
      std::sort(shots.begin(), shots.end());
      out.insert(out.end(), shots.begin(), shots.end());
    } else {
      throw IoError("'" + p.string() +
                    "' is neither a frames folder (cam_XX.png) nor a shots folder (shot_XX/)");
    }
  }
  return out;
}

std::vector<std::vector<cv::Mat>> load_frame_sets(const std::vector<fs::path>& paths, const Rig& rig) {
  std::vector<std::vector<cv::Mat>> sets;
  for (const fs::path& p : expand_shot_folders(paths)) sets.push_back(load_frames(p, rig));
  return sets;
}

cv::Mat to_float01(const cv::Mat& image) {
  cv::Mat out;
  const double scale = image.depth() == CV_8U ? 1.0 / 255 : image.depth() == CV_16U ? 1.0 / 65535 : 1.0;
  image.convertTo(out, CV_MAKETYPE(CV_32F, image.channels()), scale);
  return out;
}

cv::Mat to_u8(const cv::Mat& image01) {
  cv::Mat out;
  image01.convertTo(out, CV_MAKETYPE(CV_8U, image01.channels()), 255.0);
  return out;
}

}  // namespace omma
