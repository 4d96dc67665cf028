// omma view3d CLOUD.ply --out DIR: a page that shows a point cloud in 3D (turn with the mouse, zoom with
// the wheel), self-contained so that it opens from file:// with no network: DIR/index.html carries
// three.js (npm `three`, embedded in omma at build time with the live page's web files,
// live/web_assets.h), its PLYLoader and OrbitControls, the page's script (web/view3d.js) and the cloud;
// the PLY is copied beside it. The page reports window.omma3d = {ready, points, bounds, ...}.
#include "apps/view3d.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <stdexcept>

#include <fmt/format.h>

#include "apps/command.h"
#include "omma/core/io.h"
#include "omma/io/metadata.h"
#include "omma/io/point_cloud.h"
#include "omma/live/web_assets.h"

namespace omma::app {
namespace {
namespace fs = std::filesystem;

struct View3dArgs {
  std::string cloud, out, title;
  long long max_points = 2000000;
  double point_size = 2;
  bool json = false;
};

std::string_view asset(const char* path) {
  const live::WebAsset* a = live::find_web_asset(path);
  if (!a)
    throw std::runtime_error(
        fmt::format("omma was built without the 3D viewer's file {} (web/node_modules/three was missing at "
                    "build time: run "
                    "scripts/install-deps.sh, which runs npm ci in web/, and rebuild)",
                    path));
  return a->data;
}

// Text safe inside HTML elements and attributes, and free of the template's @@ markers.
std::string html_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '@':
        out += "&#64;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// The template with every @@NAME@@ replaced by values.at(NAME), in one pass (what is inserted is not
// searched again). Throws std::logic_error for a marker without a value.
std::string expand(std::string_view tpl, const std::map<std::string, std::string>& values) {
  std::string out;
  size_t at = 0;
  for (;;) {
    const size_t open = tpl.find("@@", at);
    if (open == std::string_view::npos) break;
    const size_t close = tpl.find("@@", open + 2);
    if (close == std::string_view::npos) break;
    const std::string name(tpl.substr(open + 2, close - open - 2));
    const auto it = values.find(name);
    if (it == values.end()) throw std::logic_error("view3d.html: no value for @@" + name + "@@");
    out.append(tpl.substr(at, open - at));
    out += it->second;
    at = close + 2;
  }
  out.append(tpl.substr(at));
  return out;
}

}  // namespace

View3dPage write_view3d_page(const fs::path& in, const fs::path& dir, long long max_points, double point_size,
                             const std::string& title_in) {
  if (max_points < 1)
    throw std::invalid_argument(fmt::format("--max-points must be >= 1, got {}", max_points));
  if (!(point_size > 0 && point_size <= 64))
    throw std::invalid_argument(fmt::format("--point-size must be in (0, 64] pixels, got {}", point_size));
  const std::vector<uint8_t> raw = read_file(in, kMaxDataFileBytes, "point cloud");
  std::string bytes(raw.begin(), raw.end());
  const io::PointCloud cloud = io::parse_ply(bytes, "point cloud " + in.string());  // checks it
  // Every stride-th point when the file has more than --max-points (the page holds them all in memory).
  const long long n = static_cast<long long>(cloud.size());
  const long long stride = n > max_points ? (n + max_points - 1) / max_points : 1;
  long long shown = n;
  if (stride > 1) {
    io::PointCloud sub;
    sub.comments = cloud.comments;
    for (size_t i = 0; i < cloud.size(); i += size_t(stride)) {
      sub.xyz.push_back(cloud.xyz[i]);
      sub.rgb.push_back(cloud.rgb[i]);
    }
    shown = static_cast<long long>(sub.size());
    bytes = io::encode_ply(sub);
  }
  const std::string title = title_in.empty() ? in.filename().string() : title_in;
  nlohmann::json options = {
      {"pointSize", point_size}, {"pointsInFile", n}, {"stride", stride}, {"title", title}};
  std::string options_js = options.dump();
  // Inside a <script>: no "</script" and no template marker can appear in the JSON.
  for (const auto& [from, to] : {std::pair<std::string, std::string>{"<", "\\u003c"}, {"@", "\\u0040"}}) {
    for (size_t at = 0; (at = options_js.find(from, at)) != std::string::npos; at += to.size())
      options_js.replace(at, from.size(), to);
  }
  auto b64 = [](std::string_view s) { return io::base64_encode(s); };
  const std::string page =
      expand(asset("/view3d/view3d.html"), {{"TITLE", html_escape(title)},
                                            {"OPTIONS", options_js},
                                            {"THREE_CORE", b64(asset("/view3d/three.core.js"))},
                                            {"THREE_MODULE", b64(asset("/view3d/three.module.js"))},
                                            {"PLY_LOADER", b64(asset("/view3d/PLYLoader.js"))},
                                            {"ORBIT_CONTROLS", b64(asset("/view3d/OrbitControls.js"))},
                                            {"VIEW3D_JS", b64(asset("/view3d/view3d.js"))},
                                            {"CLOUD", b64(bytes)}});
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (!fs::is_directory(dir)) throw IoError("cannot create the folder '" + dir.string() + "'");
  View3dPage r;
  r.index = dir / "index.html";
  write_text_atomically(r.index, page);
  r.ply = dir / in.filename();
  if (!fs::exists(r.ply) || !fs::equivalent(r.ply, in))
    write_text_atomically(r.ply, std::string(raw.begin(), raw.end()));
  r.points = shown;
  r.points_in_file = n;
  r.stride = stride;
  r.page_bytes = page.size();
  return r;
}

namespace {

void run_view3d(const View3dArgs& a) {
  set_json_mode(a.json);
  const View3dPage p = write_view3d_page(a.cloud, a.out, a.max_points, a.point_size, a.title);
  if (a.json) {
    print_json({{"page", p.index.string()},
                {"ply", p.ply.string()},
                {"points", p.points},
                {"points_in_file", p.points_in_file},
                {"stride", p.stride},
                {"page_bytes", p.page_bytes}});
  } else {
    std::cout << fmt::format(
        "{}: {} points{} (open it in a browser; no network needed)\n", p.index.string(), p.points,
        p.stride > 1 ? fmt::format(", one in {} of {}", p.stride, p.points_in_file) : "");
  }
}

}  // namespace

void add_view3d_command(CLI::App& root) {
  static View3dArgs a;
  auto* cmd = root.add_subcommand(
      "view3d",
      "Write a page that shows a point cloud (PLY, e.g. from `omma stitch --depth estimate --ply`) in 3D:\n"
      "drag to turn, wheel to zoom, right-drag to pan. DIR/index.html holds everything (three.js, the\n"
      "cloud) and opens from file:// with no network; the PLY is copied beside it.");
  cmd->add_option("CLOUD", a.cloud, "Point cloud: PLY with float x, y, z and uchar red, green, blue")
      ->required();
  cmd->add_option("--out", a.out, "Output folder (created): index.html and the PLY")->required();
  cmd->add_option("--max-points", a.max_points,
                  "Show at most N points (every k-th of a larger cloud; the page holds them all)")
      ->capture_default_str();
  cmd->add_option("--point-size", a.point_size, "Point size on screen, pixels")->capture_default_str();
  cmd->add_option("--title", a.title, "The page's title [default: the PLY's file name]");
  cmd->add_flag("--json", a.json,
                "Print one JSON object {page, ply, points, points_in_file, stride, page_bytes} on stdout");
  cmd->callback([] { run_view3d(a); });
}

}  // namespace omma::app
