#include "omma/io/metadata.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <mutex>
#include <optional>
#include <set>
#include <stdexcept>
#include <tuple>
#include <vector>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <spdlog/spdlog.h>
#include <zlib.h>

extern "C" {
#include <libavutil/base64.h>
#include <libavutil/md5.h>
}

#include "omma/core/io.h"
#include "omma/io/tiff_writer.h"

namespace omma::io {
namespace fs = std::filesystem;

namespace {

void put_u32(std::string& s, uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) s.push_back(char((v >> shift) & 0xFF));
}
void put_u16(std::string& s, uint16_t v) {
  s.push_back(char(v >> 8));
  s.push_back(char(v & 0xFF));
}

// ---- JPEG and PNG -----------------------------------------------------------------------------

std::string embed_xmp_jpeg(std::string_view jpg, const std::string& xmp) {
  static constexpr std::string_view kNs("http://ns.adobe.com/xap/1.0/\0", 29);
  if (jpg.size() < 4 || uint8_t(jpg[0]) != 0xFF || uint8_t(jpg[1]) != 0xD8)
    throw IoError("cannot add XMP: not a JPEG file");
  const size_t payload = kNs.size() + xmp.size();
  if (payload + 2 > 0xFFFF) throw IoError("cannot add XMP: packet too large for one JPEG segment");
  // After SOI and the JFIF APP0 segment (which must come first), if there is one.
  size_t at = 2;
  if (jpg.size() >= at + 4 && uint8_t(jpg[at]) == 0xFF && uint8_t(jpg[at + 1]) == 0xE0)
    at += 2 + ((uint8_t(jpg[at + 2]) << 8) | uint8_t(jpg[at + 3]));
  if (at > jpg.size()) throw IoError("cannot add XMP: damaged JPEG file");
  std::string seg = "\xFF\xE1";
  put_u16(seg, uint16_t(payload + 2));  // the length counts itself, not the marker
  seg.append(kNs);
  seg.append(xmp);
  std::string out(jpg.substr(0, at));
  out += seg;
  out.append(jpg.substr(at));
  return out;
}

std::string embed_xmp_png(std::string_view png, const std::string& xmp) {
  static constexpr std::string_view kSig("\x89PNG\r\n\x1a\n", 8);
  if (png.size() < 33 || png.substr(0, 8) != kSig || png.substr(12, 4) != "IHDR")
    throw IoError("cannot add XMP: not a PNG file");
  // iTXt: keyword, NUL, compression flag 0, method 0, empty language tag and translated keyword
  // (NUL each), then the UTF-8 text; the CRC covers the type and the data.
  std::string data = std::string("XML:com.adobe.xmp") + std::string("\0\0\0\0\0", 5) + xmp;
  std::string chunk;
  put_u32(chunk, uint32_t(data.size()));
  const std::string typed = "iTXt" + data;
  chunk += typed;
  put_u32(chunk, uint32_t(crc32(0L, reinterpret_cast<const Bytef*>(typed.data()), uInt(typed.size()))));
  const size_t at = 8 + 8 + 13 + 4;  // signature, IHDR (length, type, 13 bytes, CRC)
  std::string out(png.substr(0, at));
  out += chunk;
  out.append(png.substr(at));
  return out;
}

}  // namespace

SphericalLayout spherical_layout(const PanoGrid& g) {
  SphericalLayout l;
  l.width = g.width;
  l.height = g.height;
  switch (g.projection) {
    case Projection::kEquirect:  // 90 of 180 degrees, from the zenith down
      l.full_width = g.width;
      l.full_height = 2 * g.height;
      break;
    case Projection::kVr180:  // the middle 180 of 360 degrees
      l.full_width = 2 * g.width;
      l.full_height = g.height;
      l.left = g.width / 2;
      break;
    case Projection::kEquirectFull:
      l.full_width = g.width;
      l.full_height = g.height;
      break;
    case Projection::kEquirect100:  // 100 of 180 degrees, from the zenith down
      l.full_width = g.width;
      l.full_height = static_cast<int>(std::lround(g.height * 180.0 / 100.0));
      break;
  }
  return l;
}

