#include "omma/live/sim_loop.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <random>
#include <thread>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include "omma/core/progress.h"
#include "omma/core/valid.h"

namespace omma::live {

bool SimCameraOptions::IsValid(std::string* why) const {
  if (!(fps_min > 0 && fps_max >= fps_min && fps_max <= 1000))
    return invalid(
        why, fmt::format("simulated camera rates {}-{} fps: need 0 < min <= max <= 1000", fps_min, fps_max));
  if (!(jitter_ms >= 0 && jitter_ms <= 1000))
    return invalid(why, fmt::format("jitter {} ms: need 0-1000 ms", jitter_ms));
  if (!(loop_s > 0 && loop_s <= 3600))
    return invalid(why, fmt::format("loop length {} s: need 0 < loop <= 3600 s", loop_s));
  if (!(max_memory_mb > 0))
    return invalid(why, fmt::format("loop memory bound {} MB: need > 0", max_memory_mb));
  return true;
}

double SimMotion::amplitude() const { return speed * period_s / kPi; }

double SimMotion::offset(double t) const { return amplitude() * (1 - std::cos(2 * kPi * t / period_s)) / 2; }

sim::DomePose SimMotion::pose(double t) const {
  sim::DomePose pose;
  if (translate)
    pose.translation_mm = offset(t) * axis;
  else
    pose.rotation = Eigen::AngleAxisd(deg2rad(offset(t)), Vec3::UnitZ()).toRotationMatrix();
  return pose;
}

// One camera of the loop, playing back on its own clock.
class SimLoopCamera : public CameraSource {
 public:
  SimLoopCamera(std::shared_ptr<SimLoop> loop, int cam, std::string what)
      : loop_(std::move(loop)), cam_(cam), what_(std::move(what)) {}
  Clock::time_point next_capture() override { return due(k_); }
  bool read(cv::Mat& frame) override {
    const auto& frames = loop_->frames_[cam_];
    if (Clock::now() < due(k_)) std::this_thread::sleep_until(due(k_));
    // Late: the newest frame already captured, as a sensor overwriting its buffer would give.
    const auto now = Clock::now();
    while (due(k_ + 1) <= now) ++k_;
    frame = frames[k_ % frames.size()];
    last_ = due(k_);
    ++k_;
    return true;
  }
  double fps() const override { return loop_->camera_fps(cam_); }
  Clock::time_point last_capture() const override { return last_; }
  std::string describe() const override { return what_; }

