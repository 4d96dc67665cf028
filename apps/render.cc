// omma render: large panoramas (Giga-Eye, 21.6 / 82.3 MP) from a frames folder or a recording.
#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>

#include "apps/command.h"
#include "omma/core/frames.h"
#include "omma/core/io.h"
#include "omma/core/log.h"
#include "omma/core/progress.h"
#include "omma/design/prototype.h"
#include "omma/engine/pano_render.h"
#include "omma/engine/tiff_writer.h"
#include "omma/pano/quality.h"

namespace omma::app {
namespace {
namespace fs = std::filesystem;

struct RenderArgs {
  std::string input, rig, size = "9000x2400", projection = "equirect-100", method = "mrf", out, sets, truth;
  std::string demosaic = "hybrid", awb = "grayworld";
  int band_rows = 256, repeat = 1, bits = 12;
  bool no_cache = false, stream_maps = false, json = false, raw = false;
};

// "pano_{set}.tif" -> "pano_00012.tif"; a name without {set} gets "_00012" before the extension
// when several sets are rendered.
fs::path set_path(const std::string& pattern, int64_t set, bool many) {
  const std::string key = "{set}";
  const auto at = pattern.find(key);
  if (at != std::string::npos)
    return pattern.substr(0, at) + fmt::format("{:05d}", set) + pattern.substr(at + key.size());
  if (!many) return pattern;
  fs::path p = pattern;
  return p.replace_filename(p.stem().string() + fmt::format("_{:05d}", set) + p.extension().string());
}

void run_render(const RenderArgs& a) {
  set_json_mode(a.json);
  using clock = std::chrono::steady_clock;
  const auto t_start = clock::now();
  if (a.out.empty()) throw std::invalid_argument("--out is required");
  const Size2 size = parse_size(a.size);
  if (a.band_rows < 1) throw std::invalid_argument("--band-rows must be >= 1");
  if (a.repeat < 1 || a.repeat > 10000) throw std::invalid_argument("--repeat must be 1..10000");
  engine::PanoRenderOptions o;
  o.grid = PanoGrid{parse_projection(a.projection), size.width, size.height};
  if (a.method == "hq") {
    o.offline = true;
    o.method = pano::Method::kLinear;
  } else {
    o.method = pano::parse_method(a.method);
  }
  o.band_rows = a.band_rows;
  o.resident_maps = !a.stream_maps;
  if (a.no_cache) o.cache_dir.clear();
  o.progress = !a.json;
  isp::IspOptions iso;
  iso.demosaic = isp::parse_demosaic(a.demosaic);
  iso.awb = isp::parse_awb(a.awb);
  iso.srgb = true;
  iso.bits = a.bits;  // a recording's own bit depth replaces it (render_frame_set)
  const bool recording = fs::exists(fs::path(a.input) / "manifest.json");
  if (!recording && !fs::is_directory(a.input))
    throw IoError("input '" + a.input + "' is neither a recording nor a frames folder");
  std::unique_ptr<engine::RecordingReader> rec;
  Rig rig;
  if (recording) {
    rec = std::make_unique<engine::RecordingReader>(a.input);
    rig = a.rig.empty() ? rec->manifest().rig : design::load_rig_or_builtin(a.rig);
    if (rig.cameras.size() != rec->manifest().rig.cameras.size())
      throw std::invalid_argument(fmt::format("--rig has {} cameras, the recording {}", rig.cameras.size(),
                                              rec->manifest().rig.cameras.size()));
    for (size_t c = 0; c < rig.cameras.size(); ++c)
      if (rig.cameras[c].in.width != rec->manifest().rig.cameras[c].in.width ||
          rig.cameras[c].in.height != rec->manifest().rig.cameras[c].in.height)
        throw std::invalid_argument(fmt::format("--rig camera {} is {}x{}, the recording's {}x{} (another sensor mode)",
                                                rig.cameras[c].id, rig.cameras[c].in.width, rig.cameras[c].in.height,
                                                rec->manifest().rig.cameras[c].in.width,
                                                rec->manifest().rig.cameras[c].in.height));
  } else {
    const fs::path rig_path = a.rig.empty() ? fs::path(a.input) / "rig.json" : fs::path(a.rig);
    rig = a.rig.empty() ? load_rig(rig_path) : design::load_rig_or_builtin(a.rig);
  }
  // Which frame sets.
  int64_t first = 0, last = recording ? rec->frame_sets() - 1 : 0;
  if (!a.sets.empty()) {
    const auto colon = a.sets.find(':');
    try {
      first = std::stoll(a.sets.substr(0, colon));
      last = colon == std::string::npos ? first : std::stoll(a.sets.substr(colon + 1)) - 1;
    } catch (const std::exception&) {
      throw std::invalid_argument("--sets must be I or A:B (frame sets A..B-1)");
    }
  }
  if (!recording && (first != 0 || last != 0)) throw std::invalid_argument("--sets needs a recording");
  if (recording && (first < 0 || last < first || last >= rec->frame_sets()))
    throw std::invalid_argument(fmt::format("--sets {} outside the recording's {} frame sets", a.sets, rec->frame_sets()));
  cv::Mat truth;
  if (!a.truth.empty()) {
    truth = read_image(a.truth, cv::IMREAD_COLOR);
    if (truth.cols != size.width || truth.rows != size.height)
      throw std::invalid_argument(fmt::format("--truth is {}x{}, the panorama {}x{}", truth.cols, truth.rows, size.width,
                                              size.height));
  }
  std::vector<cv::Mat> frames;
  if (!recording) frames = a.raw ? isp::develop_all(load_raw_frames(a.input, rig), iso) : load_frames(a.input, rig);
  engine::PanoRenderer renderer(rig, o);
  const auto mem = renderer.memory();
  const bool many = last > first;
  double render_s = 0, develop_s = 0, read_s = 0;
  int64_t rendered = 0;
  fs::path last_out;
  Progress progress("render", size_t((last - first + 1) * a.repeat), !a.json && (many || a.repeat > 1));
  for (int64_t s = first; s <= last; ++s)
    for (int r = 0; r < a.repeat; ++r) {
      last_out = set_path(a.out, s, many);
      if (recording) {
        const auto t = engine::render_frame_set(*rec, s, renderer, iso, last_out);
        render_s += t.render;
        develop_s += t.develop;
        read_s += t.read;
      } else {
        if (r == 0 && s == first) renderer.set_frames(frames);
        render_s += engine::render_to_file(renderer, last_out);
      }
      ++rendered;
      progress.step();
    }
  progress.finish();
  nlohmann::json q = nullptr;
  if (!truth.empty()) {
    const std::string ext = last_out.extension().string();
    const cv::Mat pano = (ext == ".tif" || ext == ".tiff") ? engine::read_tiff_rows(last_out) : read_image(last_out, cv::IMREAD_COLOR);
    q = {{"psnr_db", pano::psnr_db(pano, truth)}, {"ssim", pano::ssim(pano, truth)}};
  }
  const double total = std::chrono::duration<double>(clock::now() - t_start).count();
  const double per = render_s / rendered;
  if (a.json) {
    print_json({{"input", a.input},
                {"recording", recording},
                {"out", last_out.string()},
                {"panoramas", rendered},
                {"width", size.width},
                {"height", size.height},
                {"megapixels", size.width * double(size.height) / 1e6},
                {"method", a.method},
                {"bands", renderer.bands()},
                {"maps_seconds", renderer.maps_seconds()},
                {"maps_from_cache", renderer.maps_from_cache()},
                {"render_seconds_per_panorama", per},
                {"panoramas_per_s", per > 0 ? 1 / per : 0},
                {"develop_seconds", develop_s},
                {"read_seconds", read_s},
                {"memory",
                 {{"store_bytes", mem.store_bytes},
                  {"maps_bytes", mem.maps_bytes},
                  {"band_bytes", mem.band_bytes},
                  {"total_bytes", mem.total()}}},
                {"quality", q},
                {"seconds", total}});
  } else {
    std::cout << fmt::format(
        "{}: {} panorama(s) {}x{} ({:.1f} MP, {}) from {}; maps {:.2f} s ({} of {} bands from the cache); render "
        "{:.3f} s per panorama ({:.2f}/s); memory {:.0f} MB (store {:.0f}, maps {:.0f}, band {:.0f})\n",
        last_out.string(), rendered, size.width, size.height, size.width * double(size.height) / 1e6, a.method,
        a.input, renderer.maps_seconds(), renderer.maps_from_cache(), renderer.bands(), per, per > 0 ? 1 / per : 0,
        mem.total() / 1e6, mem.store_bytes / 1e6, mem.maps_bytes / 1e6, mem.band_bytes / 1e6);
    if (!q.is_null())
      std::cout << fmt::format("  against {}: PSNR {:.2f} dB, SSIM {:.4f}\n", a.truth, q["psnr_db"].get<double>(),
                               q["ssim"].get<double>());
  }
}

}  // namespace

void add_render_command(CLI::App& root) {
  static RenderArgs a;
  auto* cmd = root.add_subcommand(
      "render",
      "Render large panoramas (Giga-Eye: 9000x2400 = 21.6 MP, 17700x4650 = 82.3 MP over 360x100 deg) from a\n"
      "frames folder (cam_XX.png, rig.json) or a recording (omma record: raw frame sets, developed by the ISP),\n"
      "band by band from cached maps. .tif/.tiff outputs are BigTIFF (any size, memory = one band); other\n"
      "formats hold the whole image. Methods: the engine's, or hq (offline: every tap in double precision).");
  cmd->add_option("INPUT", a.input, "Frames folder or recording folder")->required();
  cmd->add_option("--rig", a.rig, "Rig file or built-in rig (default: INPUT/rig.json or the recording's rig)");
  cmd->add_option("--out", a.out, "Output image; with several frame sets a pattern with {set}, e.g. pano_{set}.tif")
      ->required();
  cmd->add_option("--size", a.size, "Panorama size WxH")->capture_default_str();
  cmd->add_option("--projection", a.projection, "equirect-100 | equirect | equirect-full | vr180")->capture_default_str();
  cmd->add_option("--method", a.method, "nn | linear | gaussian | mrf | mrf-spherical | sad | hq")->capture_default_str();
  cmd->add_option("--sets", a.sets, "Frame sets of a recording: I or A:B (A..B-1); default: all");
  cmd->add_option("--band-rows", a.band_rows, "Rows per band map")->capture_default_str();
  cmd->add_flag("--stream-maps", a.stream_maps, "Keep one band map in memory at a time (loaded from the cache)");
  cmd->add_flag("--no-cache", a.no_cache, "Do not read or write the map cache");
  cmd->add_flag("--raw", a.raw, "Frames folder: develop cam_XX_raw.png with the ISP instead of cam_XX.png");
  cmd->add_option("--bits", a.bits, "Bit depth of the raw frames of a frames folder (--raw)")->capture_default_str();
  cmd->add_option("--demosaic", a.demosaic, "ISP demosaicing of raw frames")->capture_default_str();
  cmd->add_option("--awb", a.awb, "ISP white balance of raw frames")->capture_default_str();
  cmd->add_option("--truth", a.truth, "Ground-truth panorama of the same size: report PSNR and SSIM");
  cmd->add_option("--repeat", a.repeat, "Render each frame set N times (speed measurement)")->capture_default_str();
  cmd->add_flag("--json", a.json, "Print one JSON summary on stdout");
  cmd->callback([] { run_render(a); });
}

}  // namespace omma::app
