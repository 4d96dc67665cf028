#include "omma/io/spherical_video.h"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/spherical.h>
#include <libavutil/stereo3d.h>
}

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <optional>
#include <regex>
#include <vector>

#include <fmt/format.h>

#include "omma/core/io.h"
#include "omma/io/metadata.h"

namespace omma::io {
namespace fs = std::filesystem;

namespace {

// ---- bytes --------------------------------------------------------------------------------------

void put_u32(std::string& s, uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) s.push_back(char((v >> shift) & 0xFF));
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

// The V1 uuid ffcc8263-f855-4a93-8814-587a02521fdd.
const std::string kV1Uuid("\xff\xcc\x82\x63\xf8\x55\x4a\x93\x88\x14\x58\x7a\x02\x52\x1f\xdd", 16);

// ---- ISO base media file boxes ------------------------------------------------------------------

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

// Changes the size field of `b` (in s) by delta bytes.
void resize_box(std::string& s, const Box& b, int64_t delta, const std::string& what) {
  const int64_t size = int64_t(b.size) + delta;
  if (b.header == 16)
    set_u64(s, b.start + 8, uint64_t(size));
  else if (size > int64_t(0xFFFFFFFFll))
    throw IoError(what + "box too large");
  else
    set_u32(s, b.start, uint32_t(size));
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

// The `equi` projection bounds of the grid's layout: the fractions of the full sphere cut off at the
// top, bottom, left and right, 0.32 fixed point (value * 2^32, rounded down). The MP4 box and
// FFmpeg's side data (Matroska) carry the same four numbers.
struct EquiBounds {
  uint32_t top = 0, bottom = 0, left = 0, right = 0;
};
EquiBounds equi_bounds(const PanoGrid& grid) {
  const SphericalLayout l = spherical_layout(grid);
  auto frac = [](int part, int whole) { return uint32_t((uint64_t(part) << 32) / uint64_t(whole)); };
  return {frac(l.top, l.full_height), frac(l.full_height - l.top - l.height, l.full_height),
          frac(l.left, l.full_width), frac(l.full_width - l.left - l.width, l.full_width)};
}

// st3d (mono) + sv3d for the grid's layout (Spherical Video V2).
std::string spherical_v2_boxes(const PanoGrid& grid) {
  const std::string st3d = full_box("st3d", std::string(1, '\0'));        // stereo_mode 0: monoscopic
  const std::string svhd = full_box("svhd", std::string("omma") + '\0');  // metadata source, NUL-terminated
  std::string prhd_payload;
  for (int i = 0; i < 3; ++i) put_u32(prhd_payload, 0);  // pose yaw, pitch, roll: 0 (16.16 fixed point)
  const EquiBounds b = equi_bounds(grid);
  std::string equi_payload;
  for (const uint32_t v : {b.top, b.bottom, b.left, b.right}) put_u32(equi_payload, v);
  const std::string proj = plain_box("proj", full_box("prhd", prhd_payload) + full_box("equi", equi_payload));
  return st3d + plain_box("sv3d", svhd + proj);
}

std::string spherical_v1_box(const PanoGrid& grid) {
  return plain_box("uuid", kV1Uuid + spherical_v1_xml(grid));
}

// The movie box of the file read by `in` (file_size bytes), found from the top-level box headers;
// throws (message prefix `what`) if the box structure is damaged or there is not exactly one.
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

constexpr size_t kVisualSampleEntry = 78;  // fields of a VisualSampleEntry before its child boxes

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
    return {root, trak, *mdia, *minf, *stbl, *stsd, entries.front()};
  }
  return {};
}

// Adds delta (bytes, either sign) to every chunk offset (stco / co64) of every track of the movie
// box `root` (in m) at or behind the file position moved_from; throws (message prefix `what`) if a
// table is damaged or a 32-bit offset overflows.
void shift_chunk_offsets(std::string& m, const Box& root, uint64_t moved_from, int64_t delta,
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
        const int64_t moved = int64_t(off) + delta;
        if (moved < 0 || (!co64 && moved > int64_t(0xFFFFFFFFll)))
          throw IoError(what + "chunk offset overflow");
        if (co64)
          set_u64(m, at, uint64_t(moved));
        else
          set_u32(m, at, uint32_t(moved));
      }
    }
  }
}

