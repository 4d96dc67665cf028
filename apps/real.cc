// omma real: omma measured on real photographs with ground truth, beside OpenCV, COLMAP and Hugin
// (bench/real.h). scripts/real_images.sh runs every case into docs/results/real_images.md.
#include "omma/bench/real.h"

#include <iostream>
#include <stdexcept>

#include <fmt/format.h>

#include "apps/command.h"
#include "omma/testing/real_data.h"

namespace omma::app {

namespace {
struct RealArgs {
  std::string data, out;
  bool no_peers = false, quick = false, json = false;
  int threads = 2;
};

// Prints the object's numbers as "key: value" lines, nested objects indented.
void print_tree(const nlohmann::json& j, int indent) {
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string pad(indent, ' ');
    if (it->is_object()) {
      std::cout << pad << it.key() << ":\n";
      print_tree(*it, indent + 2);
    } else if (it->is_number_float()) {
      std::cout << fmt::format("{}{}: {:.4g}\n", pad, it.key(), it->get<double>());
    } else {
      std::cout << pad << it.key() << ": " << (it->is_string() ? it->get<std::string>() : it->dump()) << "\n";
    }
  }
}

bench::RealOptions options(const RealArgs& a) {
  bench::RealOptions o;
  o.data_dir = a.data.empty() ? testing::opencv_samples_dir() : std::filesystem::path(a.data);
  if (o.data_dir.empty())
    throw std::runtime_error(
        "OpenCV's sample images are not installed: apt-get install opencv-doc (or give --data DIR, or set "
        "OMMA_OPENCV_SAMPLES)");
  o.out_dir = a.out;
  o.peers = !a.no_peers;
  o.quick = a.quick;
  o.threads = a.threads;
  return o;
}

void report(const RealArgs& a, const nlohmann::json& r) {
  if (a.json)
    print_json(r);
  else
    print_tree(r, 0);
}
}  // namespace

void add_real_command(CLI::App& root) {
  static RealArgs a;
  auto* cmd = root.add_subcommand(
      "real",
      "Measure omma on real photographs with ground truth that no simulator made (OpenCV's samples,\n"
      "Debian package opencv-doc), beside the peers a user would otherwise pick, in the same run:\n"
      "  stereo-calib   calibrate the real stereo pair from natural features (start: focal 3 % off, pose\n"
      "                 5 deg off) against cv::stereoCalibrate on its chessboard; COLMAP's mapper beside it\n"
      "  depth          the depth sweep on the Middlebury Aloe pair against its true disparity; StereoSGBM\n"
      "  stitch PAIR    calibrate and stitch leuven, aero or graf; OpenCV's Stitcher and Hugin beside it\n"
      "scripts/real_images.sh runs them all into docs/results/real_images.md.");
  cmd->require_subcommand(1);
  auto common = [](CLI::App* c) {
    c->add_option("--data", a.data,
                  "Folder of OpenCV's samples [default: /usr/share/doc/opencv-doc/examples/data]");
    c->add_option("--out", a.out, "Write the pictures (and intermediate files) into this folder");
    c->add_flag("--no-peers", a.no_peers, "Do not run the peers (OpenCV, COLMAP, Hugin)");
    c->add_flag("--quick", a.quick, "The smaller variant that a CI test runs");
    c->add_option("--threads", a.threads, "Threads (default 2)")->check(CLI::Range(1, 256));
    c->add_flag("--json", a.json, "Print one JSON object on stdout");
  };
  auto* stereo = cmd->add_subcommand("stereo-calib", "Calibrate the real stereo rig from natural features");
  common(stereo);
  stereo->callback([] {
    set_json_mode(a.json);
    report(a, bench::real_stereo_calibration(options(a)));
  });
  auto* depth = cmd->add_subcommand("depth", "Depth of the Middlebury Aloe pair against its true disparity");
  common(depth);
  depth->callback([] {
    set_json_mode(a.json);
    report(a, bench::real_depth(options(a)));
  });
  static std::string pair;
  auto* stitch = cmd->add_subcommand("stitch", "Calibrate and stitch a real pair: leuven, aero or graf");
  stitch->add_option("PAIR", pair, "leuven, aero or graf")
      ->required()
      ->check(CLI::IsMember(bench::real_stitch_pairs()));
  common(stitch);
  stitch->callback([] {
    set_json_mode(a.json);
    report(a, bench::real_stitch(pair, options(a)));
  });
}

}  // namespace omma::app
