#include "omma/io/metadata.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <optional>
#include <vector>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <zlib.h>

#include "omma/core/io.h"

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
uint32_t get_u32(const std::string& s, size_t at) {
  uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v = (v << 8) | uint8_t(s[at + i]);
  return v;
}
uint64_t get_u64(const std::string& s, size_t at) {
  return (uint64_t(get_u32(s, at)) << 32) | get_u32(s, at + 4);
}
void set_u32(std::string& s, size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i) s[at + i] = char((v >> (24 - 8 * i)) & 0xFF);
}
void set_u64(std::string& s, size_t at, uint64_t v) {
  set_u32(s, at, uint32_t(v >> 32));
  set_u32(s, at + 4, uint32_t(v));
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

// ---- MP4 ----------------------------------------------------------------------------------------

struct Box {
  size_t start = 0;   // offset of the box's header
  size_t header = 8;  // 8, or 16 with a 64-bit size
  uint64_t size = 0;  // whole box
  std::string type;
  size_t end() const { return start + size_t(size); }
};

// The box at `at` inside [.., limit) of `s`; nullopt if it does not fit.
std::optional<Box> box_at(const std::string& s, size_t at, size_t limit) {
  if (at + 8 > limit) return std::nullopt;
  Box b;
  b.start = at;
  b.size = get_u32(s, at);
  b.type = s.substr(at + 4, 4);
  if (b.size == 1) {
    if (at + 16 > limit) return std::nullopt;
    b.size = get_u64(s, at + 8);
    b.header = 16;
  } else if (b.size == 0) {
    b.size = limit - at;
  }
  if (b.size < b.header || b.size > limit - at) return std::nullopt;
  return b;
}

// Children of the box `parent` whose payload starts `skip` bytes after its header.
std::vector<Box> children(const std::string& s, const Box& parent, size_t skip = 0) {
  std::vector<Box> out;
  for (size_t at = parent.start + parent.header + skip; at < parent.end();) {
    const auto b = box_at(s, at, parent.end());
    if (!b) break;
    out.push_back(*b);
    at = b->end();
  }
  return out;
}

std::optional<Box> child(const std::string& s, const Box& parent, const std::string& type, size_t skip = 0) {
  for (const auto& b : children(s, parent, skip))
    if (b.type == type) return b;
  return std::nullopt;
}

void grow(std::string& s, const Box& b, size_t delta) {
  if (b.header == 16)
    set_u64(s, b.start + 8, b.size + delta);
  else if (b.size + delta > 0xFFFFFFFFull)
    throw IoError("cannot add spherical metadata: box too large");
  else
    set_u32(s, b.start, uint32_t(b.size + delta));
}

std::string full_box(const std::string& type, const std::string& payload) {
  std::string b;
  put_u32(b, uint32_t(12 + payload.size()));
  b += type;
  put_u32(b, 0);  // version 0, flags 0
  return b + payload;
}

std::string plain_box(const std::string& type, const std::string& payload) {
  std::string b;
  put_u32(b, uint32_t(8 + payload.size()));
  return b + type + payload;
}

// st3d (mono) + sv3d for the grid's layout (Spherical Video V2).
std::string spherical_v2_boxes(const PanoGrid& grid) {
  const SphericalLayout l = spherical_layout(grid);
  std::string st3d_payload(1, '\0');  // stereo_mode 0: monoscopic
  const std::string st3d = full_box("st3d", st3d_payload);
  const std::string svhd = full_box("svhd", std::string("omma") + '\0');  // metadata source, NUL-terminated
  std::string prhd_payload;
  for (int i = 0; i < 3; ++i) put_u32(prhd_payload, 0);  // pose yaw, pitch, roll: 0 (16.16 fixed point)
  // Bounds: the fractions of the full sphere cut off at the top, bottom, left and right, as 0.32
  // fixed point (value * 2^32, rounded down).
  auto frac = [](int part, int whole) { return uint32_t((uint64_t(part) << 32) / uint64_t(whole)); };
  std::string equi_payload;
  put_u32(equi_payload, frac(l.top, l.full_height));
  put_u32(equi_payload, frac(l.full_height - l.top - l.height, l.full_height));
  put_u32(equi_payload, frac(l.left, l.full_width));
  put_u32(equi_payload, frac(l.full_width - l.left - l.width, l.full_width));
  const std::string proj = plain_box("proj", full_box("prhd", prhd_payload) + full_box("equi", equi_payload));
  return st3d + plain_box("sv3d", svhd + proj);
}

// The movie box of the MP4 file read by `in` (file_size bytes), found from the top-level box
// headers; throws (message prefix `what`) if the box structure is damaged or there is not
// exactly one.
Box movie_box(std::ifstream& in, uint64_t file_size, const std::string& what) {
  std::optional<Box> moov;
  for (uint64_t at = 0; at < file_size;) {
    std::string head(16, '\0');
    in.seekg(std::streamoff(at));
    in.read(head.data(), 16);
    head.resize(size_t(in.gcount()));
    in.clear();
    if (head.size() < 8) throw IoError(what + "not an MP4 file (damaged box structure)");
    Box b{size_t(at), 8, get_u32(head, 0), head.substr(4, 4)};
    if (b.size == 1 && head.size() == 16)
      b.size = get_u64(head, 8), b.header = 16;
    else if (b.size == 0)
      b.size = file_size - at;  // "to the end of the file"
    if (b.size < b.header || b.size > file_size - at)
      throw IoError(what + "not an MP4 file (damaged box structure)");
    if (b.type == "moov") {
      if (moov) throw IoError(what + "two movie boxes");
      if (b.size > (uint64_t(1) << 30)) throw IoError(what + "movie box too large");
      moov = b;
    }
    at += b.size;
  }
  if (!moov) throw IoError(what + "no movie box (not an MP4 file?)");
  return *moov;
}

// The boxes from the movie box `root` (in m) down to the first sample entry of the first video
// track, outermost first: moov/trak (handler 'vide')/mdia/minf/stbl/stsd/entry; empty if none.
std::vector<Box> video_sample_entry_path(const std::string& m, const Box& root) {
  for (const Box& trak : children(m, root)) {
    if (trak.type != "trak") continue;
    const auto mdia = child(m, trak, "mdia");
    if (!mdia) continue;
    const auto hdlr = child(m, *mdia, "hdlr");
    if (!hdlr || hdlr->size < hdlr->header + 12 || m.substr(hdlr->start + hdlr->header + 8, 4) != "vide")
      continue;
    const auto minf = child(m, *mdia, "minf");
    const auto stbl = minf ? child(m, *minf, "stbl") : std::nullopt;
    const auto stsd = stbl ? child(m, *stbl, "stsd") : std::nullopt;
    if (!stsd) continue;
    const auto entries = children(m, *stsd, 8);  // after version/flags and entry_count
    if (entries.empty()) continue;
    const Box entry = entries.front();
    return {root, trak, *mdia, *minf, *stbl, *stsd, entry};
  }
  return {};
}

// Adds delta (bytes) to every chunk offset (stco / co64) of every track of the movie box `root`
// (in m) at or behind the file position moved_from; throws (message prefix `what`) if a table is
// damaged or a 32-bit offset overflows.
void shift_chunk_offsets(std::string& m, const Box& root, uint64_t moved_from, size_t delta,
                         const std::string& what) {
  for (const Box& trak : children(m, root)) {
    if (trak.type != "trak") continue;
    const auto mdia = child(m, trak, "mdia");
    const auto minf = mdia ? child(m, *mdia, "minf") : std::nullopt;
    const auto stbl = minf ? child(m, *minf, "stbl") : std::nullopt;
    if (!stbl) continue;
    for (const Box& t : children(m, *stbl)) {
      const bool co64 = t.type == "co64";
      if ((t.type != "stco" && !co64) || t.size < t.header + 8) continue;
      const size_t first = t.start + t.header + 8, n = get_u32(m, t.start + t.header + 4);
      const size_t width = co64 ? 8 : 4;
      if (n > (t.end() - first) / width) throw IoError(what + "damaged chunk offset table");
      for (size_t i = 0; i < n; ++i) {
        const size_t at = first + i * width;
        const uint64_t off = co64 ? get_u64(m, at) : get_u32(m, at);
        if (off < moved_from) continue;
        if (co64)
          set_u64(m, at, off + delta);
        else if (off + delta > 0xFFFFFFFFull)
          throw IoError(what + "chunk offset overflow");
        else
          set_u32(m, at, uint32_t(off + delta));
      }
    }
  }
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

std::string gpano_xmp(const PanoGrid& grid) {
  const SphericalLayout l = spherical_layout(grid);
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

bool carries_xmp(const fs::path& path) {
  const std::string e = lower_extension(path);
  return e == ".jpg" || e == ".jpeg" || e == ".png";
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
  std::vector<uchar> buf;
  try {
    if (!cv::imencode(lower_extension(path), image, buf))
      throw IoError("cannot encode image '" + path.string() + "'");
  } catch (const cv::Exception& e) {
    throw IoError("cannot write image '" + path.string() + "': " + e.what());
  }
  const std::string bytes = embed_xmp(std::string_view(reinterpret_cast<const char*>(buf.data()), buf.size()),
                                      path.extension().string(), gpano_xmp(grid));
  write_atomically(path, [&](const fs::path& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    out.write(bytes.data(), std::streamsize(bytes.size()));
    if (!out.flush()) throw IoError("cannot write image '" + path.string() + "'");
  });
}

void add_spherical_video_metadata(const fs::path& path, const PanoGrid& grid) {
  const std::string what = "cannot add spherical metadata to '" + path.string() + "': ";
  std::ifstream in(path, std::ios::binary);
  std::error_code ec;
  const uint64_t file_size = fs::file_size(path, ec);
  if (!in || ec) throw IoError("cannot open video '" + path.string() + "'");
  // Top-level boxes (headers only): exactly one moov, which is read into memory; the media data
  // around it is copied in blocks.
  const Box moov = movie_box(in, file_size, what);
  std::string m(size_t(moov.size), '\0');
  in.seekg(std::streamoff(moov.start));
  if (!in.read(m.data(), std::streamsize(m.size()))) throw IoError(what + "cannot read the movie box");
  const Box root{0, moov.header, moov.size, "moov"};
  // moov/trak (handler 'vide')/mdia/minf/stbl/stsd/first sample entry.
  // path_boxes: the ancestors to grow, outermost first.
  const std::vector<Box> path_boxes = video_sample_entry_path(m, root);
  if (path_boxes.empty()) throw IoError(what + "no video track");
  const Box entry = path_boxes.back();
  constexpr size_t kVisualSampleEntry = 78;  // fields of a VisualSampleEntry before its child boxes
  if (entry.size < entry.header + kVisualSampleEntry) throw IoError(what + "damaged video sample entry");
  if (child(m, entry, "sv3d", kVisualSampleEntry)) return;  // already spherical
  const std::string boxes = spherical_v2_boxes(grid);
  const size_t insert_at = entry.end();
  m.insert(insert_at, boxes);
  for (const Box& b : path_boxes) grow(m, b, boxes.size());
  // Chunk offsets (absolute file positions) behind the insertion move with it: the media data
  // when the movie box comes first ("fast start").
  const uint64_t moved_from = moov.start + insert_at;
  const Box root2{0, moov.header, moov.size + boxes.size(), "moov"};
  shift_chunk_offsets(m, root2, moved_from, boxes.size(), what);
  write_atomically(path, [&](const fs::path& tmp) {
    std::ofstream o(tmp, std::ios::binary);
    std::vector<char> block(1 << 20);
    auto copy = [&](uint64_t from, uint64_t to) {
      in.seekg(std::streamoff(from));
      for (uint64_t left = to - from; left > 0;) {
        const size_t n = size_t(std::min<uint64_t>(left, block.size()));
        if (!in.read(block.data(), std::streamsize(n))) throw IoError(what + "read failed");
        o.write(block.data(), std::streamsize(n));
        left -= n;
      }
    };
    copy(0, moov.start);
    o.write(m.data(), std::streamsize(m.size()));
    copy(moov.end(), file_size);
    if (!o.flush()) throw IoError("cannot write video '" + path.string() + "'");
  });
}

}  // namespace omma::io
