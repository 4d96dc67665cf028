// omma render: large panoramas (Giga-Eye, 21.6 / 82.3 MP) from a frames folder or a recording, as one
// process or distributed under mpirun (omma/dist: frame sets as items of a job, or one panorama split by
// bands).
#include <charconv>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <tbb/global_control.h>

#include "apps/command.h"
#include "apps/depth_spec.h"
#include "apps/split_render.h"
#include "omma/core/frames.h"
#include "omma/core/io.h"
#include "omma/core/log.h"
#include "omma/core/progress.h"
#include "omma/design/prototype.h"
#include "omma/dist/comm.h"
#include "omma/dist/job.h"
#include "omma/io/pano_file.h"
#include "omma/io/recording.h"
#include "omma/io/tiff_writer.h"
#include "omma/isp/photometric.h"
#include "omma/pano/quality.h"
#include "omma/pano/surface.h"
#include "omma/render/pano_render.h"

namespace omma::app {
namespace {
namespace fs = std::filesystem;

struct RenderArgs {
  std::string input, rig, size = "9000x2400", projection = "equirect-100", method = "mrf", out, sets, truth;
  std::string demosaic = "hybrid", awb = "grayworld";
  std::string split = "sets", manifest, rank0 = "works";
  std::string incomplete = "hold";         // io::IncompletePolicy
  std::string depth = "inf", depth_pitch;  // --depth (apps/depth_spec.h), --depth-pitch
  double hold_max_age_ms = 0;              // 0: two frame-set periods
  int band_rows = 256, repeat = 1, bits = 12, threads = 0, window = 0;
  bool no_cache = false, stream_maps = false, json = false, raw = false, no_resume = false,
       no_photometric = false;
};

// One input (a recording or a frames folder) rendered frame set by frame set: the work of
// dist::run_job (one item per frame set), of --split tiles (every rank on one set) and of --repeat.
class RenderJob : public dist::Job {
 public:
  RenderJob(const RenderArgs& a, const render::PanoRenderOptions& o, const isp::IspOptions& iso,
            const io::FrameSetPlanOptions& incomplete, bool root)
      : a_(a), o_(o), iso_(iso), incomplete_(incomplete), root_(root) {}

