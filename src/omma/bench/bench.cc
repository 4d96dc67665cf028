#include "omma/bench/bench.h"

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <ctime>
#include <mutex>
#include <stdexcept>
#include <thread>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>
#include <opencv2/stitching/detail/blenders.hpp>
#include <tbb/parallel_for.h>

#include "omma/core/log.h"
#include "omma/core/valid.h"
#include "omma/design/prototype.h"
#include "omma/isp/isp.h"
#include "omma/isp/photometric.h"
#include "omma/render/depth_render.h"
#include "omma/sim/render.h"
#include "omma/testing/synthetic.h"

namespace omma::bench {
namespace {

std::string size_tag(const PanoGrid& g) { return std::to_string(g.width) + "x" + std::to_string(g.height); }

// Per camera: its footprint's bounding box on the panorama and cv::remap maps for it (pixels the
// camera does not see map outside its image, so BORDER_TRANSPARENT leaves them untouched).
struct CameraWarp {
  cv::Rect roi;
  cv::Mat map1, map2;  // fixed point (CV_16SC2 + CV_16UC1)
  cv::Mat mask;        // CV_8U 255 where the camera sees the pixel
};

std::vector<CameraWarp> camera_warps(const Rig& rig, const PanoGrid& g) {
  std::vector<CameraWarp> out(rig.cameras.size());
  tbb::parallel_for(size_t(0), rig.cameras.size(), [&](size_t c) {
    const CameraModel m = rig.cameras[c].model();
    cv::Mat mx(g.height, g.width, CV_32F, cv::Scalar(-10)), my(g.height, g.width, CV_32F, cv::Scalar(-10));
    int x0 = g.width, y0 = g.height, x1 = -1, y1 = -1;
    for (int row = 0; row < g.height; ++row)
      for (int col = 0; col < g.width; ++col) {
        const Vec3 w = g.pixel_direction(col, row);
        if (!m.sees(w)) continue;
        const auto p = m.project(w);
        if (!p || !m.inside(*p)) continue;
        mx.at<float>(row, col) = float(p->x() - 0.5);
        my.at<float>(row, col) = float(p->y() - 0.5);
        x0 = std::min(x0, col), x1 = std::max(x1, col), y0 = std::min(y0, row), y1 = std::max(y1, row);
      }
    CameraWarp& cw = out[c];
    if (x1 < 0) return;
    cw.roi = cv::Rect(x0, y0, x1 - x0 + 1, y1 - y0 + 1);
    cv::convertMaps(mx(cw.roi), my(cw.roi), cw.map1, cw.map2, CV_16SC2);
    cw.mask = (mx(cw.roi) > -5);
  });
  return out;
}

}  // namespace

Workload omma_workload(const Rig& rig, const render::MapOptions& opt, int threads,
                       const std::vector<cv::Mat>& frames, const std::string& variant,
                       const std::string& suffix) {
  const auto t0 = std::chrono::steady_clock::now();
  auto map = std::make_shared<render::CompiledMap>(render::compile_map(rig, opt));
  const double compile_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  auto store = std::make_shared<render::FrameStore>(map->layout);
  for (size_t c = 0; c < frames.size(); ++c) store->set(int(c), frames[c]);
  auto out = std::make_shared<cv::Mat>();
  Workload w;
  w.name = "omma-" + pano::to_string(opt.method) + variant + "-" + size_tag(opt.grid) + suffix;
  w.threads = threads;
  w.run = [map, store, out, threads] { render::render(*map, *store, *out, {.threads = threads}); };
  w.info = {{"bytes_per_pixel", map->bytes_per_pixel()},
            {"taps_per_pixel", double(map->taps()) / (double(map->width) * map->height)},
            {"compile_s", compile_s},
            {"threads", threads},
            {"min_weight", opt.min_weight},
            {"kernel", to_string(render::best_kernel())}};
  return w;
}

Workload omma_depth_workload(const Rig& rig, const render::MapOptions& opt,
                             const std::vector<cv::Mat>& frames) {
  render::DepthRenderOptions o;
  o.map = opt;
  o.map.min_weight = render::kEngineDepthMinWeight;  // as the live engine (engine.cc)
  auto dr = std::make_shared<render::DepthRenderer>(rig, o);
  auto store = std::make_shared<render::FrameStore>(dr->layout());
  for (size_t c = 0; c < frames.size(); ++c) store->set(int(c), frames[c]);
  // The estimate sees a different frame set every panorama (two random sets in turn: no result of
  // one panorama can be reused for the next); the render's cost does not depend on the frames' content.
  auto fr = std::make_shared<std::vector<std::vector<cv::Mat>>>(
      std::vector<std::vector<cv::Mat>>{frames, testing::random_frames(rig, 43)});
  auto out = std::make_shared<cv::Mat>();
  auto n = std::make_shared<size_t>(0);
  Workload w;
  w.name = "omma-" + pano::to_string(opt.method) + "-depth-" + size_tag(opt.grid);
  w.run = [dr, store, fr, out, n] { dr->render(*store, (*fr)[(*n)++ % fr->size()], *out); };
  const PanoGrid& cg = dr->sweep().coarse_grid();
  w.info = {{"bytes_per_pixel", dr->bytes_per_pixel()},
            {"taps_per_pixel", double(dr->taps()) / (double(opt.grid.width) * opt.grid.height)},
            {"compile_s", dr->compile_seconds()},
            {"depth_grid", fmt::format("{}x{}", cg.width, cg.height)},
            {"depth_candidates", dr->sweep().options().steps},
            {"depth_every_frame", true},
            {"depth_frames_change", true},
            {"depth_min_weight", o.map.min_weight}};
  return w;
}

namespace {
// A camera thread of the live engine (engine.cc) for the bench: on each job it makes camera c's
// frame ready (corrected by its photometric table, or copied) while the caller renders.
class CameraWorker {
 public:
  explicit CameraWorker(std::vector<isp::PhotometricTable> tables) : tables_(std::move(tables)) {
    thread_ = std::thread([this] { loop(); });
  }
  ~CameraWorker() {
    {
      std::lock_guard<std::mutex> l(m_);
      quit_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }
  void start(const cv::Mat* frame, size_t c) {
    std::lock_guard<std::mutex> l(m_);
    frame_ = frame, camera_ = c, busy_ = true;
    cv_.notify_all();
  }
  const cv::Mat& wait() {
    std::unique_lock<std::mutex> l(m_);
    cv_.wait(l, [this] { return !busy_; });
    return ready_;
  }

 private:
  void loop() {
    std::unique_lock<std::mutex> l(m_);
    for (;;) {
      cv_.wait(l, [this] { return quit_ || (busy_ && frame_); });
      if (quit_) return;
      l.unlock();
      if (!tables_.empty())
        tables_[camera_].apply(*frame_, ready_);  // the correction ...
      else
        frame_->copyTo(ready_);  // ... or the plain hand-over
      l.lock();
      busy_ = false, frame_ = nullptr;
      cv_.notify_all();
    }
  }
  std::vector<isp::PhotometricTable> tables_;
  std::thread thread_;
  std::mutex m_;
  std::condition_variable cv_;
  const cv::Mat* frame_ = nullptr;
  size_t camera_ = 0;
  bool busy_ = false, quit_ = false;
  cv::Mat ready_;
};
}  // namespace

Workload omma_live_workload(const Rig& rig, const render::MapOptions& opt, const std::vector<cv::Mat>& frames,
                            bool photometric) {
  auto map = std::make_shared<render::CompiledMap>(render::compile_map(rig, opt));
  auto store = std::make_shared<render::FrameStore>(map->layout);
  for (size_t c = 0; c < frames.size(); ++c) store->set(int(c), frames[c]);
  std::vector<isp::PhotometricTable> tables;
  if (photometric) {
    Rig modelled = rig;
    for (RigCamera& c : modelled.cameras) c.photometric = sim::true_photometric(c, sim::CameraEffects{});
    tables = isp::photometric_tables(modelled);
  }
  auto worker = std::make_shared<CameraWorker>(std::move(tables));
  auto fr = std::make_shared<std::vector<cv::Mat>>(frames);
  auto out = std::make_shared<cv::Mat>();
  auto next = std::make_shared<size_t>(0);
  Workload w;
  w.name = "omma-" + pano::to_string(opt.method) + (photometric ? "-photometric-" : "-store-") +
           size_tag(opt.grid);
  w.run = [map, store, worker, fr, out, next] {
    const size_t c = (*next)++ % fr->size();
    worker->start(&(*fr)[c], c);             // the camera thread, concurrently with ...
    render::render(*map, *store, *out, {});  // ... the render loop's panorama
    store->set(int(c), worker->wait());      // then the new frame enters the store
  };
  w.info = {{"bytes_per_pixel", map->bytes_per_pixel()},
            {"camera_frames_per_panorama", 1},
            {"photometric", photometric}};
  return w;
}

Workload opencv_remap_workload(const Rig& rig, const PanoGrid& grid, const std::vector<cv::Mat>& frames) {
  auto warps = std::make_shared<std::vector<CameraWarp>>(camera_warps(rig, grid));
  auto out = std::make_shared<cv::Mat>(grid.height, grid.width, CV_8UC3, cv::Scalar::all(0));
  auto fr = std::make_shared<std::vector<cv::Mat>>(frames);
  Workload w;
  w.name = "opencv-remap-" + size_tag(grid);
  w.run = [warps, out, fr] {
    for (size_t c = 0; c < warps->size(); ++c) {
      const CameraWarp& cw = (*warps)[c];
      if (cw.roi.empty()) continue;
      cv::Mat dst = (*out)(cw.roi);
      cv::remap((*fr)[c], dst, cw.map1, cw.map2, cv::INTER_LINEAR, cv::BORDER_TRANSPARENT);
    }
  };
  w.info = {{"threads", "opencv default"}};
  return w;
}

Workload opencv_multiband_workload(const Rig& rig, const PanoGrid& grid, const std::vector<cv::Mat>& frames) {
  const auto warps = camera_warps(rig, grid);
  auto warped = std::make_shared<std::vector<cv::Mat>>();
  auto masks = std::make_shared<std::vector<cv::Mat>>();
  auto tls = std::make_shared<std::vector<cv::Point>>();
  for (size_t c = 0; c < warps.size(); ++c) {
    if (warps[c].roi.empty()) continue;
    cv::Mat img;
    cv::remap(frames[c], img, warps[c].map1, warps[c].map2, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    cv::Mat s16;
    img.convertTo(s16, CV_16SC3);
    warped->push_back(s16);
    masks->push_back(warps[c].mask.clone());
    tls->push_back(warps[c].roi.tl());
  }
  auto out = std::make_shared<cv::Mat>();
  const cv::Rect dst_roi(0, 0, grid.width, grid.height);
  Workload w;
  w.name = "opencv-multiband-" + size_tag(grid);
  w.run = [warped, masks, tls, out, dst_roi] {
    cv::detail::MultiBandBlender blender(false, 5);
    blender.prepare(dst_roi);
    for (size_t i = 0; i < warped->size(); ++i) blender.feed((*warped)[i], (*masks)[i], (*tls)[i]);
    cv::Mat result, result_mask;
    blender.blend(result, result_mask);
    *out = result;
  };
  w.info = {{"bands", 5}, {"threads", "opencv default"}};
  return w;
}

Workload memcpy_workload(const render::CompiledMap& map, const std::string& tag) {
  const size_t store = map.store_bytes_read();
  const size_t bytes = map.bytes() + store + size_t(map.width) * map.height * 3;
  auto src = std::make_shared<std::vector<uint8_t>>(bytes, 1);
  auto dst = std::make_shared<std::vector<uint8_t>>(bytes, 0);
  Workload w;
  w.name = "memcpy-bound-" + tag;
  w.run = [src, dst] {
    const size_t n = src->size(), chunk = 1 << 20;
    tbb::parallel_for(size_t(0), (n + chunk - 1) / chunk, [&](size_t i) {
      const size_t a = i * chunk, b = std::min(n, a + chunk);
      std::memcpy(dst->data() + a, src->data() + a, b - a);
    });
  };
  w.info = {{"bytes", bytes},
            {"map_bytes", map.bytes()},
            {"store_bytes_read", store},
            {"store_bytes", map.layout.bytes()}};
  return w;
}

namespace {
double process_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + ts.tv_nsec * 1e-9;
}

// One untimed run (the caches to this workload), then runs for at least min_seconds and at least
// min_iterations times.
struct Timing {
  long frames = 0;
  double wall_s = 0, cpu_s = 0;
};
Timing time_workload(const Workload& w, double min_seconds, int min_iterations) {
  w.run();
  Timing t;
  const auto t0 = std::chrono::steady_clock::now();
  const double c0 = process_cpu_seconds();
  while (t.frames < min_iterations || t.wall_s < min_seconds) {
    w.run();
    ++t.frames;
    t.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  t.cpu_s = process_cpu_seconds() - c0;
  return t;
}
}  // namespace

double measure_fps(const Workload& w, double min_seconds, int min_iterations, double* cpu_s_per_frame) {
  const Timing t = time_workload(w, min_seconds, min_iterations);
  if (cpu_s_per_frame) *cpu_s_per_frame = t.cpu_s / t.frames;
  return t.frames / t.wall_s;
}

namespace {
// One raw 10-bit RGGB frame per camera: the random-texture frames mosaiced (x4 to 10 bits).
std::vector<cv::Mat> random_raw_frames(const Rig& rig, uint32_t seed) {
  std::vector<cv::Mat> raws;
  for (const cv::Mat& f : testing::random_frames(rig, seed)) {
    cv::Mat f16;
    f.convertTo(f16, CV_16UC3, 4.0);
    raws.push_back(isp::mosaic_rggb(f16));
  }
  return raws;
}
}  // namespace

bool BenchOptions::IsValid(std::string* why) const {
  if (!(min_seconds > 0) || !std::isfinite(min_seconds))
    return invalid(why, "min_seconds must be a positive number");
  if (rounds < 1) return invalid(why, "rounds must be >= 1");
  return true;
}

std::vector<BenchEntry> run_bench_suite(const Rig& rig_in, const BenchOptions& opt,
                                        std::vector<std::string>* skipped) {
  if (std::string why; !opt.IsValid(&why)) throw std::invalid_argument("bench: " + why);
  const Rig rig = rig_in.cameras.empty() ? design::thesis_prototype_rig() : rig_in;
  const auto frames = testing::random_frames(rig, 42);
  std::vector<PanoGrid> grids = {{Projection::kVr180, 1080, 1080}, {Projection::kEquirect, 1920, 512}};
  if (opt.quick) grids = {{Projection::kVr180, 216, 216}, {Projection::kEquirect, 384, 102}};
  auto wanted = [&](const std::string& name) {
    if (opt.only.empty()) return true;
    for (const auto& s : opt.only)
      if (name.find(s) != std::string::npos) return true;
    return false;
  };
  std::vector<Workload> ws;
  auto add = [&](const Workload& w) {
    if (wanted(w.name)) ws.push_back(w);
  };
  for (const PanoGrid& g : grids) {
    std::shared_ptr<render::CompiledMap> bound_map;
    for (pano::Method m : {pano::Method::kNearest, pano::Method::kLinear, pano::Method::kMrf}) {
      const std::string base = "omma-" + pano::to_string(m) + "-" + size_tag(g);
      if (!wanted(base) && !wanted("memcpy-bound-" + size_tag(g))) continue;
      try {
        render::MapOptions mo;
        mo.grid = g;
        mo.method = m;
        add(omma_workload(rig, mo, 0, frames));
        add(omma_workload(rig, mo, 1, frames, "", "-1thread"));
        if (m == pano::Method::kMrf) {  // the price of render::MapOptions::min_weight: every tap kept
          render::MapOptions all = mo;
          all.min_weight = 0;
          add(omma_workload(rig, all, 0, frames, "-alltaps"));
          if (opt.depth && wanted("omma-mrf-depth-" + size_tag(g))) add(omma_depth_workload(rig, mo, frames));
          // Frames entering the store as in the live engine, with and without the photometric
          // correction (the mrf figure may drop by at most 10 %).
          if (wanted(base) || wanted("omma-mrf-store-") || wanted("omma-mrf-photometric-")) {
            add(omma_live_workload(rig, mo, frames, false));
            add(omma_live_workload(rig, mo, frames, true));
          }
        }
        if (m != pano::Method::kNearest)  // mrf if pano has it, else linear
          bound_map = std::make_shared<render::CompiledMap>(render::compile_map(rig, mo));
      } catch (const std::logic_error& e) {
        if (skipped) skipped->push_back(base + ": " + e.what());
      }
    }
    if (wanted("opencv-remap-" + size_tag(g))) add(opencv_remap_workload(rig, g, frames));
    if (wanted("opencv-multiband-" + size_tag(g))) add(opencv_multiband_workload(rig, g, frames));
    if (bound_map && wanted("memcpy-bound-" + size_tag(g))) add(memcpy_workload(*bound_map, size_tag(g)));
  }
  // The ISP: one set = every camera's raw frame, developed (hybrid demosaicing +
  // gray world, thesis appendix A) against OpenCV's cvtColor bilinear Bayer conversion of the same
  // frames, both over the cameras with oneTBB. fps = sets per second.
  const auto raws = random_raw_frames(rig, 7);
  const std::string set_tag = fmt::format("{}x{}x{}", raws.size(), raws[0].cols, raws[0].rows);
  if (wanted("isp-hybrid-grayworld-" + set_tag)) {
    Workload w{"isp-hybrid-grayworld-" + set_tag,
               0,
               [&raws] {
                 isp::IspOptions o;  // hybrid + gray world by default
                 const auto developed = isp::develop_all(raws, o);
                 if (developed.empty()) throw std::logic_error("no frames");
               },
               {{"unit", "sets of frames"}}};
    add(w);
  }
  if (wanted("opencv-bayer-bilinear-" + set_tag)) {
    Workload w{"opencv-bayer-bilinear-" + set_tag,
               0,
               [&raws] {
                 std::vector<cv::Mat> out(raws.size());
                 tbb::parallel_for(size_t(0), raws.size(), [&](size_t i) {
                   cv::cvtColor(raws[i], out[i], cv::COLOR_BayerBG2BGR);  // RGGB with (0,0) = R
                 });
               },
               {{"unit", "sets of frames"}}};
    add(w);
  }
  // Interleaved measurement (see bench.h).
  const int rounds = std::max(1, opt.rounds);
  const double slice = opt.min_seconds / rounds;
  std::vector<Timing> sum(ws.size());
  std::vector<std::vector<double>> round_fps(ws.size());
  for (int r = 0; r < rounds; ++r) {
    spdlog::info("bench: round {}/{} over {} workloads", r + 1, rounds, ws.size());
    for (size_t i = 0; i < ws.size(); ++i) {
      const Timing t = time_workload(ws[i], slice, 1);
      sum[i].frames += t.frames, sum[i].wall_s += t.wall_s, sum[i].cpu_s += t.cpu_s;
      round_fps[i].push_back(t.frames / t.wall_s);
    }
  }
  std::vector<BenchEntry> out;
  for (size_t i = 0; i < ws.size(); ++i) {
    nlohmann::json info = ws[i].info;
    info["cpu_ms_per_frame"] = sum[i].cpu_s / sum[i].frames * 1e3;  // CPU time of all threads per frame
    info["frames"] = sum[i].frames;
    out.push_back({ws[i].name, sum[i].frames / sum[i].wall_s, info, round_fps[i]});
  }
  return out;
}

nlohmann::json BenchRatio::to_json() const {
  nlohmann::json j = {{"name", name}, {"fps", fps}};
  if (vs_remap > 0) j["vs_opencv_remap"] = vs_remap, j["target_10x_opencv_remap_met"] = vs_remap >= 10;
  if (vs_multiband > 0)
    j["vs_opencv_multiband"] = vs_multiband, j["target_100x_opencv_multiband_met"] = vs_multiband >= 100;
  if (!vs_remap_rounds.empty()) j["vs_opencv_remap_rounds"] = vs_remap_rounds;
  if (!vs_multiband_rounds.empty()) j["vs_opencv_multiband_rounds"] = vs_multiband_rounds;
  if (bound_over > 0)
    j["memcpy_bound_over_ours"] = bound_over, j["target_within_2x_bound_met"] = bound_over <= 2;
  if (name.rfind("omma-mrf-1080x1080", 0) == 0) j["target_400fps_met"] = fps >= 400;
  if (vs_static > 0) j["vs_static"] = vs_static;
  if (name == "omma-mrf-depth-1080x1080")  // the first target (25) and the present one (56, on 2 cores)
    j["target_25fps_met"] = fps >= 25, j["target_56fps_met"] = fps >= 56;
  // What the correction costs is the photometric workload against the same frame
  // entry without it (store); against the plain render (no frames entering at all) for reference.
  if (vs_plain > 0) j["vs_plain_render"] = vs_plain, j["vs_plain_render_rounds"] = vs_plain_rounds;
  if (vs_store > 0) {
    j["vs_store_without_photometric"] = vs_store, j["vs_store_rounds"] = vs_store_rounds;
    j["target_drop_at_most_10pct_met"] = vs_store >= 0.9;
  }
  return j;
}

std::vector<BenchRatio> bench_ratios(const std::vector<BenchEntry>& entries) {
  auto find = [&](const std::string& name) -> const BenchEntry* {
    for (const auto& e : entries)
      if (e.name == name) return &e;
    return nullptr;
  };
  auto fps_of = [&](const std::string& name) {
    const BenchEntry* e = find(name);
    return e ? e->fps : 0.0;
  };
  auto per_round = [&](const BenchEntry& ours, const std::string& peer) {
    std::vector<double> r;
    const BenchEntry* p = find(peer);
    if (!p || p->round_fps.size() != ours.round_fps.size()) return r;
    for (size_t i = 0; i < ours.round_fps.size(); ++i)
      if (p->round_fps[i] > 0) r.push_back(ours.round_fps[i] / p->round_fps[i]);
    return r;
  };
  std::vector<BenchRatio> out;
  for (const auto& e : entries) {
    if (e.name.rfind("omma-", 0) != 0 || e.name.find("-1thread") != std::string::npos || !(e.fps > 0))
      continue;
    const std::string size = e.name.substr(e.name.rfind('-') + 1);  // "1080x1080"
    BenchRatio r;
    r.name = e.name;
    r.fps = e.fps;
    if (const double a = fps_of("opencv-remap-" + size); a > 0) r.vs_remap = e.fps / a;
    if (const double b = fps_of("opencv-multiband-" + size); b > 0) r.vs_multiband = e.fps / b;
    if (const double m = fps_of("memcpy-bound-" + size); m > 0) r.bound_over = m / e.fps;
    r.vs_remap_rounds = per_round(e, "opencv-remap-" + size);
    r.vs_multiband_rounds = per_round(e, "opencv-multiband-" + size);
    if (const size_t d = e.name.find("-depth-"); d != std::string::npos)  // against the static map
      if (const double st = fps_of(e.name.substr(0, d) + "-" + size); st > 0) r.vs_static = e.fps / st;
    if (const size_t at = e.name.find("-photometric-"); at != std::string::npos) {
      const std::string plain = e.name.substr(0, at) + "-" + size,
                        store = e.name.substr(0, at) + "-store-" + size;
      if (const double f = fps_of(plain); f > 0)
        r.vs_plain = e.fps / f, r.vs_plain_rounds = per_round(e, plain);
      if (const double f = fps_of(store); f > 0)
        r.vs_store = e.fps / f, r.vs_store_rounds = per_round(e, store);
    }
    out.push_back(r);
  }
  return out;
}

}  // namespace omma::bench
