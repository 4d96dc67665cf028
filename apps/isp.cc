// omma isp: develop a raw RGGB Bayer frame (vignetting, demosaicing, white balance), or evaluate the
// demosaicing methods on a photograph (thesis §5.1.2, appendix A, Table A.1).
#include "omma/isp/isp.h"

#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

#include "apps/command.h"
#include "omma/core/io.h"
#include "omma/core/log.h"

namespace omma::app {

namespace {

struct IspArgs {
  std::string in, out, flat, eval;
  std::string demosaic = "hybrid", awb = "grayworld";
  int bits = 10;
  int border = 8;
  bool rgb565 = false;
  bool srgb = false;
  bool json = false;
};

nlohmann::json psnr_json(const isp::ChannelPsnr& p) {
  auto r2 = [](double v) { return std::round(v * 100.0) / 100.0; };
  return {{"r", r2(p.r)}, {"g", r2(p.g)}, {"b", r2(p.b)}};
}

void run_isp(const IspArgs& a) {
  set_json_mode(a.json);
  if (!a.eval.empty()) {
    if (!a.in.empty() || !a.out.empty()) throw std::invalid_argument("--eval takes no --in or --out");
    const cv::Mat photo = read_image(a.eval, 1 /*cv::IMREAD_COLOR*/);
    const auto res = isp::evaluate_demosaic(photo, a.border);
    nlohmann::json methods = nlohmann::json::object();
    for (const char* k : {"bilinear", "hybrid", "ah", "cc", "opencv_bilinear", "opencv_ea"})
      methods[k] = psnr_json(res.at(k));
    const nlohmann::json j = {{"image", a.eval}, {"methods", methods}};
    if (a.json) {
      print_json(j);
    } else {
      std::printf("%-16s %8s %8s %8s   (PSNR dB, %d-pixel border left out)\n", "method", "R", "G", "B",
                  a.border);
      for (const auto& [k, v] : methods.items())
        std::printf("%-16s %8.2f %8.2f %8.2f\n", k.c_str(), v["r"].get<double>(), v["g"].get<double>(),
                    v["b"].get<double>());
    }
    return;
  }
  if (a.in.empty() || a.out.empty())
    throw std::invalid_argument("give --in RAW and --out RGB, or --eval PHOTO");
  isp::IspOptions o;
  o.demosaic = isp::parse_demosaic(a.demosaic);
  o.awb = isp::parse_awb(a.awb);
  o.bits = a.bits;
  o.srgb = a.srgb;
  const cv::Mat raw = read_image(a.in);
  if (raw.channels() != 1 || raw.depth() != CV_16U)
    throw std::invalid_argument("'" + a.in +
                                "' is not a raw Bayer frame: expected a 16-bit single-channel "
                                "PNG with " +
                                std::to_string(a.bits) + "-bit RGGB values, got " +
                                std::to_string(raw.channels()) + " channel(s) of " +
                                (raw.depth() == CV_8U    ? "8"
                                 : raw.depth() == CV_16U ? "16"
                                                         : "other") +
                                " bits");
  if (!a.flat.empty()) o.flat_gain = isp::load_flat_field(a.flat);
  const cv::Mat rgb = isp::develop(raw, o);
  write_image(a.out, a.rgb565 ? isp::pack_rgb565(rgb) : rgb);
  if (a.json)
    print_json({{"in", a.in},
                {"out", a.out},
                {"demosaic", a.demosaic},
                {"awb", a.awb},
                {"width", raw.cols},
                {"height", raw.rows},
                {"rgb565", a.rgb565}});
  else
    spdlog::info("isp: {} -> {} ({}x{}, {}, {})", a.in, a.out, raw.cols, raw.rows, a.demosaic, a.awb);
}

}  // namespace

void add_isp_command(CLI::App& root) {
  auto a = std::make_shared<IspArgs>();
  auto* cmd = root.add_subcommand(
      "isp",
      "Single-camera ISP (thesis §5.1.2, appendix A): develop a raw RGGB Bayer frame ((0,0) = R; 16-bit\n"
      "PNG with 10-bit values) into an 8-bit RGB image: vignetting correction, demosaicing, white\n"
      "balance, 8 MSBs. Or, with --eval, mosaic a photograph and print per-channel PSNR (dB) of each\n"
      "demosaicing method and of OpenCV's bilinear and edge-aware conversions (Table A.1).");
  cmd->add_option("--in", a->in, "Raw Bayer frame (16-bit single-channel PNG, RGGB)");
  cmd->add_option("--out", a->out, "Output image (8-bit BGR; written atomically)");
  cmd->add_option("--demosaic", a->demosaic, "bilinear | hybrid | ah | cc")
      ->check(CLI::IsMember({"bilinear", "hybrid", "ah", "cc"}))
      ->capture_default_str();
  cmd->add_option("--awb", a->awb, "White balance: none | grayworld | whitepatch")
      ->check(CLI::IsMember({"none", "grayworld", "whitepatch"}))
      ->capture_default_str();
  cmd->add_option("--flat", a->flat,
                  "Flat-field raw frame (white target, same size) for vignetting correction");
  cmd->add_option("--bits", a->bits, "Bit depth of the raw values")
      ->check(CLI::Range(8, 16))
      ->capture_default_str();
  cmd->add_flag(
      "--srgb", a->srgb,
      "sRGB-encode the output (for linear raw such as the simulator's) instead of the 8 linear MSBs");
  cmd->add_flag("--rgb565", a->rgb565, "Write the RGB565-packed frame (16-bit single channel, §5.2) instead");
  cmd->add_option("--eval", a->eval, "Photograph to evaluate the demosaicing methods on (instead of --in)");
  cmd->add_option("--border", a->border, "Pixels left out on each side for --eval PSNR")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  cmd->add_flag("--json", a->json, "Print one JSON object on stdout");
  cmd->callback([a] { run_isp(*a); });
}

}  // namespace omma::app