  void open() override {
    recording_ = fs::exists(fs::path(a_.input) / "manifest.json");
    if (!recording_ && !fs::is_directory(a_.input))
      throw IoError("input '" + a_.input + "' is neither a recording nor a frames folder");
    if (recording_) {
      rec_ = std::make_unique<io::RecordingReader>(a_.input);
      const Rig& rr = rec_->manifest().rig;
      rig_ = a_.rig.empty() ? rr : design::load_rig_or_builtin(a_.rig);
      if (const std::string why = io::rig_mismatch(rig_, rr); !why.empty())
        throw std::invalid_argument("--rig " + why);
    } else {
      const fs::path rig_path = a_.rig.empty() ? fs::path(a_.input) / "rig.json" : fs::path(a_.rig);
      rig_ = a_.rig.empty() ? load_rig(rig_path) : design::load_rig_or_builtin(a_.rig);
    }
    // The rig's photometric model (vignetting, colour gains), once: raw frames are developed with it
    // in place of the white balance (these gain maps); developed frames are corrected in load().
    if (!a_.no_photometric && (recording_ || a_.raw)) gains_ = isp::flat_gains_from_rig(rig_);
    // Which frame sets.
    first_ = 0;
    last_ = recording_ ? rec_->frame_sets() - 1 : 0;
    if (!a_.sets.empty()) {
      const auto colon = a_.sets.find(':');
      // Whole decimal numbers only: "1:3abc" or "1e3" is refused, not read as a prefix.
      auto number = [&](const std::string& t) {
        int64_t v = 0;
        const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
        if (t.empty() || ec != std::errc() || end != t.data() + t.size())
          throw std::invalid_argument("--sets must be I or A:B (frame sets A..B-1), got '" + a_.sets + "'");
        return v;
      };
      first_ = number(a_.sets.substr(0, colon));
      last_ = colon == std::string::npos ? first_ : number(a_.sets.substr(colon + 1)) - 1;
    }
    if (!recording_ && (first_ != 0 || last_ != 0)) throw std::invalid_argument("--sets needs a recording");
    if (recording_ && (first_ < 0 || last_ < first_ || last_ >= rec_->frame_sets()))
      throw std::invalid_argument(
          fmt::format("--sets {} outside the recording's {} frame sets", a_.sets, rec_->frame_sets()));
    if (recording_) plan_frame_sets();
    if (o_.estimate_depth) apply_depth_pitch(a_.depth_pitch, rig_, o_.sweep);
  }
  // Sets lacking cameras: --incomplete (io::plan_frame_sets; deterministic, the same on every rank).
  void plan_frame_sets() {
    plan_ = rec_->plan(first_, last_, incomplete_);  // throws under fail
    planned_ = std::make_unique<io::PlannedFrameSets>(*rec_, plan_);
    if (plan_.incomplete > 0 && root_)
      spdlog::warn(
          "{} of {} frame sets lack cameras (--incomplete {}): {} completed with held frames ({} frames, "
          "at most {:.1f} ms old), {} skipped",
          plan_.incomplete, plan_.considered, io::incomplete_policy_name(plan_.policy), plan_.held_sets,
          plan_.held_frames, plan_.max_held_age_ns / 1e6, plan_.skipped);
    if (plan_.sets.empty())
      throw std::invalid_argument(fmt::format(
          "no frame set to render: all {} frame sets lack cameras{} (--incomplete {})", plan_.considered,
          plan_.policy == io::IncompletePolicy::kHold
              ? fmt::format(", with no frame to hold within {:.1f} ms", plan_.max_hold_age_ns / 1e6)
              : "",
          io::incomplete_policy_name(plan_.policy)));
  }
  int64_t items() const override { return recording_ ? int64_t(plan_.sets.size()) : 1; }
  int64_t set_of(int64_t i) const { return recording_ ? plan_.sets.at(size_t(i)).set : 0; }
  fs::path output(int64_t i) const override { return io::frame_set_path(a_.out, set_of(i), last_ > first_); }
  std::string item_name(int64_t i) const override {
    return recording_ ? fmt::format("frame set {}", set_of(i)) : "the panorama";
  }
  nlohmann::json input_summary() const override { return recording_ ? plan_.to_json() : nlohmann::json(); }
  const io::FrameSetPlan* plan() const { return recording_ ? &plan_ : nullptr; }
  nlohmann::json parameters() const override {
    std::error_code ec;
    const fs::path input = fs::weakly_canonical(a_.input, ec);
    return {{"input", input.string()},
            {"rig", a_.rig},
            {"size", a_.size},
            {"projection", a_.projection},
            {"method", a_.method},
            {"band_rows", a_.band_rows},
            {"demosaic", a_.demosaic},
            {"awb", a_.awb},
            {"bits", a_.bits},
            {"raw", a_.raw},
            {"photometric", !a_.no_photometric},
            {"incomplete", io::incomplete_policy_name(incomplete_.policy)},
            {"hold_max_age_ms", a_.hold_max_age_ms},
            {"min_weight", o_.min_weight},
            {"depth", a_.depth},
            {"depth_pitch", a_.depth_pitch}};
  }
  void setup() override {
    renderer_ = std::make_unique<render::PanoRenderer>(rig_, o_);
    // A fixed surface (sphere:R, truth:FILE): once, for every frame set.
    if (o_.depth && !o_.estimate_depth) {
      // A sphere around the centre, seen from it, is one distance: the panorama's coarsest grid holds it.
      const bool sphere = a_.depth.rfind("sphere:", 0) == 0;
      renderer_->set_depth(
          choose_depth(a_.depth, "", rig_, {}, sphere ? renderer_->coarsest_grid() : o_.grid).depth);
    }
  }
  // Reads and develops frame set i into the renderer (read and develop times).
  dist::ItemTimes load(int64_t i) {
    dist::ItemTimes t;
    if (recording_) {
      render::FrameSetTimes ft;
      renderer_->set_frames(render::develop_frame_set(*planned_, i, iso_, &ft, gains_));
      t.read = ft.read;
      t.develop = ft.develop;
    } else {
      const auto t0 = clock::now();
      std::vector<cv::Mat> frames = a_.raw ? load_raw_frames(a_.input, rig_) : load_frames(a_.input, rig_);
      const auto t1 = clock::now();
      if (a_.raw)
        frames = isp::develop_with_model(frames, iso_, gains_);
      else if (!a_.no_photometric)
        frames = isp::correct_frames(rig_, frames);
      renderer_->set_frames(frames);
      t.read = seconds(t0, t1);
      t.develop = seconds(t1, clock::now());
    }
    if (o_.estimate_depth) {
      t.develop += renderer_->estimate_seconds();  // the depth is estimated from the developed frames
      depth_seconds_ += renderer_->estimate_seconds();
      ++depth_estimates_;
    }
    return t;
  }
  // The depth estimates so far (this process): count and seconds.
  int depth_estimates() const { return depth_estimates_; }
  double depth_seconds() const { return depth_seconds_; }
  dist::ItemTimes run(int64_t i) override {
    dist::ItemTimes t = load(i);
    const auto t0 = clock::now();
    t.render = io::render_to_file(*renderer_, output(i));
    t.write = seconds(t0, clock::now()) - t.render;
    return t;
  }
  bool recording() const { return recording_; }
  render::PanoRenderer& renderer() { return *renderer_; }

