#include "omma/io/point_cloud.h"

#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "omma/core/io.h"
#include "omma/core/version.h"

namespace omma::io {
namespace fs = std::filesystem;

bool PointCloudOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (step < 1) return fail(fmt::format("the point cloud's step must be >= 1, got {}", step));
  if (!(min_confidence >= 0 && min_confidence <= 1))
    return fail(
        fmt::format("the point cloud's minimum confidence must be in [0, 1], got {}", min_confidence));
  if (!q.allFinite()) return fail("the point cloud's observer q must be finite");
  return true;
}

PointCloud depth_to_points(const cv::Mat& depth, const cv::Mat& colour, const PanoGrid& grid,
                           const PointCloudOptions& opt, const cv::Mat& confidence) {
  std::string why;
  if (!opt.IsValid(&why)) throw std::invalid_argument(why);
  const cv::Size size(grid.width, grid.height);
  if (colour.size() != size || colour.depth() != CV_8U ||
      (colour.channels() != 1 && colour.channels() != 3 && colour.channels() != 4))
    throw std::invalid_argument(
        fmt::format("point cloud: the colour panorama must be 8-bit 1, 3 or 4 channels "
                    "of the grid's {}x{}, got {}x{} with {} channels of depth code {}",
                    grid.width, grid.height, colour.cols, colour.rows, colour.channels(), colour.depth()));
  if (!depth.empty() && (depth.type() != CV_32FC1 || depth.size() != size))
    throw std::invalid_argument(
        fmt::format("point cloud: the depth map must be CV_32FC1 {}x{}, got {}x{} type {}", grid.width,
                    grid.height, depth.cols, depth.rows, depth.type()));
  if (!confidence.empty() && (confidence.type() != CV_32FC1 || confidence.size() != size))
    throw std::invalid_argument(
        fmt::format("point cloud: the confidence map must be CV_32FC1 {}x{}, got {}x{}", grid.width,
                    grid.height, confidence.cols, confidence.rows));
  PointCloud cloud;
  if (depth.empty()) return cloud;
  const int ch = colour.channels();
  for (int row = 0; row < grid.height; row += opt.step) {
    const float* d = depth.ptr<float>(row);
    const uint8_t* c = colour.ptr<uint8_t>(row);
    const float* conf = confidence.empty() ? nullptr : confidence.ptr<float>(row);
    for (int col = 0; col < grid.width; col += opt.step) {
      const float D = d[col];
      if (std::isnan(D) || !(D > 0))
        throw std::invalid_argument(
            fmt::format("point cloud: depth {} at pixel ({}, {}) is not a distance > 0", D, col, row));
      if (std::isinf(D)) continue;
      if (conf && !(conf[col] >= opt.min_confidence)) continue;
      const Vec3 X = opt.q + double(D) * grid.pixel_direction(col, row);
      cloud.xyz.push_back({float(X.x()), float(X.y()), float(X.z())});
      const uint8_t* p = c + size_t(col) * ch;
      cloud.rgb.push_back(ch == 1 ? std::array<uint8_t, 3>{p[0], p[0], p[0]}
                                  : std::array<uint8_t, 3>{p[2], p[1], p[0]});  // BGR(A) -> RGB
    }
  }
  return cloud;
}

std::string encode_ply(const PointCloud& cloud, const Vec3& q) {
  if (cloud.rgb.size() != cloud.xyz.size())
    throw std::invalid_argument(
        fmt::format("point cloud: {} positions but {} colours", cloud.xyz.size(), cloud.rgb.size()));
  std::string out = "ply\nformat binary_little_endian 1.0\n";
  out += fmt::format(
      "comment omma {}: x y z in millimetres in the rig (dome) frame: origin the dome centre, +z the\n"
      "comment dome axis; X = q + D w seen from q = ({}, {}, {}) mm; colours 8-bit sRGB of the panorama\n",
      version(), q.x(), q.y(), q.z());
  for (const std::string& c : cloud.comments) {
    if (c.find_first_of("\r\n") != std::string::npos)
      throw std::invalid_argument("a PLY comment must be one line, got '" + c + "'");
    out += "comment " + c + "\n";
  }
  out += fmt::format(
      "element vertex {}\nproperty float x\nproperty float y\nproperty float z\n"
      "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n",
      cloud.size());
  const size_t header = out.size();
  out.resize(header + cloud.size() * 15);
  char* p = out.data() + header;
  static_assert(std::numeric_limits<float>::is_iec559, "PLY float is IEEE 754");
  for (size_t i = 0; i < cloud.size(); ++i, p += 15) {
    for (int k = 0; k < 3; ++k) {
      uint32_t bits = 0;
      std::memcpy(&bits, &cloud.xyz[i][k], 4);
      for (int b = 0; b < 4; ++b) p[4 * k + b] = char((bits >> (8 * b)) & 0xFF);  // little-endian
    }
    for (int k = 0; k < 3; ++k) p[12 + k] = char(cloud.rgb[i][k]);
  }
  return out;
}

void write_ply(const fs::path& path, const PointCloud& cloud, const Vec3& q) {
  const std::string bytes = encode_ply(cloud, q);
  write_atomically(path, [&](const fs::path& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    out.write(bytes.data(), std::streamsize(bytes.size()));
    if (!out.flush()) throw IoError("cannot write point cloud '" + path.string() + "'");
  });
}