std::optional<SphericalLayout> photo_sphere_layout(const PanoGrid& g, std::string* why) {
  const AngularSpan span = angular_span(g.projection);
  // Square pixels: the height the width implies for the grid's span, within half a pixel.
  const double square_height = g.width * span.height / span.width;
  if (g.width < 1 || g.height < 1 || std::abs(g.height - square_height) > 0.5) {
    if (why) {
      const double deg = 180.0 / kPi;
      *why = fmt::format(
          "{}x{} {} has non-square pixels ({:.2f} x {:.2f} px/deg); no GPano written; use --size {}x{} for "
          "a viewer-ready panorama",
          g.width, g.height, to_string(g.projection), g.width / (span.width * deg),
          g.height / (span.height * deg), g.width, std::max<long>(1, std::lround(square_height)));
    }
    return std::nullopt;
  }
  SphericalLayout l;
  l.width = g.width;
  l.height = g.height;
  l.full_width = static_cast<int>(std::lround(g.width * 2 * kPi / span.width));
  // A grid spanning every latitude is the full height itself; a cap from the zenith down is a crop.
  l.full_height = span.height >= kPi - 1e-9 ? g.height : static_cast<int>(std::lround(l.full_width / 2.0));
  l.left = (l.full_width - l.width) / 2;  // vr180: the front half; 0 for the 360-degree grids
  l.top = 0;
  return l;
}

std::string gpano_xmp(const PanoGrid& grid) {
  std::string why;
  const std::optional<SphericalLayout> layout = photo_sphere_layout(grid, &why);
  if (!layout) throw std::invalid_argument(why);
  const SphericalLayout& l = *layout;
  return fmt::format(
      "<?xpacket begin=\"\xEF\xBB\xBF\" id=\"W5M0MpCehiHzreSzNTczkc9d\"?>\n"
      "<x:xmpmeta xmlns:x=\"adobe:ns:meta/\" x:xmptk=\"omma\">\n"
      " <rdf:RDF xmlns:rdf=\"http://www.w3.org/1999/02/22-rdf-syntax-ns#\">\n"
      "  <rdf:Description rdf:about=\"\" xmlns:GPano=\"http://ns.google.com/photos/1.0/panorama/\">\n"
      "   <GPano:UsePanoramaViewer>True</GPano:UsePanoramaViewer>\n"
      "   <GPano:ProjectionType>equirectangular</GPano:ProjectionType>\n"
      "   <GPano:FullPanoWidthPixels>{}</GPano:FullPanoWidthPixels>\n"
      "   <GPano:FullPanoHeightPixels>{}</GPano:FullPanoHeightPixels>\n"
      "   <GPano:CroppedAreaImageWidthPixels>{}</GPano:CroppedAreaImageWidthPixels>\n"
      "   <GPano:CroppedAreaImageHeightPixels>{}</GPano:CroppedAreaImageHeightPixels>\n"
      "   <GPano:CroppedAreaLeftPixels>{}</GPano:CroppedAreaLeftPixels>\n"
      "   <GPano:CroppedAreaTopPixels>{}</GPano:CroppedAreaTopPixels>\n"
      "   <GPano:StitchingSoftware>omma ({})</GPano:StitchingSoftware>\n"
      "  </rdf:Description>\n"
      " </rdf:RDF>\n"
      "</x:xmpmeta>\n"
      "<?xpacket end=\"w\"?>",
      l.full_width, l.full_height, l.width, l.height, l.left, l.top, to_string(grid.projection));
}

std::string panorama_xmp(const PanoGrid& grid) {
  std::string why;
  if (photo_sphere_layout(grid, &why)) return gpano_xmp(grid);
  // One warning per projection and size: a run's thousands of frames, or a demo's many methods,
  // share one grid.
  static std::mutex mutex;
  static std::set<std::tuple<int, int, int>> warned;
  std::lock_guard lock(mutex);
  if (warned.insert({static_cast<int>(grid.projection), grid.width, grid.height}).second)
    spdlog::warn("{}", why);
  return {};
}

bool carries_xmp(const fs::path& path) {
  const std::string e = lower_extension(path);
  return e == ".jpg" || e == ".jpeg" || e == ".png" || e == ".tif" || e == ".tiff";
}

std::string embed_xmp(std::string_view encoded, const std::string& ext, const std::string& xmp) {
  const std::string e = lower_extension(fs::path("x" + ext));
  if (e == ".jpg" || e == ".jpeg") return embed_xmp_jpeg(encoded, xmp);
  if (e == ".png") return embed_xmp_png(encoded, xmp);
  throw IoError("cannot add XMP to a '" + ext + "' file (JPEG and PNG only)");
}