 private:
  using clock = std::chrono::steady_clock;
  static double seconds(clock::time_point a, clock::time_point b) {
    return std::chrono::duration<double>(b - a).count();
  }
  const RenderArgs& a_;
  render::PanoRenderOptions o_;
  isp::IspOptions iso_;
  io::FrameSetPlanOptions incomplete_;
  bool root_ = true;
  io::FrameSetPlan plan_;
  std::unique_ptr<io::PlannedFrameSets> planned_;
  bool recording_ = false;
  std::unique_ptr<io::RecordingReader> rec_;
  Rig rig_;
  int64_t first_ = 0, last_ = 0;
  std::vector<cv::Mat> gains_;  // flat-gain maps of the rig's photometric model (empty: none)
  std::unique_ptr<render::PanoRenderer> renderer_;
  int depth_estimates_ = 0;
  double depth_seconds_ = 0;
};

// What one run of `omma render` did, for its summary.
struct RenderTotals {
  double render_s = 0, develop_s = 0, read_s = 0, write_s = 0;
  int64_t rendered = 0, reused = 0;
  fs::path last_out;
  nlohmann::json dist_json = nullptr;  // how the work was distributed (null: --repeat)
};

// The options, the same on every rank (so an error is every rank's, given once by the caller).
struct RenderSetup {
  render::PanoRenderOptions o;
  isp::IspOptions iso;
  Size2 size{0, 0};
  dist::Rank0 rank0 = dist::Rank0::kWorks;
  io::FrameSetPlanOptions incomplete;
};
RenderSetup parse_render_args(const dist::Comm& comm, const RenderArgs& a) {
  RenderSetup s;
  render::PanoRenderOptions& o = s.o;
  isp::IspOptions& iso = s.iso;
  Size2& size = s.size;
  dist::Rank0& rank0 = s.rank0;
  const bool root = comm.rank() == 0;
  if (a.out.empty()) throw std::invalid_argument("--out is required");
  size = parse_size(a.size, /*banded=*/true);
  if (a.band_rows < 1) throw std::invalid_argument("--band-rows must be >= 1");
  if (a.repeat < 1 || a.repeat > 10000) throw std::invalid_argument("--repeat must be 1..10000");
  if (a.repeat > 1 && comm.size() > 1)
    throw std::invalid_argument("--repeat measures one process's speed: run it without mpirun");
  if (a.split != "sets" && a.split != "tiles") throw std::invalid_argument("--split must be sets or tiles");
  if (a.threads < 0) throw std::invalid_argument("--threads must be >= 0");
  rank0 = dist::parse_rank0(a.rank0);
  s.incomplete.policy = io::parse_incomplete_policy(a.incomplete);
  if (!(a.hold_max_age_ms >= 0 && a.hold_max_age_ms <= 1e9))
    throw std::invalid_argument("--hold-max-age-ms must be in [0, 1e9] (0: two frame-set periods)");
  s.incomplete.max_hold_age_ns = int64_t(std::llround(a.hold_max_age_ms * 1e6));
  o.grid = PanoGrid{parse_projection(a.projection), size.width, size.height};
  if (const std::string ext = lower_extension(a.out); ext != ".tif" && ext != ".tiff" && ext != ".btf")
    check_image_format(a.out, size.width, size.height);  // before any work: e.g. a JPEG too wide
  if (a.method == "hq") {
    o.offline = true;
    o.method = pano::Method::kLinear;
  } else {
    o.method = pano::parse_method(a.method);
  }
  o.band_rows = a.band_rows;
  o.resident_maps = !a.stream_maps;
  // --depth: inf keeps the static band maps; any surface makes the bands depth-adaptive.
  check_depth_spec(a.depth);
  if (a.depth != "inf") {
    if (o.offline) throw std::invalid_argument("--depth needs an engine method (not hq)");
    o.depth = true;
    if (is_estimate_spec(a.depth)) {  // NEAR,FAR,STEPS replace the Giga-Eye defaults
      o.estimate_depth = true;
      o.sweep = parse_estimate_spec(a.depth, render::giga_sweep_options());
    }
  } else if (!a.depth_pitch.empty()) {
    throw std::invalid_argument("--depth-pitch applies to --depth estimate only");
  }
  if (a.no_cache) o.cache_dir.clear();
  o.progress = !a.json && root;
  iso.demosaic = isp::parse_demosaic(a.demosaic);
  iso.awb = isp::parse_awb(a.awb);
  iso.srgb = true;
  iso.bits = a.bits;  // a recording's own bit depth replaces it (develop_frame_set)
  return s;
}

// --repeat: the speed of one process, the frame sets rendered --repeat times each (no manifest).
void render_repeat(RenderJob& job, const RenderArgs& a, RenderTotals& r) {
  job.open();
  job.setup();
  Progress progress("render", size_t(job.items() * a.repeat), !a.json);
  for (int64_t i = 0; i < job.items(); ++i) {
    const dist::ItemTimes t = job.load(i);
    r.read_s += t.read;
    r.develop_s += t.develop;
    for (int k = 0; k < a.repeat; ++k) {
      r.last_out = job.output(i);
      r.render_s += io::render_to_file(job.renderer(), r.last_out);
      ++r.rendered;
      progress.step();
    }
  }
  progress.finish();
}

// --split sets: one frame set per work item of dist::run_job (resumable, with a manifest).
// Returns false on the ranks other than 0 (nothing to report).
bool render_sets(dist::Comm& comm, RenderJob& job, const RenderArgs& a, dist::Rank0 rank0, RenderTotals& r) {
  const bool root = comm.rank() == 0;
  dist::RunOptions ro;
  ro.manifest =
      a.manifest.empty() ? fs::path(a.out).parent_path() / "render-manifest.json" : fs::path(a.manifest);
  ro.resume = !a.no_resume;
  ro.rank0 = rank0;
  ro.progress = !a.json;
  ro.label = "frame sets";
  const dist::RunSummary sum = dist::run_job(comm, job, ro);
  if (!root) return false;
  r.rendered = sum.made;
  r.reused = sum.reused;
  r.render_s = sum.totals.render;
  r.develop_s = sum.totals.develop;
  r.read_s = sum.totals.read;
  r.write_s = sum.totals.write + sum.checksum_seconds;
  r.last_out = job.output(job.items() - 1);
  const double work_s = sum.seconds - sum.setup_seconds;
  r.dist_json = {{"split", "sets"},
                 {"ranks", sum.ranks},
                 {"mpi", sum.mpi},
                 {"rank0", dist::rank0_name(sum.rank0)},
                 {"manifest", ro.manifest.string()},
                 {"made", sum.made},
                 {"reused", sum.reused},
                 {"setup_seconds", sum.setup_seconds},
                 {"work_seconds", work_s},
                 {"frame_sets_per_s", work_s > 0 ? sum.made / work_s : 0},
                 {"seconds_per_stage",
                  {{"read", sum.totals.read},
                   {"develop", sum.totals.develop},
                   {"render", sum.totals.render},
                   {"write", sum.totals.write},
                   {"checksum", sum.checksum_seconds}}},
                 {"cpu_seconds", sum.cpu_seconds}};
  return true;
}

// --split tiles: every rank opens and prepares, then each frame set is split by bands among the
// ranks (dist::render_split). Returns false on the ranks other than 0.
bool render_tiles(dist::Comm& comm, RenderJob& job, const RenderArgs& a, dist::Rank0 rank0, RenderTotals& r) {
  using clock = std::chrono::steady_clock;
  const bool root = comm.rank() == 0;
  std::string error;
  error.clear();
  try {
    job.open();
  } catch (const std::exception& e) {
    error = e.what();
  }
  dist::check_all_ranks(comm, error);
  error.clear();
  if (root) try {
      job.setup();  // first: fills the map cache the others read
    } catch (const std::exception& e) {
      error = e.what();
    }
  dist::check_all_ranks(comm, error);
  error.clear();
  if (!root) try {
      job.setup();
    } catch (const std::exception& e) {
      error = e.what();
    }
  dist::check_all_ranks(comm, error);
  dist::SplitOptions so;
  so.window = a.window;
  so.rank0 = rank0;
  double wall = 0, load_wall = 0;
  int max_held = 0;
  std::vector<int> per_rank;
  for (int64_t i = 0; i < job.items(); ++i) {
    error.clear();
    const auto tl = clock::now();
    try {
      const dist::ItemTimes t = job.load(i);
      r.read_s += t.read;  // rank 0's; every rank reads and develops the whole set
      r.develop_s += t.develop;
    } catch (const std::exception& e) {
      error = e.what();
    }
    dist::check_all_ranks(comm, error, job.item_name(i) + ": ");
    load_wall += std::chrono::duration<double>(clock::now() - tl).count();
    r.last_out = job.output(i);
    const dist::SplitSummary s = dist::render_split(comm, job.renderer(), r.last_out, so);
    r.render_s += s.render_seconds;
    r.write_s += s.write_seconds;
    wall += s.seconds;
    max_held = std::max(max_held, s.max_held);
    if (per_rank.empty()) per_rank.assign(s.bands_per_rank.size(), 0);
    for (size_t k = 0; k < s.bands_per_rank.size(); ++k) per_rank[k] += s.bands_per_rank[k];
    ++r.rendered;
  }
  if (!root) return false;
  r.dist_json = {{"split", "tiles"},
                 {"ranks", comm.size()},
                 {"mpi", comm.is_mpi()},
                 {"rank0", dist::rank0_name(comm.size() == 1 ? dist::Rank0::kWorks : rank0)},
                 {"bands", job.renderer().bands()},
                 {"bands_per_rank", per_rank},
                 {"max_bands_held", max_held},
                 {"load_seconds", load_wall},
                 {"split_seconds", wall}};
  return true;
}

// The summary: JSON (--json) or a line, with the quality against --truth.
void report_render(const dist::Comm& comm, RenderJob& job, const RenderArgs& a, const Size2& size,
                   const cv::Mat& truth, const RenderTotals& r, double total) {
  nlohmann::json q = nullptr;
  if (!truth.empty()) {
    const std::string ext = lower_extension(r.last_out);
    const cv::Mat pano = (ext == ".tif" || ext == ".tiff" || ext == ".btf")
                             ? io::read_tiff_rows(r.last_out)
                             : read_image(r.last_out, cv::IMREAD_COLOR);
    q = {{"psnr_db", pano::psnr_db(pano, truth)}, {"ssim", pano::ssim(pano, truth)}};
  }
  render::PanoRenderer& renderer = job.renderer();
  const auto mem = renderer.memory();
  const double per = r.rendered > 0 ? r.render_s / r.rendered : 0;
  if (a.json) {
    print_json({{"input", a.input},
                {"recording", job.recording()},
                {"out", r.last_out.string()},
                {"panoramas", r.rendered},
                {"reused", r.reused},
                {"width", size.width},
                {"height", size.height},
                {"megapixels", size.width * double(size.height) / 1e6},
                {"method", a.method},
                {"bands", renderer.bands()},
                {"maps_seconds", renderer.maps_seconds()},
                {"maps_from_cache", renderer.maps_from_cache()},
                {"render_seconds_per_panorama", per},
                {"panoramas_per_s", per > 0 ? 1 / per : 0},
                {"develop_seconds", r.develop_s},
                {"read_seconds", r.read_s},
                {"write_seconds", r.write_s},
                {"memory",
                 {{"store_bytes", mem.store_bytes},
                  {"maps_bytes", mem.maps_bytes},
                  {"band_bytes", mem.band_bytes},
                  {"total_bytes", mem.total()}}},
                {"distributed", r.dist_json},
                {"frame_sets", job.plan() ? job.plan()->to_json() : nlohmann::json(nullptr)},
                {"quality", q},
                {"depth",
                 {{"mode", a.depth},
                  {"estimates", job.depth_estimates()},
                  {"estimate_seconds_per_panorama",
                   job.depth_estimates() > 0 ? job.depth_seconds() / job.depth_estimates() : 0.0}}},
                {"seconds", total}});
  } else {
    std::cout << fmt::format(
        "{}: {} panorama(s) {}x{} ({:.1f} MP, {}) from {}{}; maps {:.2f} s ({} of {} bands from the cache); "
        "render "
        "{:.3f} s per panorama ({:.2f}/s); memory {:.0f} MB (store {:.0f}, maps {:.0f}, band {:.0f})\n",
        r.last_out.string(), r.rendered, size.width, size.height, size.width * double(size.height) / 1e6,
        a.method, a.input,
        r.reused > 0 ? fmt::format(" ({} more verified from an earlier run)", r.reused) : "",
        renderer.maps_seconds(), renderer.maps_from_cache(), renderer.bands(), per, per > 0 ? 1 / per : 0,
        mem.total() / 1e6, mem.store_bytes / 1e6, mem.maps_bytes / 1e6, mem.band_bytes / 1e6);
    if (!r.dist_json.is_null() && comm.size() > 1)
      std::cout << fmt::format(
          "  {} ranks, split by {}{}\n", comm.size(), a.split,
          a.split == "sets" ? ", manifest " + r.dist_json["manifest"].get<std::string>() : "");
    if (const io::FrameSetPlan* p = job.plan())
      std::cout << fmt::format(
          "  frame sets: {} of {} complete; --incomplete {}: {} completed with held frames, {} skipped; 0 "
          "holes\n",
          p->complete, p->considered, io::incomplete_policy_name(p->policy), p->held_sets, p->skipped);
    if (a.depth != "inf")
      std::cout << fmt::format("  depth {}: {}\n", a.depth,
                               job.depth_estimates() > 0
                                   ? fmt::format("estimated {} time(s), {:.2f} s each", job.depth_estimates(),
                                                 job.depth_seconds() / job.depth_estimates())
                                   : std::string("fixed"));
    if (!q.is_null())
      std::cout << fmt::format("  against {}: PSNR {:.2f} dB, SSIM {:.4f}\n", a.truth,
                               q["psnr_db"].get<double>(), q["ssim"].get<double>());
  }
}

void render(dist::Comm& comm, const RenderArgs& a) {
  using clock = std::chrono::steady_clock;
  const auto t_start = clock::now();
  const bool root = comm.rank() == 0;
  RenderSetup s;
  std::string error;
  try {
    s = parse_render_args(comm, a);
  } catch (const std::exception& e) {
    error = e.what();
  }
  dist::check_all_ranks(comm, error);
  cv::Mat truth;
  if (root && !a.truth.empty()) {
    truth = read_image(a.truth, cv::IMREAD_COLOR);
    if (truth.cols != s.size.width || truth.rows != s.size.height)
      throw std::invalid_argument(fmt::format("--truth is {}x{}, the panorama {}x{}", truth.cols, truth.rows,
                                              s.size.width, s.size.height));
  }
  RenderJob job(a, s.o, s.iso, s.incomplete, root);
  RenderTotals r;
  if (a.repeat > 1) {
    render_repeat(job, a, r);
  } else if (a.split == "sets") {
    if (!render_sets(comm, job, a, s.rank0, r)) return;
  } else {
    if (!render_tiles(comm, job, a, s.rank0, r)) return;
  }
  report_render(comm, job, a, s.size, truth, r,
                std::chrono::duration<double>(clock::now() - t_start).count());
}

void run_render(const RenderArgs& a) {
  // Under mpirun every rank runs this; only rank 0 prints (progress, logs, the summary).
  auto comm = dist::make_comm();
  const bool root = comm->rank() == 0;
  set_json_mode(a.json || !root);
  if (!root) spdlog::set_level(spdlog::level::warn);
  std::optional<tbb::global_control> threads;
  if (a.threads > 0) threads.emplace(tbb::global_control::max_allowed_parallelism, a.threads);
  try {
    render(*comm, a);
  } catch (const dist::JobError& e) {
    if (e.quiet()) throw ExitSilently{1};  // rank 0 reports it
    throw;
  } catch (const std::exception& e) {
    if (comm->size() > 1) {
      // A failure the other ranks cannot know of (outside the checked phases): stop them all.
      std::fprintf(stderr, "omma: error: rank %d: %s\n", comm->rank(), e.what());
      comm->abort(1);
    }
    throw;
  }
}

}  // namespace

void add_render_command(CLI::App& root) {
  static RenderArgs a;
  auto* cmd = root.add_subcommand(
      "render",
      "Render large panoramas (Giga-Eye: 9000x2400 = 21.6 MP, 17700x4650 = 82.3 MP over 360x100 deg) from a\n"
      "frames folder (cam_XX.png, rig.json) or a recording (omma record: raw frame sets, developed by the "
      "ISP),\n"
      "band by band from cached maps. .tif/.tiff outputs are streamed (any size, memory = one band; BigTIFF\n"
      "beyond 4 GiB, or always as .btf); other formats hold the whole image. JPEG, PNG and TIFF carry the\n"
      "360-degree GPano XMP when the pixels are square (9000x2500, not 9000x2400: docs/guide/stitching.md).\n"
      "Methods: the engine's, or hq (offline: every tap in double precision).\n"
      "On a cluster: mpirun -np K omma render REC --out DIR/pano_{set}.tif hands the frame sets out to the "
      "K\n"
      "ranks as they ask; each output is written atomically and listed in a manifest, and a rerun makes "
      "only\n"
      "what is missing. --split tiles splits each panorama by bands across the ranks instead.");
  cmd->add_option("INPUT", a.input, "Frames folder or recording folder")->required();
  cmd->add_option("--rig", a.rig,
                  "Rig file or built-in rig (default: INPUT/rig.json or the recording's rig)");
  cmd->add_option("--out", a.out,
                  "Output image; with several frame sets a pattern with {set}, e.g. pano_{set}.tif")
      ->required();
  cmd->add_option("--size", a.size, "Panorama size WxH")->capture_default_str();
  cmd->add_option("--projection", a.projection, "equirect-100 | equirect | equirect-full | vr180")
      ->capture_default_str();
  cmd->add_option("--method", a.method, "nn | linear | gaussian | mrf | mrf-spherical | sad | hq")
      ->capture_default_str();
  cmd->add_option("--sets", a.sets, "Frame sets of a recording: I or A:B (A..B-1); default: all");
  cmd->add_option(
         "--incomplete", a.incomplete,
         "Frame sets of a recording that lack cameras: hold (each missing camera's last frame at most\n"
         "--hold-max-age-ms old; sets it cannot fill are skipped), skip (no panorama for them) or fail.\n"
         "Never a black hole; the counts go to stderr, --json and the manifest")
      ->capture_default_str();
  cmd->add_option("--hold-max-age-ms", a.hold_max_age_ms,
                  "--incomplete hold: oldest frame held, ms (0: two frame-set periods of the recording)")
      ->capture_default_str();
  cmd->add_option("--band-rows", a.band_rows, "Rows per band map")->capture_default_str();
  cmd->add_option(
         "--depth", a.depth,
         std::string("Projection surface: inf keeps the static band maps (the far field); any other\n"
                     "renders every band depth-adaptively (each tap moved to its camera's view of the\n"
                     "surface point), e.g. for near scenes seen by Giga-Eye's cameras 200 mm apart:\n") +
             kDepthSpecHelp +
             "                        (render's default: 400,inf,32 on a 1 deg grid, estimated per frame "
             "set)")
      ->capture_default_str();
  cmd->add_option("--depth-pitch", a.depth_pitch,
                  "With --depth estimate: the sweep grid's pitch, DEG or 'camera' (default 1 deg)");
  cmd->add_flag("--stream-maps", a.stream_maps,
                "Keep one band map in memory at a time (loaded from the cache)");
  cmd->add_flag("--no-cache", a.no_cache, "Do not read or write the map cache");
  cmd->add_flag(
      "--no-photometric", a.no_photometric,
      "Ignore the rig's photometric model (by default cameras with one are developed with its vignetting\n"
      "and colour gains instead of the white balance; developed frames are corrected)");
  cmd->add_flag("--raw", a.raw, "Frames folder: develop cam_XX_raw.png with the ISP instead of cam_XX.png");
  cmd->add_option("--bits", a.bits, "Bit depth of the raw frames of a frames folder (--raw)")
      ->capture_default_str();
  cmd->add_option("--demosaic", a.demosaic, "ISP demosaicing of raw frames")->capture_default_str();
  cmd->add_option("--awb", a.awb, "ISP white balance of raw frames")->capture_default_str();
  cmd->add_option("--truth", a.truth, "Ground-truth panorama of the same size: report PSNR and SSIM");
  cmd->add_option("--repeat", a.repeat, "Render each frame set N times (speed measurement)")
      ->capture_default_str();
  cmd->add_option(
         "--split", a.split,
         "Under mpirun: sets (each rank renders whole frame sets, handed out as it asks) or tiles (all\n"
         "ranks render one panorama at a time, split by bands; rank 0 writes the .tif)")
      ->capture_default_str();
  cmd->add_option(
      "--manifest", a.manifest,
      "Manifest of the outputs (size, checksum, rank, seconds per stage); default: render-manifest.json\n"
      "beside the outputs. A rerun skips the outputs it lists that still verify");
  cmd->add_flag("--no-resume", a.no_resume, "Make every output again, even those an earlier run verified");
  cmd->add_option("--rank0", a.rank0,
                  "Under mpirun: rank 0 works (renders too) or serves (only hands out work)")
      ->capture_default_str();
  cmd->add_option("--window", a.window,
                  "--split tiles: bands rank 0 may hold waiting for their turn (0: 2 x ranks)")
      ->capture_default_str();
  cmd->add_option("--threads", a.threads, "Threads per process (0: all cores)")->capture_default_str();
  cmd->add_flag("--json", a.json, "Print one JSON summary on stdout");
  cmd->callback([] { run_render(a); });
}

}  // namespace omma::app