namespace {

struct Property {
  std::string name;
  int bytes = 0;  // 1, 2, 4, 8
  char kind = 0;  // 'i' signed, 'u' unsigned, 'f' float
};

bool scalar_type(const std::string& t, Property& p) {
  static const struct {
    const char* name;
    int bytes;
    char kind;
  } kTypes[] = {{"char", 1, 'i'},  {"int8", 1, 'i'},    {"uchar", 1, 'u'},  {"uint8", 1, 'u'},
                {"short", 2, 'i'}, {"int16", 2, 'i'},   {"ushort", 2, 'u'}, {"uint16", 2, 'u'},
                {"int", 4, 'i'},   {"int32", 4, 'i'},   {"uint", 4, 'u'},   {"uint32", 4, 'u'},
                {"float", 4, 'f'}, {"float32", 4, 'f'}, {"double", 8, 'f'}, {"float64", 8, 'f'}};
  for (const auto& k : kTypes)
    if (t == k.name) {
      p.bytes = k.bytes;
      p.kind = k.kind;
      return true;
    }
  return false;
}

double read_binary(const char* p, const Property& prop) {
  uint64_t bits = 0;
  for (int b = 0; b < prop.bytes; ++b) bits |= uint64_t(uint8_t(p[b])) << (8 * b);
  if (prop.kind == 'f') {
    if (prop.bytes == 4) {
      const uint32_t b32 = uint32_t(bits);
      float f;
      std::memcpy(&f, &b32, 4);
      return f;
    }
    double d;
    std::memcpy(&d, &bits, 8);
    return d;
  }
  if (prop.kind == 'u') return double(bits);
  const int shift = 64 - 8 * prop.bytes;  // sign-extend
  return double(int64_t(bits << shift) >> shift);
}

}  // namespace

PointCloud parse_ply(const std::string& bytes, const std::string& what) {
  auto bad = [&](const std::string& m) { return IoError(what + ": " + m); };
  if (bytes.compare(0, 4, "ply\n") != 0 && bytes.compare(0, 5, "ply\r\n") != 0)
    throw bad("not a PLY file (no 'ply' line)");
  const size_t end = bytes.find("end_header");
  if (end == std::string::npos) throw bad("no end_header");
  const size_t body = bytes.find('\n', end);
  if (body == std::string::npos) throw bad("end_header not followed by a newline");
  std::istringstream header(bytes.substr(0, end));
  std::string line, format;
  PointCloud cloud;
  long long vertices = -1;
  bool in_vertex = false, seen_other = false;
  std::vector<Property> props;
  while (std::getline(header, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string key;
    ls >> key;
    if (key == "format") {
      std::string version;
      ls >> format >> version;
    } else if (key == "comment") {
      cloud.comments.push_back(line.size() > 8 ? line.substr(8) : "");
    } else if (key == "element") {
      std::string name;
      long long n = -1;
      ls >> name >> n;
      if (name == "vertex") {
        if (seen_other) throw bad("an element comes before the vertices");
        if (n < 0 || ls.fail()) throw bad("bad vertex count");
        vertices = n;
        in_vertex = true;
      } else {
        if (vertices < 0) seen_other = true;
        in_vertex = false;
      }
    } else if (key == "property" && in_vertex) {
      std::string type, name;
      ls >> type >> name;
      Property p;
      if (type == "list" || !scalar_type(type, p))
        throw bad("vertex property '" + line + "' is not a scalar");
      p.name = name;
      props.push_back(p);
    }
  }
  if (format != "binary_little_endian" && format != "ascii")
    throw bad("format '" + format + "' (binary_little_endian or ascii only)");
  if (vertices < 0) throw bad("no vertex element");
  int ix[6] = {-1, -1, -1, -1, -1, -1};
  const char* names[6] = {"x", "y", "z", "red", "green", "blue"};
  size_t stride = 0;
  for (size_t i = 0; i < props.size(); ++i) {
    for (int k = 0; k < 6; ++k)
      if (props[i].name == names[k]) ix[k] = int(i);
    stride += size_t(props[i].bytes);
  }
  for (int k = 0; k < 6; ++k)
    if (ix[k] < 0) throw bad(std::string("the vertices have no property '") + names[k] + "'");
  cloud.xyz.resize(size_t(vertices));
  cloud.rgb.resize(size_t(vertices));
  auto store = [&](size_t v, const std::vector<double>& values) {
    for (int k = 0; k < 3; ++k) cloud.xyz[v][k] = float(values[size_t(ix[k])]);
    for (int k = 0; k < 3; ++k) {
      const double c = values[size_t(ix[3 + k])];
      if (!(c >= 0 && c <= 255)) throw bad(fmt::format("vertex {}: colour {} outside 0..255", v, c));
      cloud.rgb[v][k] = uint8_t(c);
    }
  };
  std::vector<double> values(props.size());
  if (format == "binary_little_endian") {
    if (bytes.size() - (body + 1) < uint64_t(vertices) * stride)
      throw bad(fmt::format("truncated: {} vertices of {} bytes need {} bytes, the file has {}", vertices,
                            stride, uint64_t(vertices) * stride, bytes.size() - (body + 1)));
    const char* p = bytes.data() + body + 1;
    for (size_t v = 0; v < size_t(vertices); ++v) {
      for (size_t i = 0; i < props.size(); ++i) {
        values[i] = read_binary(p, props[i]);
        p += props[i].bytes;
      }
      store(v, values);
    }
  } else {
    std::istringstream data(bytes.substr(body + 1));
    for (size_t v = 0; v < size_t(vertices); ++v) {
      for (size_t i = 0; i < props.size(); ++i)
        if (!(data >> values[i])) throw bad(fmt::format("truncated or bad number at vertex {}", v));
      store(v, values);
    }
  }
  return cloud;
}

PointCloud read_ply(const fs::path& path) {
  const std::vector<uint8_t> data = read_file(path, kMaxDataFileBytes, "point cloud");
  return parse_ply(std::string(data.begin(), data.end()), "point cloud " + path.string());
}

}  // namespace omma::io