void write_panorama(const fs::path& path, const cv::Mat& image, const PanoGrid& grid) {
  if (!carries_xmp(path)) return write_image(path, image);
  if (image.empty()) throw IoError("refusing to write empty image '" + path.string() + "'");
  if (image.cols != grid.width || image.rows != grid.height)
    throw IoError(fmt::format("panorama '{}' is {}x{} but its grid is {}x{}", path.string(), image.cols,
                              image.rows, grid.width, grid.height));
  const std::string xmp = panorama_xmp(grid);
  const std::string ext = lower_extension(path);
  if (ext == ".tif" || ext == ".tiff") {
    // OpenCV's encoder (any depth and channels it takes), then the XMP and the resolution tags
    // added to the temporary file's directory.
    return write_image(path, image, [&](const fs::path& tmp) { add_tiff_metadata(tmp, xmp); });
  }
  if (xmp.empty()) return write_image(path, image);
  std::vector<uchar> buf;
  try {
    if (!cv::imencode(ext, image, buf)) throw IoError("cannot encode image '" + path.string() + "'");
  } catch (const cv::Exception& e) {
    throw IoError("cannot write image '" + path.string() + "': " + e.what());
  }
  const std::string bytes = embed_xmp(std::string_view(reinterpret_cast<const char*>(buf.data()), buf.size()),
                                      path.extension().string(), xmp);
  write_atomically(path, [&](const fs::path& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    out.write(bytes.data(), std::streamsize(bytes.size()));
    if (!out.flush()) throw IoError("cannot write image '" + path.string() + "'");
  });
}

// ---- Additions for depth panoramas (depth_pano.h) -------------------------------------------------

std::string base64_encode(std::string_view bytes) {
  if (bytes.size() > size_t(INT32_MAX / 4 * 3 - 3)) throw IoError("base64: data too large");
  std::string out(AV_BASE64_SIZE(bytes.size()), '\0');  // with its terminating NUL
  if (!av_base64_encode(out.data(), int(out.size()), reinterpret_cast<const uint8_t*>(bytes.data()),
                        int(bytes.size())))
    throw IoError("base64: cannot encode");
  out.resize(out.size() - 1);
  return out;
}

std::string gpano_description(const PanoGrid& grid) {
  if (!photo_sphere_layout(grid)) return {};
  const std::string packet = gpano_xmp(grid);
  const size_t begin = packet.find("  <rdf:Description");
  const std::string close = "</rdf:Description>\n";
  const size_t end = packet.find(close, begin);
  return packet.substr(begin, end + close.size() - begin);
}

std::string xmp_packet(const std::string& descriptions) {
  return "<?xpacket begin=\"\xEF\xBB\xBF\" id=\"W5M0MpCehiHzreSzNTczkc9d\"?>\n"
         "<x:xmpmeta xmlns:x=\"adobe:ns:meta/\" x:xmptk=\"omma\">\n"
         " <rdf:RDF xmlns:rdf=\"http://www.w3.org/1999/02/22-rdf-syntax-ns#\">\n" +
         descriptions +
         " </rdf:RDF>\n"
         "</x:xmpmeta>\n"
         "<?xpacket end=\"w\"?>";
}

std::string extended_xmp_guid(const std::string& extended) {
  uint8_t digest[16];
  av_md5_sum(digest, reinterpret_cast<const uint8_t*>(extended.data()), extended.size());
  std::string hex;
  for (uint8_t b : digest) hex += fmt::format("{:02X}", b);
  return hex;
}

std::string embed_xmp_jpeg_extended(std::string_view jpg, const std::string& xmp,
                                    const std::string& extended) {
  static constexpr std::string_view kNs("http://ns.adobe.com/xmp/extension/\0", 35);
  if (extended.size() > UINT32_MAX) throw IoError("cannot add extended XMP: larger than 4 GB");
  const std::string with_standard = embed_xmp_jpeg(jpg, xmp);
  // The extended segments go right after the standard one: find its end again.
  size_t at = 2;
  if (uint8_t(with_standard[at]) == 0xFF && uint8_t(with_standard[at + 1]) == 0xE0)
    at += 2 + ((uint8_t(with_standard[at + 2]) << 8) | uint8_t(with_standard[at + 3]));
  at += 2 + ((uint8_t(with_standard[at + 2]) << 8) | uint8_t(with_standard[at + 3]));  // the XMP APP1
  const std::string guid = extended_xmp_guid(extended);
  const size_t head = kNs.size() + 32 + 4 + 4;
  const size_t portion = 0xFFFF - 2 - head;  // a segment's length counts itself
  std::string segs;
  for (size_t off = 0; off < extended.size(); off += portion) {
    const size_t n = std::min(portion, extended.size() - off);
    segs += "\xFF\xE1";
    put_u16(segs, uint16_t(2 + head + n));
    segs.append(kNs);
    segs += guid;
    put_u32(segs, uint32_t(extended.size()));
    put_u32(segs, uint32_t(off));
    segs.append(extended, off, n);
  }
  std::string out = with_standard.substr(0, at);
  out += segs;
  out.append(with_standard, at, std::string::npos);
  return out;
}

}  // namespace omma::io
