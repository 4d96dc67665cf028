#include "omma/io/depth_pano.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <spdlog/spdlog.h>

#include "omma/core/io.h"
#include "omma/core/version.h"
#include "omma/io/metadata.h"

namespace omma::io {
namespace fs = std::filesystem;

namespace {

void check_depth_type(const cv::Mat& depth, const char* what) {
  if (depth.type() != CV_32FC1)
    throw std::invalid_argument(
        fmt::format("{}: the depth map must be CV_32FC1 (mm), got type {}", what, depth.type()));
}

// Bytes of an encoded image (OpenCV's encoder), with a clear error.
std::string encode(const std::string& ext, const cv::Mat& image, const std::string& what) {
  std::vector<uchar> buf;
  try {
    if (!cv::imencode(ext, image, buf)) throw IoError("cannot encode " + what);
  } catch (const cv::Exception& e) {
    throw IoError("cannot encode " + what + ": " + e.what());
  }
  return std::string(reinterpret_cast<const char*>(buf.data()), buf.size());
}

void write_bytes(const fs::path& path, const std::string& bytes) {
  write_atomically(path, [&](const fs::path& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    out.write(bytes.data(), std::streamsize(bytes.size()));
    if (!out.flush()) throw IoError("cannot write '" + path.string() + "'");
  });
}

constexpr const char* kGDepthNs = "http://ns.google.com/photos/1.0/depthmap/";

}  // namespace

DepthRange depth_range(const cv::Mat& depth) {
  DepthRange r;
  if (depth.empty()) return r;
  check_depth_type(depth, "depth range");
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (int y = 0; y < depth.rows; ++y) {
    const float* d = depth.ptr<float>(y);
    for (int x = 0; x < depth.cols; ++x)
      if (std::isfinite(d[x])) {
        lo = std::min(lo, double(d[x]));
        hi = std::max(hi, double(d[x]));
        ++r.finite;
      }
  }
  if (r.finite > 0) {
    r.near_mm = lo;
    r.far_mm = hi;
  }
  return r;
}

cv::Mat depth_to_png16(const cv::Mat& depth) {
  check_depth_type(depth, "depth PNG");
  cv::Mat out(depth.size(), CV_16UC1);
  for (int y = 0; y < depth.rows; ++y) {
    const float* d = depth.ptr<float>(y);
    uint16_t* o = out.ptr<uint16_t>(y);
    for (int x = 0; x < depth.cols; ++x) {
      if (std::isnan(d[x]) || !(d[x] > 0))
        throw std::invalid_argument(
            fmt::format("depth PNG: depth {} at pixel ({}, {}) is not a distance > 0", d[x], x, y));
      o[x] = std::isinf(d[x]) ? 0 : uint16_t(std::clamp(std::lround(double(d[x])), 1L, long(kDepthPngMaxMm)));
    }
  }
  return out;
}

cv::Mat depth_from_png16(const cv::Mat& png16) {
  if (png16.type() != CV_16UC1)
    throw std::invalid_argument(
        fmt::format("depth PNG: expected 16-bit one channel, got type {}", png16.type()));
  cv::Mat out(png16.size(), CV_32FC1);
  for (int y = 0; y < png16.rows; ++y) {
    const uint16_t* v = png16.ptr<uint16_t>(y);
    float* o = out.ptr<float>(y);
    for (int x = 0; x < png16.cols; ++x)
      o[x] = v[x] == 0 ? std::numeric_limits<float>::infinity() : float(v[x]);
  }
  return out;
}

std::string depth_png_xmp(const PanoGrid& grid) {
  const std::string gdepth = fmt::format(
      "  <rdf:Description rdf:about=\"\" xmlns:GDepth=\"{}\" xmlns:dc=\"http://purl.org/dc/elements/1.1/\">\n"
      "   <GDepth:Format>RangeLinear</GDepth:Format>\n"
      "   <GDepth:Near>0</GDepth:Near>\n"
      "   <GDepth:Far>{:.0f}</GDepth:Far>\n"
      "   <GDepth:Units>mm</GDepth:Units>\n"
      "   <GDepth:MeasureType>OpticRay</GDepth:MeasureType>\n"
      "   <GDepth:Software>omma {}</GDepth:Software>\n"
      "   <GDepth:ImageWidth>{}</GDepth:ImageWidth>\n"
      "   <GDepth:ImageHeight>{}</GDepth:ImageHeight>\n"
      "   <dc:description>\n"
      "    <rdf:Alt>\n"
      "     <rdf:li xml:lang=\"x-default\">omma depth panorama ({} {}x{}): 16-bit depth in millimetres along "
      "each "
      "pixel's ray from the observer (the dome centre unless stated), 0 = unknown or infinity, saturating at "
      "{:.0f} mm</rdf:li>\n"
      "    </rdf:Alt>\n"
      "   </dc:description>\n"
      "  </rdf:Description>\n",
      kGDepthNs, kDepthPngMaxMm, version(), grid.width, grid.height, to_string(grid.projection), grid.width,
      grid.height, kDepthPngMaxMm);
  return xmp_packet(gpano_description(grid) + gdepth);
}

void write_depth_png(const fs::path& path, const cv::Mat& depth, const PanoGrid& grid) {
  if (lower_extension(path) != ".png")
    throw std::invalid_argument("the depth panorama must be a .png file, got '" + path.string() + "'");
  check_depth_type(depth, "depth panorama");
  if (depth.cols != grid.width || depth.rows != grid.height)
    throw std::invalid_argument(fmt::format("depth panorama '{}' is {}x{} but its grid is {}x{}",
                                            path.string(), depth.cols, depth.rows, grid.width, grid.height));
  const std::string png = encode(".png", depth_to_png16(depth), "depth panorama '" + path.string() + "'");
  write_bytes(path, embed_xmp(png, ".png", depth_png_xmp(grid)));
}

cv::Mat read_depth_png(const fs::path& path) {
  const cv::Mat img = read_image(path);
  if (img.type() != CV_16UC1)
    throw IoError("depth panorama '" + path.string() + "' is not a 16-bit one-channel image");
  return depth_from_png16(img);
}

cv::Mat gdepth_encode_inverse(const cv::Mat& depth, const DepthRange& r) {
  check_depth_type(depth, "GDepth");
  const double n = r.near_mm, f = r.far_mm;
  if (!(n > 0 && f >= n && std::isfinite(f)))
    throw std::invalid_argument(fmt::format("GDepth: bad range {}..{} mm", n, f));
  cv::Mat out(depth.size(), CV_16UC1);
  for (int y = 0; y < depth.rows; ++y) {
    const float* d = depth.ptr<float>(y);
    uint16_t* o = out.ptr<uint16_t>(y);
    for (int x = 0; x < depth.cols; ++x) {
      const double D = std::isinf(d[x]) ? f : std::clamp(double(d[x]), n, f);
      const double dn = f > n ? f * (D - n) / (D * (f - n)) : 0.0;
      o[x] = uint16_t(std::lround(std::clamp(dn, 0.0, 1.0) * 65535.0));
    }
  }
  return out;
}

cv::Mat gdepth_decode_inverse(const cv::Mat& png16, double n, double f) {
  if (png16.type() != CV_16UC1) throw std::invalid_argument("GDepth: expected a 16-bit one-channel image");
  cv::Mat out(png16.size(), CV_32FC1);
  for (int y = 0; y < png16.rows; ++y) {
    const uint16_t* v = png16.ptr<uint16_t>(y);
    float* o = out.ptr<float>(y);
    for (int x = 0; x < png16.cols; ++x) o[x] = float(f * n / (f - v[x] / 65535.0 * (f - n)));
  }
  return out;
}

void write_panorama_with_depth(const fs::path& path, const cv::Mat& colour, const cv::Mat& depth,
                               const PanoGrid& grid) {
  const std::string ext = lower_extension(path);
  if (ext != ".jpg" && ext != ".jpeg" && ext != ".png")
    throw std::invalid_argument("a depth map is embedded in JPEG and PNG panoramas only, not '" +
                                path.string() + "'");
  if (colour.cols != grid.width || colour.rows != grid.height)
    throw IoError(fmt::format("panorama '{}' is {}x{} but its grid is {}x{}", path.string(), colour.cols,
                              colour.rows, grid.width, grid.height));
  if (!depth.empty() && (depth.cols != grid.width || depth.rows != grid.height))
    throw std::invalid_argument(fmt::format("the depth map is {}x{} but the grid is {}x{}", depth.cols,
                                            depth.rows, grid.width, grid.height));
  const DepthRange r = depth_range(depth);
  if (r.finite == 0) {
    spdlog::warn("{}: the depth has no finite value: no GDepth depth map embedded", path.string());
    return write_panorama(path, colour, grid);
  }
  const std::string data =
      base64_encode(encode(".png", gdepth_encode_inverse(depth, r), "the embedded depth map"));
  const std::string fields = fmt::format(
      "   <GDepth:Format>RangeInverse</GDepth:Format>\n"
      "   <GDepth:Near>{}</GDepth:Near>\n"
      "   <GDepth:Far>{}</GDepth:Far>\n"
      "   <GDepth:Units>mm</GDepth:Units>\n"
      "   <GDepth:MeasureType>OpticRay</GDepth:MeasureType>\n"
      "   <GDepth:Mime>image/png</GDepth:Mime>\n"
      "   <GDepth:Software>omma {}</GDepth:Software>\n"
      "   <GDepth:ImageWidth>{}</GDepth:ImageWidth>\n"
      "   <GDepth:ImageHeight>{}</GDepth:ImageHeight>\n",
      r.near_mm, r.far_mm, version(), grid.width, grid.height);
  const std::string image = encode(ext, colour, "panorama '" + path.string() + "'");
  std::string bytes;
  if (ext == ".png") {
    const std::string desc = fmt::format(
        "  <rdf:Description rdf:about=\"\" xmlns:GDepth=\"{}\">\n{}   <GDepth:Data>{}</GDepth:Data>\n"
        "  </rdf:Description>\n",
        kGDepthNs, fields, data);
    bytes = embed_xmp(image, ext, xmp_packet(gpano_description(grid) + desc));
  } else {
    const std::string extended = fmt::format(
        "<x:xmpmeta xmlns:x=\"adobe:ns:meta/\" x:xmptk=\"omma\">"
        "<rdf:RDF xmlns:rdf=\"http://www.w3.org/1999/02/22-rdf-syntax-ns#\">"
        "<rdf:Description rdf:about=\"\" xmlns:GDepth=\"{}\"><GDepth:Data>{}</GDepth:Data></rdf:Description>"
        "</rdf:RDF></x:xmpmeta>",
        kGDepthNs, data);
    const std::string desc = fmt::format(
        "  <rdf:Description rdf:about=\"\" xmlns:GDepth=\"{}\" "
        "xmlns:xmpNote=\"http://ns.adobe.com/xmp/note/\">\n"
        "{}   <xmpNote:HasExtendedXMP>{}</xmpNote:HasExtendedXMP>\n"
        "  </rdf:Description>\n",
        kGDepthNs, fields, extended_xmp_guid(extended));
    bytes = embed_xmp_jpeg_extended(image, xmp_packet(gpano_description(grid) + desc), extended);
  }
  write_bytes(path, bytes);
}

}  // namespace omma::io
