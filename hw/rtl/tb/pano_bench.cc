// The whole 1080 x 1080 panorama through the Verilated pipeline (docs/results/rtl_bench.sh): frames of
// the simulated colon or a far-field photograph into the frame memories, the configuration over
// the Table 6.6 channels, one panorama run, every pixel compared with the bit-accurate model.
// Prints one JSON object: simulated cycles (and per pixel, against the model's throughput count),
// the wall time of the simulation and of the model, the differing pixels.
//
//   omma_rtl_pano_bench [--scene colon|louvre] [--projection vr180|equirect] [--size WxH]
//                       [--method nn|linear] [--boundary]
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <iostream>
#include <string>

#include "pano_chip.h"

int main(int argc, char** argv) {
  using namespace omma;
  using namespace omma::hw;
  using namespace omma::hw::rtl;
  std::string scene = "colon", method = "linear";
  PanoGrid grid{Projection::kVr180, 1080, 1080};
  bool boundary = false;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      auto next = [&]() -> std::string {
        if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
        return argv[++i];
      };
      if (a == "--scene")
        scene = next();
      else if (a == "--method")
        method = next();
      else if (a == "--projection")
        grid.projection = parse_projection(next());
      else if (a == "--size") {
        const std::string s = next();
        if (std::sscanf(s.c_str(), "%dx%d", &grid.width, &grid.height) != 2)
          throw std::invalid_argument("--size WxH");
      } else if (a == "--boundary")
        boundary = true;
      else if (a == "--help") {
        std::cout << "omma_rtl_pano_bench [--scene colon|louvre] [--projection vr180|equirect] [--size WxH] "
                     "[--method nn|linear] [--boundary]\n";
        return 0;
      } else
        throw std::invalid_argument("unknown option " + a);
    }
    if (scene != "colon" && scene != "louvre") throw std::invalid_argument("--scene colon|louvre");
    const pano::Method m = pano::parse_method(method);
    using clk = std::chrono::steady_clock;
    auto secs = [](clk::time_point a) { return std::chrono::duration<double>(clk::now() - a).count(); };
    std::cerr << "frames (" << scene << ")...\n";
    const auto& frames = scene == "colon" ? colon_frames() : louvre_frames();
    const HwConfig cfg;
    Pipeline model(cfg, rig24(), grid);
    model.load_frames(frames);
    auto t = clk::now();
    const PipelineSummary ref = model.render(m, boundary);
    const double model_s = secs(t);
    std::cerr << "RTL: load, configure, run " << grid.width << "x" << grid.height << "...\n";
    Chip chip;
    t = clk::now();
    chip.load(frames);
    chip.configure(exported_streams(rig24(), ExportOptions{cfg, grid, m, boundary, {}}));
    const double load_s = secs(t);
    t = clk::now();
    const std::clock_t c0 = std::clock();
    const Chip::Run run = chip.run(grid.width, grid.height);
    const double run_s = secs(t), run_cpu = double(std::clock() - c0) / CLOCKS_PER_SEC;
    const double px = double(grid.width) * grid.height;
    const int diff = differing_pixels(run.pano, ref.pano);
    std::printf(
        "{\"scene\": \"%s\", \"projection\": \"%s\", \"width\": %d, \"height\": %d, \"method\": \"%s\", "
        "\"boundary\": %s, \"pixels_out\": %llu, \"differing_pixels\": %d, \"cycles\": %llu, "
        "\"cycles_per_pixel\": %.4f, \"model_cycles\": %llu, \"model_cycles_per_pixel\": %.4f, "
        "\"fps_at_120MHz\": %.2f, \"sim_run_seconds\": %.2f, \"sim_run_cpu_seconds\": %.2f, "
        "\"sim_load_seconds\": %.2f, "
        "\"sim_cycles_per_second\": %.0f, \"model_seconds\": %.3f, \"config_error\": %s}\n",
        scene.c_str(), to_string(grid.projection).c_str(), grid.width, grid.height, method.c_str(),
        boundary ? "true" : "false", (unsigned long long)run.pixels, diff, (unsigned long long)run.cycles,
        run.cycles / px, (unsigned long long)ref.stats.cycles, ref.stats.cycles / px, 120e6 / run.cycles,
        run_s, run_cpu, load_s, run.cycles / run_s, model_s, chip.top().cfg_err ? "true" : "false");
    return diff == 0 && run.pixels == uint64_t(px) ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "omma_rtl_pano_bench: error: " << e.what() << "\n";
    return 1;
  }
}