bool is_v1_box(const std::string& m, const Box& b) {
  return b.type == "uuid" && b.size >= b.header + 16 && m.compare(b.start + b.header, 16, kV1Uuid) == 0;
}

// The existing V2 boxes (st3d, sv3d in the sample entry) and V1 box (in the trak) of the video
// track, concatenated in file order: to compare with what would be written.
std::string existing_metadata(const std::string& m, const std::vector<Box>& path) {
  std::string v2, v1;
  for (const Box& b : children(m, path.back(), kVisualSampleEntry))
    if (b.type == "st3d" || b.type == "sv3d") v2 += m.substr(b.start, size_t(b.size));
  for (const Box& b : children(m, path[1]))
    if (is_v1_box(m, b)) v1 += m.substr(b.start, size_t(b.size));
  return v2 + v1;
}

// Removes the first box of `m` that `match` selects among the children of path[depth] (skip: its
// header fields), shrinking path[0..depth]; false if there is none.
template <class Match>
bool remove_one(std::string& m, const std::vector<Box>& path, size_t depth, size_t skip, Match match,
                const std::string& what) {
  for (const Box& b : children(m, path[depth], skip)) {
    if (!match(b)) continue;
    const int64_t delta = -int64_t(b.size);
    for (size_t i = 0; i <= depth; ++i) resize_box(m, path[i], delta, what);
    m.erase(b.start, size_t(b.size));
    return true;
  }
  return false;
}

bool set_isobmff(const fs::path& path, const PanoGrid& grid) {
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
  auto root = [&] { return Box{0, moov.header, uint64_t(m.size()), "moov"}; };
  auto find_path = [&] {
    std::vector<Box> p = video_sample_entry_path(m, root());
    if (p.empty()) throw IoError(what + "no video track");
    if (p.back().size < p.back().header + kVisualSampleEntry)
      throw IoError(what + "damaged video sample entry");
    return p;
  };
  const std::string v2 = spherical_v2_boxes(grid), v1 = spherical_v1_box(grid);
  if (existing_metadata(m, find_path()) == v2 + v1) return false;
  // Out with the old (V2 in the sample entry, V1 in the trak), in with the new at their ends.
  const size_t depth_entry = 6, depth_trak = 1;
  auto is_v2 = [](const Box& b) { return b.type == "st3d" || b.type == "sv3d"; };
  while (remove_one(m, find_path(), depth_entry, kVisualSampleEntry, is_v2, what)) {
  }
  while (remove_one(
      m, find_path(), depth_trak, 0, [&](const Box& b) { return is_v1_box(m, b); }, what)) {
  }
  std::vector<Box> p = find_path();
  m.insert(p.back().end(), v2);
  for (const Box& b : p) resize_box(m, b, int64_t(v2.size()), what);
  p = find_path();
  m.insert(p[depth_trak].end(), v1);
  for (size_t i = 0; i <= depth_trak; ++i) resize_box(m, p[i], int64_t(v1.size()), what);
  // Chunk offsets (absolute file positions) behind the movie box move with its size: the media
  // data when the movie box comes first ("fast start").
  const int64_t delta = int64_t(m.size()) - int64_t(moov.size);
  if (moov.header == 8 && m.size() > 0xFFFFFFFFull) throw IoError(what + "movie box too large");
  shift_chunk_offsets(m, root(), moov.end(), delta, what);
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
  return true;
}

// ---- libavformat ---------------------------------------------------------------------------------

struct InputCloser {
  void operator()(AVFormatContext* c) const { avformat_close_input(&c); }
};
using Input = std::unique_ptr<AVFormatContext, InputCloser>;

Input open_input(const fs::path& path) {
  AVFormatContext* c = nullptr;
  if (const int e = avformat_open_input(&c, path.c_str(), nullptr, nullptr); e < 0)
    throw IoError("cannot open video '" + path.string() + "': " + av_error(e));
  return Input(c);
}