 private:
  // Capture instant of the k-th frame since the start: S + m T + tau_{c, k mod N}.
  Clock::time_point due(long k) {
    if (start_ == Clock::time_point{}) start_ = loop_->start_now();
    const auto& tau = loop_->capture_s_[cam_];
    const long n = long(tau.size());
    const double s = double(k / n) * loop_->motion_.period_s + tau[k % n];
    return start_ + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
  }
  std::shared_ptr<SimLoop> loop_;
  int cam_;
  std::string what_;
  long k_ = 0;
  Clock::time_point start_{}, last_{};
};

namespace {
std::shared_ptr<const sim::Scene> make_named_scene(const std::string& scene) {
  try {
    return sim::make_scene(scene);
  } catch (const std::exception& e) {
    throw SourceError("source 'sim:" + scene + "': " + e.what());
  }
}
}  // namespace

SimLoop::SimLoop(const Rig& rig, const std::string& scene, std::optional<double> speed,
                 const SimCameraOptions& opt)
    : SimLoop(rig, make_named_scene(scene), scene.rfind("colon", 0) == 0, speed, opt) {}

SimLoop::SimLoop(const Rig& rig, std::shared_ptr<const sim::Scene> scene, bool translate,
                 std::optional<double> speed, const SimCameraOptions& opt_in)
    : scene_(std::move(scene)), spec_(scene_ ? scene_->spec() : "") {
  if (!scene_) throw SourceError("sim: no scene");
  SimCameraOptions opt = opt_in;
  std::string why;
  if (!opt.IsValid(&why)) throw SourceError("source 'sim:" + spec_ + "': " + why);
  const std::optional<sim::Scene::Travel> travel = scene_->travel();
  motion_.translate = translate || travel.has_value();
  if (travel) motion_.axis = travel->direction;
  motion_.speed = speed.value_or(travel ? travel->speed_mm_s : motion_.translate ? 5.0 : 10.0);
  if (!(motion_.speed >= 0 && motion_.speed <= kMaxSimSpeed))
    throw SourceError(fmt::format("source 'sim:{}': the speed must be in [0, {}], got {}", spec_,
                                  kMaxSimSpeed, motion_.speed));
  // Memory: one 8-bit BGR frame per camera per frame period; shorten the loop to fit.
  double bytes_per_s = 0;
  for (const auto& c : rig.cameras) bytes_per_s += 3.0 * c.in.width * c.in.height * opt.fps_max;
  const double max_bytes = opt.max_memory_mb * 1e6;
  if (bytes_per_s * opt.loop_s > max_bytes) {
    const double fit = max_bytes / bytes_per_s;
    if (fit < 2.0 / opt.fps_min)
      throw SourceError(
          fmt::format("source 'sim:{}': {} cameras need {:.0f} MB per second of loop; the bound "
                      "of {:.0f} MB holds less than two frames",
                      spec_, rig.cameras.size(), bytes_per_s / 1e6, opt.max_memory_mb));
    spdlog::warn("sim: a {:.2f} s loop of {} cameras needs {:.0f} MB; shortened to {:.2f} s to fit {:.0f} MB",
                 opt.loop_s, rig.cameras.size(), bytes_per_s * opt.loop_s / 1e6, fit, opt.max_memory_mb);
    opt.loop_s = fit;
  }
  motion_.period_s = opt.loop_s;
  const double T = opt.loop_s;
  // The cameras' clocks.
  std::mt19937_64 rng(opt.seed);
  std::uniform_real_distribution<double> uni(0, 1);
  std::normal_distribution<double> normal(0, 1);
  const size_t n = rig.cameras.size();
  capture_s_.resize(n);
  frames_.resize(n);
  struct Job {
    int cam;
    int k;
  };
  std::vector<Job> jobs;
  for (size_t c = 0; c < n; ++c) {
    // A whole number of frames in the loop, the rate within [fps_min, fps_max] if the loop allows.
    const double f0 = opt.fps_min + (opt.fps_max - opt.fps_min) * uni(rng);
    const long lo = long(std::ceil(T * opt.fps_min - 1e-9)), hi = long(std::floor(T * opt.fps_max + 1e-9));
    long frames = std::lround(T * f0);
    if (lo <= hi) frames = std::clamp(frames, lo, hi);
    frames = std::max(1L, frames);
    const double period = T / double(frames);
    const double phase = period * uni(rng);
    const double clip = period / 4;
    capture_s_[c].resize(frames);
    frames_[c].resize(frames);
    for (long k = 0; k < frames; ++k) {
      const double j = std::clamp(normal(rng) * opt.jitter_ms * 1e-3, -clip, clip);
      capture_s_[c][k] = phase + double(k) * period + j;
      jobs.push_back({int(c), int(k)});
    }
  }
  // Render the loop: every frame at its own scene time. The scene is read-only (thread-safe).
  const auto t0 = Clock::now();
  Progress progress(fmt::format("sim: rendering a {:.2f} s loop, {} frames of {} cameras", T, jobs.size(), n),
                    jobs.size(), opt.progress);
  const sim::CameraEffects fx = sim::CameraEffects::ideal(1);
  tbb::parallel_for(size_t{0}, jobs.size(), [&](size_t i) {
    const Job& j = jobs[i];
    frames_[j.cam][j.k] =
        sim::render_camera(*scene_, rig.cameras[j.cam], motion_.pose(capture_s_[j.cam][j.k]), fx, false)
            .image;
    progress.step();
  });
  progress.finish();
  render_s_ = std::chrono::duration<double>(Clock::now() - t0).count();
  spdlog::info("sim: {} frames ({:.0f} MB) of {} cameras at {:.1f}-{:.1f} fps rendered in {:.1f} s",
               jobs.size(), bytes() / 1e6, n, opt.fps_min, opt.fps_max, render_s_);
}

std::vector<std::unique_ptr<CameraSource>> SimLoop::sources() {
  std::vector<std::unique_ptr<CameraSource>> out;
  auto self = shared_from_this();
  for (size_t c = 0; c < frames_.size(); ++c)
    out.push_back(std::make_unique<SimLoopCamera>(self, int(c), fmt::format("sim:{} camera {}", spec_, c)));
  return out;
}

Clock::time_point SimLoop::start_now() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (start_ == Clock::time_point{}) start_ = Clock::now();
  return start_;
}

Clock::time_point SimLoop::start() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return start_;
}

double SimLoop::scene_time(Clock::time_point t) const {
  const double s = std::chrono::duration<double>(t - start()).count();
  const double T = motion_.period_s;
  return s - std::floor(s / T) * T;
}

size_t SimLoop::frames() const {
  size_t k = 0;
  for (const auto& f : frames_) k += f.size();
  return k;
}

size_t SimLoop::bytes() const {
  size_t b = 0;
  for (const auto& fs : frames_)
    for (const auto& f : fs) b += f.total() * f.elemSize();
  return b;
}

}  // namespace omma::live
