// omma meta FILE [--projection P]: the 360-degree metadata of a video or photo: shows it, or puts it
// back after an outside tool dropped it (ffmpeg re-encodes, photo editors).
#include <iostream>
#include <map>
#include <regex>
#include <string>

#include <fmt/format.h>

#include "apps/command.h"
#include "omma/core/grid.h"
#include "omma/core/io.h"
#include "omma/io/metadata.h"
#include "omma/io/spherical_video.h"

namespace omma::app {
namespace {
namespace fs = std::filesystem;

bool is_photo(const fs::path& p) {
  const std::string e = lower_extension(p);
  return e == ".jpg" || e == ".jpeg" || e == ".png";
}

// The GPano fields of the XMP in a photo's bytes (element or attribute form), name -> text.
std::map<std::string, std::string> gpano_fields(const std::string& bytes) {
  std::map<std::string, std::string> out;
  static const std::regex field(R"re(GPano:(\w+)(?:="([^"]*)"|>([^<]*)</GPano:\1>))re");
  for (std::sregex_iterator it(bytes.begin(), bytes.end(), field), end; it != end; ++it)
    out[(*it)[1]] = (*it)[2].matched ? (*it)[2].str() : (*it)[3].str();
  return out;
}

// `bytes` (a JPEG or PNG file) without its XMP packets: JPEG APP1 segments of the XMP namespace,
// PNG iTXt chunks with the keyword XML:com.adobe.xmp. Throws IoError if the structure is damaged.
std::string strip_xmp(const std::string& bytes, const std::string& ext, const fs::path& path) {
  const std::string what = "'" + path.string() + "': ";
  std::string out;
  auto u16 = [&](size_t at) { return (size_t(uint8_t(bytes[at])) << 8) | uint8_t(bytes[at + 1]); };
  auto u32 = [&](size_t at) { return (u16(at) << 16) | u16(at + 2); };
  if (ext == ".png") {
    if (bytes.size() < 8 || bytes.compare(0, 8, "\x89PNG\r\n\x1a\n", 8) != 0)
      throw IoError(what + "not a PNG file");
    out = bytes.substr(0, 8);
    for (size_t at = 8; at < bytes.size();) {
      if (at + 12 > bytes.size()) throw IoError(what + "damaged PNG chunk");
      const size_t len = u32(at);
      if (len > bytes.size() - at - 12) throw IoError(what + "damaged PNG chunk");
      const bool xmp = bytes.compare(at + 4, 4, "iTXt") == 0 &&
                       bytes.compare(at + 8, 18, std::string("XML:com.adobe.xmp\0", 18)) == 0;
      if (!xmp) out.append(bytes, at, len + 12);
      at += len + 12;
    }
    return out;
  }
  // JPEG: the marker segments up to the start of scan; the rest (entropy-coded data) as it is.
  if (bytes.size() < 4 || uint8_t(bytes[0]) != 0xFF || uint8_t(bytes[1]) != 0xD8)
    throw IoError(what + "not a JPEG file");
  static const std::string kNs("http://ns.adobe.com/xap/1.0/\0", 29);
  out = bytes.substr(0, 2);
  size_t at = 2;
  while (at + 4 <= bytes.size() && uint8_t(bytes[at]) == 0xFF) {
    const uint8_t marker = uint8_t(bytes[at + 1]);
    if (marker == 0xDA || marker == 0xD9) break;  // start of scan, end of image
    const size_t len = u16(at + 2);
    if (len < 2 || at + 2 + len > bytes.size()) throw IoError(what + "damaged JPEG segment");
    const bool xmp = marker == 0xE1 && len >= 2 + kNs.size() && bytes.compare(at + 4, kNs.size(), kNs) == 0;
    if (!xmp) out.append(bytes, at, 2 + len);
    at += 2 + len;
  }
  out.append(bytes, at, std::string::npos);
  return out;
}

void print_video(const io::SphericalVideoInfo& v) {
  std::cout << fmt::format("{}: {} {}x{}\n", v.container, v.codec, v.width, v.height);
  if (v.v2)
    std::cout << fmt::format(
        "  Spherical Video V2: {}, cut off left {} top {} right {} bottom {} px, pose yaw {} pitch {} roll "
        "{} "
        "deg{}\n",
        v.projection, v.bound_left, v.bound_top, v.bound_right, v.bound_bottom, v.yaw, v.pitch, v.roll,
        v.stereo.empty() ? "" : ", stereo " + v.stereo);
  else
    std::cout << "  Spherical Video V2: none\n";
  if (v.v1) {
    std::cout << "  Spherical Video V1:";
    for (const auto& [k, val] : v.v1_fields) std::cout << " " << k << "=" << val;
    std::cout << "\n";
  } else {
    std::cout << "  Spherical Video V1: none\n";
  }
}

}  // namespace

void add_meta_command(CLI::App& root) {
  static std::string file, projection;
  static bool json = false;
  auto* cmd = root.add_subcommand(
      "meta",
      "Show or write the 360-degree metadata of a video (mp4, m4v, mov, mkv, webm) or photo (jpg, png).\n"
      "Without --projection: what the file carries (Spherical Video V2 and V1, GPano XMP).\n"
      "With --projection: writes that projection's metadata for the file's own pixel size, in place and\n"
      "atomically, replacing what it had: videos get Spherical Video V2 (st3d/sv3d; mkv/webm: the\n"
      "Projection element) and V1 (the GSpherical uuid box; mp4/mov), frames copied unchanged; photos the\n"
      "GPano XMP (JPEG and PNG bytes otherwise unchanged). E.g. after `ffmpeg -i pano.mp4 -c:v libx264\n"
      "re.mp4`, which drops it: omma meta re.mp4 --projection vr180");
  cmd->add_option("FILE", file, "Video or photo")->required();
  cmd->add_option(
      "--projection", projection,
      "The panorama's projection: vr180, equirect, equirect-full, equirect-100 (as omma wrote it)");
  cmd->add_flag("--json", json, "Print one JSON object on stdout");
  cmd->callback([] {
    set_json_mode(json);
    const fs::path path(file);
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) throw IoError("'" + file + "' is not a file");
    nlohmann::json j = {{"file", file}};
    if (is_photo(path)) {
      const std::string ext = lower_extension(path);
      if (!projection.empty()) {
        const cv::Mat image = read_image(path);
        const PanoGrid grid{parse_projection(projection), image.cols, image.rows};
        const std::string xmp = io::gpano_xmp(grid);  // refuses non-square pixels, saying why
        const std::vector<uint8_t> raw = read_file(path, kMaxDataFileBytes, "photo");
        const std::string bytes =
            io::embed_xmp(strip_xmp(std::string(raw.begin(), raw.end()), ext, path), ext, xmp);
        write_text_atomically(path, bytes);
        j["written"] = true;
        j["projection"] = projection;
      }
      const std::vector<uint8_t> raw = read_file(path, kMaxDataFileBytes, "photo");
      const auto fields = gpano_fields(std::string(raw.begin(), raw.end()));
      j["gpano"] = fields.empty() ? nlohmann::json(nullptr) : nlohmann::json(fields);
      j["spherical"] = !fields.empty();
      if (json) return print_json(j);
      if (fields.empty()) std::cout << file << ": no GPano XMP\n";
      for (const auto& [k, v] : fields) std::cout << "GPano:" << k << " = " << v << "\n";
      return;
    }
    if (!io::is_isobmff_path(path) && !io::is_matroska_path(path))
      throw std::invalid_argument("'" + file +
                                  "': omma meta reads mp4, m4v, mov, mkv, webm, jpg and png files");
    io::SphericalVideoInfo info = io::read_spherical_video_metadata(path);
    if (!projection.empty()) {
      const PanoGrid grid{parse_projection(projection), info.width, info.height};
      j["written"] = io::set_spherical_video_metadata(path, grid);  // false: it had exactly this
      j["projection"] = projection;
      info = io::read_spherical_video_metadata(path);
    }
    j.update(info.to_json());
    if (json) return print_json(j);
    if (j.contains("written"))
      std::cerr << fmt::format("omma meta: {} {} {} metadata for its {}x{} frames\n", file,
                               j["written"].get<bool>() ? "now has the" : "already had the", projection,
                               info.width, info.height);
    print_video(info);
  });
}

}  // namespace omma::app