int video_stream(AVFormatContext* c) {
  for (unsigned i = 0; i < c->nb_streams; ++i)
    if (c->streams[i]->codecpar->codec_type == AVMEDIA_TYPE_VIDEO &&
        !(c->streams[i]->disposition & AV_DISPOSITION_ATTACHED_PIC))
      return int(i);
  return -1;
}

bool set_matroska(const fs::path& path, const PanoGrid& grid) {
  const std::string what = "cannot add spherical metadata to '" + path.string() + "': ";
  Input in = open_input(path);
  if (const int e = avformat_find_stream_info(in.get(), nullptr); e < 0) throw IoError(what + av_error(e));
  const int vs = video_stream(in.get());
  if (vs < 0) throw IoError(what + "no video stream");
  const std::string name = in->iformat->name;
  if (name.find("matroska") == std::string::npos) throw IoError(what + "not a Matroska/WebM file");
  // Already this metadata? (as the muxer stores it: bounds compared in 0.32 fixed point)
  {
    const auto [want, size] = spherical_side_data(grid);
    size_t have_size = 0;
    const auto* have = reinterpret_cast<const AVSphericalMapping*>(
        av_stream_get_side_data(in->streams[vs], AV_PKT_DATA_SPHERICAL, &have_size));
    const bool same = have && have->projection == want->projection && have->bound_top == want->bound_top &&
                      have->bound_bottom == want->bound_bottom && have->bound_left == want->bound_left &&
                      have->bound_right == want->bound_right && !have->yaw && !have->pitch && !have->roll;
    av_free(want);
    if (same) return false;
  }
  const bool webm = lower_extension(path) == ".webm";
  write_atomically(path, [&](const fs::path& tmp) {
    AVFormatContext* out = nullptr;
    if (const int e = avformat_alloc_output_context2(&out, nullptr, webm ? "webm" : "matroska", tmp.c_str());
        e < 0)
      throw IoError(what + av_error(e));
    std::unique_ptr<AVFormatContext, void (*)(AVFormatContext*)> guard(out, [](AVFormatContext* c) {
      if (c->pb) avio_closep(&c->pb);
      avformat_free_context(c);
    });
    av_dict_copy(&out->metadata, in->metadata, 0);
    std::vector<int> map(in->nb_streams, -1);
    for (unsigned i = 0; i < in->nb_streams; ++i) {
      const AVStream* is = in->streams[i];
      const auto type = is->codecpar->codec_type;
      if (type != AVMEDIA_TYPE_VIDEO && type != AVMEDIA_TYPE_AUDIO && type != AVMEDIA_TYPE_SUBTITLE) continue;
      AVStream* os = avformat_new_stream(out, nullptr);
      if (!os || avcodec_parameters_copy(os->codecpar, is->codecpar) < 0)
        throw IoError(what + "out of memory");
      os->codecpar->codec_tag = 0;
      os->time_base = is->time_base;
      os->disposition = is->disposition;
      av_dict_copy(&os->metadata, is->metadata, 0);
      for (int k = 0; k < is->nb_side_data; ++k) {
        const AVPacketSideData& sd = is->side_data[k];
        if (int(i) == vs && (sd.type == AV_PKT_DATA_SPHERICAL || sd.type == AV_PKT_DATA_STEREO3D)) continue;
        uint8_t* copy = av_stream_new_side_data(os, sd.type, sd.size);
        if (!copy) throw IoError(what + "out of memory");
        std::copy(sd.data, sd.data + sd.size, copy);
      }
      if (int(i) == vs) {
        const auto [s, size] = spherical_side_data(grid);
        if (av_stream_add_side_data(os, AV_PKT_DATA_SPHERICAL, reinterpret_cast<uint8_t*>(s), size) < 0) {
          av_free(s);
          throw IoError(what + "out of memory");
        }
      }
      map[i] = os->index;
    }
    if (const int e = avio_open(&out->pb, tmp.c_str(), AVIO_FLAG_WRITE); e < 0)
      throw IoError(what + av_error(e));
    if (const int e = avformat_write_header(out, nullptr); e < 0) throw IoError(what + av_error(e));
    AVPacket* pkt = av_packet_alloc();
    std::unique_ptr<AVPacket, void (*)(AVPacket*)> pkt_guard(pkt, [](AVPacket* p) { av_packet_free(&p); });
    for (;;) {
      const int e = av_read_frame(in.get(), pkt);
      if (e == AVERROR_EOF) break;
      if (e < 0) throw IoError(what + "read failed: " + av_error(e));
      const int o = map[size_t(pkt->stream_index)];
      if (o < 0) {
        av_packet_unref(pkt);
        continue;
      }
      av_packet_rescale_ts(pkt, in->streams[pkt->stream_index]->time_base, out->streams[o]->time_base);
      pkt->stream_index = o;
      pkt->pos = -1;
      if (const int w = av_interleaved_write_frame(out, pkt); w < 0)
        throw IoError("cannot write video '" + path.string() + "': " + av_error(w));
    }
    if (const int e = av_write_trailer(out); e < 0)
      throw IoError("cannot write video '" + path.string() + "': " + av_error(e));
    if (const int e = avio_closep(&out->pb); e < 0)
      throw IoError("cannot write video '" + path.string() + "': " + av_error(e));
  });
  return true;
}

