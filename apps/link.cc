// omma link: the camera's serial link (thesis §5.1.3). `encode` turns a raw frame into the bit stream
// the camera sends (optionally impaired by bit flips and lost samples); `decode` rebuilds the frames,
// resynchronising after damage, and reports intact and damaged rows.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <stdexcept>
#include <string>

#include "apps/command.h"
#include "omma/core/io.h"
#include "omma/core/log.h"
#include "omma/isp/isp.h"

namespace omma::app {

namespace {

struct LinkArgs {
  std::string in, out;
  isp::LinkConfig cfg;
  int repeat = 1;
  double flip_rate = 0, drop_rate = 0;
  uint64_t seed = 1;
  bool no_conceal = false;
  bool json = false;
};

void add_config_options(CLI::App* cmd, isp::LinkConfig& c) {
  cmd->add_option("--width", c.width, "Pixels per row")->capture_default_str();
  cmd->add_option("--height", c.height, "Rows per frame")->capture_default_str();
  cmd->add_option("--bits", c.bits, "Bits per pixel (ADC resolution)")->capture_default_str();
  cmd->add_option("--row-gap-pp", c.row_gap_pp, "Zeros before each row, pixel periods (PP)")
      ->capture_default_str();
  cmd->add_option("--eof-pp", c.eof_pp, "End-of-frame marker, PP")->capture_default_str();
  cmd->add_option("--config-pp", c.config_pp, "Configuration window, PP")->capture_default_str();
  cmd->add_option("--resync-pp", c.resync_pp, "Resynchronisation pattern, PP")->capture_default_str();
}

void run_encode(const LinkArgs& a) {
  set_json_mode(a.json);
  a.cfg.validate();
  if (a.repeat < 1) throw std::invalid_argument("--frames must be at least 1");
  if (a.flip_rate < 0 || a.flip_rate > 1 || a.drop_rate < 0 || a.drop_rate > 1)
    throw std::invalid_argument("--flip-rate and --drop-rate must be in [0, 1]");
  const cv::Mat raw = read_image(a.in);
  if (raw.channels() != 1 || raw.depth() != CV_16U)
    throw std::invalid_argument("'" + a.in +
                                "' is not a raw frame: expected a 16-bit single-channel PNG "
                                "with " +
                                std::to_string(a.cfg.bits) + "-bit values");
  if (raw.cols != a.cfg.width || raw.rows != a.cfg.height)
    throw std::invalid_argument("'" + a.in + "' is " + std::to_string(raw.cols) + "x" +
                                std::to_string(raw.rows) + " but the link carries " +
                                std::to_string(a.cfg.width) + "x" + std::to_string(a.cfg.height) +
                                " (set --width/--height)");
  const isp::LinkFrame f = isp::to_link_frame(raw, a.cfg.bits);
  isp::ChipStream s = isp::encode_link(std::vector<isp::LinkFrame>(size_t(a.repeat), f), a.cfg);
  if (a.flip_rate > 0 || a.drop_rate > 0) s = isp::impair_link(s, a.flip_rate, a.drop_rate, a.seed);
  write_atomically(a.out, [&](const std::filesystem::path& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    out.write(reinterpret_cast<const char*>(s.bytes.data()), std::streamsize(s.bytes.size()));
    out.close();
    if (!out) throw IoError("cannot write '" + a.out + "'");
  });
  if (a.json)
    print_json({{"frames", a.repeat}, {"bytes", s.bytes.size()}, {"chips", s.chips}});
  else
    spdlog::info("link: {} frame(s) -> {} ({} bytes)", a.repeat, a.out, s.bytes.size());
}

void run_decode(const LinkArgs& a) {
  set_json_mode(a.json);
  a.cfg.validate();
  namespace fs = std::filesystem;
  const std::vector<uint8_t> bytes = read_file(a.in, kMaxDataFileBytes, "link file");
  if (bytes.empty()) throw std::invalid_argument("link file '" + a.in + "' is empty");
  const fs::path prefix(a.out);
  if (prefix.has_parent_path() && !fs::is_directory(prefix.parent_path()))
    throw IoError("output folder '" + prefix.parent_path().string() + "' does not exist");
  int index = 0;
  const isp::LinkSummary st = isp::decode_link(bytes, a.cfg, [&](const isp::LinkFrame& frame) {
    isp::LinkFrame f = frame;
    if (!a.no_conceal) isp::conceal_damaged_rows(f);
    char name[32];
    std::snprintf(name, sizeof name, "_%03d.png", index++);
    write_image(a.out + name, isp::to_mat(f));
  });
  if (st.frames == 0)
    throw std::runtime_error("no frame found in '" + a.in + "' (" + std::to_string(bytes.size()) +
                             " bytes): not a " + std::to_string(a.cfg.width) + "x" +
                             std::to_string(a.cfg.height) + " link stream, or damaged beyond recovery");
  if (a.json)
    print_json({{"frames", st.frames},
                {"rows_ok", st.rows_ok},
                {"rows_damaged", st.rows_damaged},
                {"bytes", st.bytes}});
  else
    std::printf("frames %d, rows ok %ld, rows damaged %ld, bytes %zu\n", st.frames, st.rows_ok,
                st.rows_damaged, st.bytes);
}

}  // namespace

void add_link_command(CLI::App& root) {
  auto* cmd = root.add_subcommand(
      "link",
      "The camera's serial link (thesis §5.1.3): per row 3 PP of zeros, then 250 pixels of 10 bits\n"
      "framed by a start (1) and a stop (0) bit, each bit XORed with the clock; end-of-frame (4 PP\n"
      "of constant 0), configuration window (505 PP), resynchronisation (250 PP). 1 PP = 12 clocks.\n"
      "Files hold one line sample per half clock, 8 per byte, first sample in the MSB.");
  cmd->require_subcommand(1);

  auto enc = std::make_shared<LinkArgs>();
  auto* e = cmd->add_subcommand("encode", "Raw frame (16-bit single-channel PNG) -> link bit stream file");
  e->add_option("IN", enc->in, "Raw frame PNG")->required();
  e->add_option("OUT", enc->out, "Bit stream file (.bin, written atomically)")->required();
  add_config_options(e, enc->cfg);
  e->add_option("--frames", enc->repeat, "Send the frame this many times (1..100000)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  e->add_option("--flip-rate", enc->flip_rate, "Probability of flipping each line sample (channel errors)")
      ->capture_default_str();
  e->add_option("--drop-rate", enc->drop_rate, "Probability of losing each line sample")
      ->capture_default_str();
  e->add_option("--seed", enc->seed, "Seed for the impairments")->capture_default_str();
  e->add_flag("--json", enc->json, "Print one JSON object on stdout");
  e->callback([enc] { run_encode(*enc); });

  auto dec = std::make_shared<LinkArgs>();
  auto* d = cmd->add_subcommand("decode", "Link bit stream file -> frames OUT_PREFIX_000.png, ... (16-bit)");
  d->add_option("IN", dec->in, "Bit stream file")->required();
  d->add_option("OUT_PREFIX", dec->out, "Output prefix; frames are written as OUT_PREFIX_NNN.png")
      ->required();
  add_config_options(d, dec->cfg);
  d->add_flag("--no-conceal", dec->no_conceal,
              "Leave damaged rows black instead of copying the nearest intact row of the same colour");
  d->add_flag("--json", dec->json,
              "Print {\"frames\", \"rows_ok\", \"rows_damaged\", \"bytes\"} as one JSON object on stdout");
  d->callback([dec] { run_decode(*dec); });
}

}  // namespace omma::app