// The V1 fields of the first video trak of an MP4/MOV file ({} if none or not such a file).
std::optional<std::map<std::string, std::string>> read_v1(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::error_code ec;
  const uint64_t file_size = fs::file_size(path, ec);
  if (!in || ec) return std::nullopt;
  std::string m;
  try {
    const Box moov = movie_box(in, file_size, "");
    m.assign(size_t(moov.size), '\0');
    in.seekg(std::streamoff(moov.start));
    if (!in.read(m.data(), std::streamsize(m.size()))) return std::nullopt;
    const auto p = video_sample_entry_path(m, Box{0, moov.header, moov.size, "moov"});
    if (p.empty()) return std::nullopt;
    for (const Box& b : children(m, p[1])) {
      if (!is_v1_box(m, b)) continue;
      const std::string xml = m.substr(b.start + b.header + 16, size_t(b.size) - b.header - 16);
      std::map<std::string, std::string> fields;
      static const std::regex element(R"(<GSpherical:(\w+)>([^<]*)</GSpherical:\1>)");
      for (std::sregex_iterator it(xml.begin(), xml.end(), element), end; it != end; ++it)
        fields[(*it)[1]] = (*it)[2];
      return fields;
    }
  } catch (const IoError&) {
  }
  return std::nullopt;
}

}  // namespace

std::string av_error(int code) {
  char buf[AV_ERROR_MAX_STRING_SIZE] = {};
  av_strerror(code, buf, sizeof buf);
  return buf;
}

std::pair<AVSphericalMapping*, size_t> spherical_side_data(const PanoGrid& grid) {
  size_t size = 0;
  AVSphericalMapping* s = av_spherical_alloc(&size);
  if (!s) throw std::bad_alloc();
  const EquiBounds b = equi_bounds(grid);
  s->bound_top = b.top;
  s->bound_bottom = b.bottom;
  s->bound_left = b.left;
  s->bound_right = b.right;
  const bool whole = !s->bound_top && !s->bound_bottom && !s->bound_left && !s->bound_right;
  s->projection = whole ? AV_SPHERICAL_EQUIRECTANGULAR : AV_SPHERICAL_EQUIRECTANGULAR_TILE;
  return {s, size};
}

std::string spherical_v1_xml(const PanoGrid& grid) {
  const SphericalLayout l = spherical_layout(grid);
  return fmt::format(
      "<?xml version=\"1.0\"?><rdf:SphericalVideo\n"
      "xmlns:rdf=\"http://www.w3.org/1999/02/22-rdf-syntax-ns#\"\n"
      "xmlns:GSpherical=\"http://ns.google.com/videos/1.0/spherical/\">"
      "<GSpherical:Spherical>true</GSpherical:Spherical>"
      "<GSpherical:Stitched>true</GSpherical:Stitched>"
      "<GSpherical:StitchingSoftware>omma ({})</GSpherical:StitchingSoftware>"
      "<GSpherical:ProjectionType>equirectangular</GSpherical:ProjectionType>"
      "<GSpherical:StereoMode>mono</GSpherical:StereoMode>"
      "<GSpherical:FullPanoWidthPixels>{}</GSpherical:FullPanoWidthPixels>"
      "<GSpherical:FullPanoHeightPixels>{}</GSpherical:FullPanoHeightPixels>"
      "<GSpherical:CroppedAreaImageWidthPixels>{}</GSpherical:CroppedAreaImageWidthPixels>"
      "<GSpherical:CroppedAreaImageHeightPixels>{}</GSpherical:CroppedAreaImageHeightPixels>"
      "<GSpherical:CroppedAreaLeftPixels>{}</GSpherical:CroppedAreaLeftPixels>"
      "<GSpherical:CroppedAreaTopPixels>{}</GSpherical:CroppedAreaTopPixels>"
      "</rdf:SphericalVideo>",
      to_string(grid.projection), l.full_width, l.full_height, l.width, l.height, l.left, l.top);
}

bool is_isobmff_path(const fs::path& path) {
  const std::string e = lower_extension(path);
  return e == ".mp4" || e == ".m4v" || e == ".mov";
}

bool is_matroska_path(const fs::path& path) {
  const std::string e = lower_extension(path);
  return e == ".mkv" || e == ".webm";
}

bool set_spherical_video_metadata(const fs::path& path, const PanoGrid& grid) {
  if (is_matroska_path(path)) return set_matroska(path, grid);
  return set_isobmff(path, grid);
}

void add_spherical_video_metadata(const fs::path& path, const PanoGrid& grid) {
  set_spherical_video_metadata(path, grid);
}

SphericalVideoInfo read_spherical_video_metadata(const fs::path& path) {
  Input in = open_input(path);
  const int vs = video_stream(in.get());
  if (vs < 0) throw IoError("'" + path.string() + "' has no video stream");
  const AVStream* st = in->streams[vs];
  SphericalVideoInfo info;
  info.container = in->iformat->name;
  info.codec = avcodec_get_name(st->codecpar->codec_id);
  info.width = st->codecpar->width;
  info.height = st->codecpar->height;
  if (const auto* s = reinterpret_cast<const AVSphericalMapping*>(
          av_stream_get_side_data(st, AV_PKT_DATA_SPHERICAL, nullptr))) {
    info.v2 = true;
    info.projection = s->projection == AV_SPHERICAL_EQUIRECTANGULAR_TILE
                          ? "tiled equirectangular"
                          : av_spherical_projection_name(s->projection);
    if (s->projection == AV_SPHERICAL_EQUIRECTANGULAR_TILE) {
      size_t l = 0, t = 0, r = 0, b = 0;
      av_spherical_tile_bounds(s, size_t(info.width), size_t(info.height), &l, &t, &r, &b);
      info.bound_left = int64_t(l), info.bound_top = int64_t(t), info.bound_right = int64_t(r),
      info.bound_bottom = int64_t(b);
    }
    info.yaw = s->yaw / 65536.0, info.pitch = s->pitch / 65536.0, info.roll = s->roll / 65536.0;
  }
  if (const auto* s =
          reinterpret_cast<const AVStereo3D*>(av_stream_get_side_data(st, AV_PKT_DATA_STEREO3D, nullptr)))
    info.stereo = av_stereo3d_type_name(s->type);
  if (info.container.find("mp4") != std::string::npos) {
    if (auto v1 = read_v1(path)) {
      info.v1 = true;
      info.v1_fields = std::move(*v1);
    }
  }
  return info;
}

nlohmann::json SphericalVideoInfo::to_json() const {
  nlohmann::json j = {{"container", container}, {"codec", codec}, {"width", width}, {"height", height}};
  nlohmann::json v2j = nullptr;
  if (v2)
    v2j = {{"projection", projection},
           {"bound_left", bound_left},
           {"bound_top", bound_top},
           {"bound_right", bound_right},
           {"bound_bottom", bound_bottom},
           {"yaw", yaw},
           {"pitch", pitch},
           {"roll", roll},
           {"stereo", stereo}};
  j["spherical_v2"] = v2j;
  j["spherical_v1"] = v1 ? nlohmann::json(v1_fields) : nlohmann::json(nullptr);
  j["spherical"] = v1 || v2;
  return j;
}

}  // namespace omma::io
