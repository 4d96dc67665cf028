#include "omma/calib/photometric.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>
#include <stdexcept>

#include <Eigen/Dense>
#include <ceres/ceres.h>
#include <fmt/format.h>
#include <opencv2/imgproc.hpp>
#include <tbb/parallel_for.h>

#include "omma/core/log.h"
#include "omma/core/progress.h"
#include "omma/core/srgb.h"
#include "omma/core/valid.h"

namespace omma::calib {
namespace {

constexpr int kLensTerms = PhotometricSummary::kLensTerms;
using Lens = std::array<double, PhotometricSummary::kLensTerms>;

// tan^2 of the angle between the ray of pixel px and the optical axis (the lens model's q).
double tan2_angle(const CameraModel& m, const Vec2& px) {
  const double ca = std::clamp(m.unproject(px).dot(m.frame.t), 1e-6, 1.0);
  return 1.0 / (ca * ca) - 1.0;
}

template <typename T>
T lens_falloff(const T* beta, T q) {
  T v(0);
  for (int k = kLensTerms - 1; k >= 0; --k) v = (v + beta[k]) * q;
  return T(1) + v;
}

void check_sets(const Rig& rig, const std::vector<std::vector<cv::Mat>>& sets, const char* what) {
  if (sets.empty()) throw std::invalid_argument(fmt::format("{}: no frame sets", what));
  for (size_t s = 0; s < sets.size(); ++s) {
    if (sets[s].size() != rig.cameras.size())
      throw std::invalid_argument(fmt::format("{}: frame set {} has {} frames for a rig of {} cameras", what,
                                              s, sets[s].size(), rig.cameras.size()));
    for (size_t i = 0; i < rig.cameras.size(); ++i) {
      const cv::Mat& f = sets[s][i];
      const RigCamera& c = rig.cameras[i];
      if (f.type() != CV_8UC3 && f.type() != CV_16UC3)
        throw std::invalid_argument(fmt::format(
            "{}: frame of camera {} (set {}) is not an 8- or 16-bit colour image", what, c.id, s));
      if (f.cols != c.in.width || f.rows != c.in.height)
        throw std::invalid_argument(
            fmt::format("{}: frame of camera {} (set {}) is {}x{}, the rig says {}x{}", what, c.id, s, f.cols,
                        f.rows, c.in.width, c.in.height));
    }
  }
}

// One camera's frame prepared for sampling: smoothed log signal (CV_32FC3), a mask of usable
// pixels (well exposed, well registered), as 8-bit.
struct Prepared {
  cv::Mat log;     // CV_32FC3
  cv::Mat usable;  // CV_8U, 1 = usable
};

Prepared prepare(const cv::Mat& frame, const PhotometricOptions& o) {
  Prepared p;
  cv::Mat lin = decode_linear(frame), sm;
  cv::GaussianBlur(lin, sm, cv::Size(), o.smooth_sigma_px, o.smooth_sigma_px, cv::BORDER_REPLICATE);
  cv::Mat clipped = cv::max(sm, 1e-6);
  cv::log(clipped, p.log);
  // Saturated or black pixels (raw, before smoothing), grown by the smoothing's reach.
  cv::Mat lo, hi, bad;
  cv::inRange(lin, cv::Scalar::all(o.min_signal), cv::Scalar::all(o.max_signal),
              lo);  // 255 where all in range
  cv::bitwise_not(lo, bad);
  const int grow = int(std::ceil(2 * o.smooth_sigma_px)) + 1;
  cv::dilate(bad, bad, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * grow + 1, 2 * grow + 1)));
  // Log gradient (every channel): |d log I / dx| + |d log I / dy| per pixel, the largest channel.
  cv::Mat gx, gy;
  cv::Sobel(p.log, gx, CV_32F, 1, 0, 3, 1.0 / 8);
  cv::Sobel(p.log, gy, CV_32F, 0, 1, 3, 1.0 / 8);
  cv::Mat g = cv::abs(gx) + cv::abs(gy);
  std::vector<cv::Mat> ch;
  cv::split(g, ch);
  cv::Mat gmax = cv::max(cv::max(ch[0], ch[1]), ch[2]);
  cv::Mat steep = gmax * o.registration_px > o.max_log_change;  // 255 where too steep
  p.usable = (bad == 0) & (steep == 0);
  return p;
}

struct Sample {
  int a = 0, b = 0;
  float la[3], lb[3];     // smoothed log signal
  double qa = 0, qb = 0;  // tan^2 of the ray angle in each camera
};

cv::Vec3f bilinear(const cv::Mat& m, const Vec2& px) {
  const double x = px.x() - 0.5, y = px.y() - 0.5;  // pixel-centre convention -> sample grid
  const int x0 = std::clamp(int(std::floor(x)), 0, m.cols - 2),
            y0 = std::clamp(int(std::floor(y)), 0, m.rows - 2);
  const float ax = float(std::clamp(x - x0, 0.0, 1.0)), ay = float(std::clamp(y - y0, 0.0, 1.0));
  const cv::Vec3f* r0 = m.ptr<cv::Vec3f>(y0);
  const cv::Vec3f* r1 = m.ptr<cv::Vec3f>(y0 + 1);
  return (r0[x0] * (1 - ax) + r0[x0 + 1] * ax) * (1 - ay) + (r1[x0] * (1 - ax) + r1[x0 + 1] * ax) * ay;
}

bool usable_at(const cv::Mat& usable, const Vec2& px) {
  const int c = int(px.x()), r = int(px.y());
  if (c < 1 || r < 1 || c >= usable.cols - 1 || r >= usable.rows - 1) return false;
  return usable.at<uint8_t>(r, c) && usable.at<uint8_t>(r, c + 1) && usable.at<uint8_t>(r + 1, c) &&
         usable.at<uint8_t>(r, c - 1) && usable.at<uint8_t>(r - 1, c);
}

struct OverlapCost {
  float la[3], lb[3];
  double qa, qb;
  double weight = 1;
  template <typename T>
  bool operator()(const T* ga, const T* gb, const T* beta, T* res) const {  // beta: kLensTerms
    const T va = lens_falloff(beta, T(qa)), vb = lens_falloff(beta, T(qb));
    if (!(va > T(1e-3)) || !(vb > T(1e-3))) return false;
    const T d = ceres::log(va) - ceres::log(vb);
    for (int c = 0; c < 3; ++c) res[c] = T(weight) * (T(double(la[c]) - double(lb[c])) - (ga[c] - gb[c] + d));
    return true;
  }
};

// Per channel: mean over the cameras' log gains = 0 (the gauge, see photometric.h).
struct GaugeCost {
  int n = 0;
  double weight = 10;
  template <typename T>
  bool operator()(T const* const* g, T* res) const {
    for (int c = 0; c < 3; ++c) {
      T s(0);
      for (int i = 0; i < n; ++i) s += g[i][c];
      res[c] = T(weight) * s / T(n);
    }
    return true;
  }
};

void solver_options(const PhotometricOptions& o, ceres::Solver::Options* so) {
  so->linear_solver_type = ceres::DENSE_QR;
  so->max_num_iterations = o.max_iterations;
  so->num_threads = o.threads;
  so->minimizer_progress_to_stdout = false;
  so->logging_type = ceres::SILENT;
}

}  // namespace

bool PhotometricOptions::IsValid(std::string* why) const {
  if (grid_step_px < 1 || grid_step_px > 64) return invalid(why, "grid_step_px must be 1..64");
  if (!(smooth_sigma_px >= 0 && smooth_sigma_px <= 20))
    return invalid(why, "smooth_sigma_px must be in [0, 20]");
  if (!(min_signal >= 0 && max_signal <= 1 && min_signal < max_signal))
    return invalid(why, "need 0 <= min_signal < max_signal <= 1");
  if (!(registration_px > 0) || !(max_log_change > 0))
    return invalid(why, "registration_px and max_log_change must be > 0");
  if (!(loss_scale > 0)) return invalid(why, "loss_scale must be > 0");
  if (!(noise_signal >= 0)) return invalid(why, "noise_signal must be >= 0");
  if (min_samples < 1 || max_samples_per_pair < 10)
    return invalid(why, "min_samples >= 1, max_samples_per_pair >= 10");
  if (threads < 1 || max_iterations < 1) return invalid(why, "threads and max_iterations must be >= 1");
  return true;
}

cv::Mat decode_linear(const cv::Mat& srgb) {
  if (srgb.depth() != CV_8U && srgb.depth() != CV_16U)
    throw std::invalid_argument("decode_linear: needs an 8- or 16-bit image");
  static const std::vector<float> lut8 = [] {
    std::vector<float> t(256);
    for (int i = 0; i < 256; ++i) t[i] = srgb_to_linear(i / 255.0f);
    return t;
  }();
  static const std::vector<float> lut16 = [] {
    std::vector<float> t(65536);
    for (int i = 0; i < 65536; ++i) t[i] = srgb_to_linear(i / 65535.0f);
    return t;
  }();
  cv::Mat out(srgb.size(), CV_MAKETYPE(CV_32F, srgb.channels()));
  const int n = srgb.cols * srgb.channels();
  for (int r = 0; r < srgb.rows; ++r) {
    float* d = out.ptr<float>(r);
    if (srgb.depth() == CV_8U) {
      const uint8_t* s = srgb.ptr<uint8_t>(r);
      for (int i = 0; i < n; ++i) d[i] = lut8[s[i]];
    } else {
      const uint16_t* s = srgb.ptr<uint16_t>(r);
      for (int i = 0; i < n; ++i) d[i] = lut16[s[i]];
    }
  }
  return out;
}

std::vector<cv::Mat> flat_field_frames(const std::vector<cv::Mat>& frames,
                                       const std::vector<std::vector<cv::Mat>>& flat_sets, double sigma_px) {
  for (const auto& set : flat_sets) {
    if (set.size() != frames.size())
      throw std::invalid_argument(
          fmt::format("flat field: {} flat frames for {} frames", set.size(), frames.size()));
    for (size_t i = 0; i < frames.size(); ++i)
      if (set[i].size() != frames[i].size())
        throw std::invalid_argument(fmt::format("flat field: flat frame {} is {}x{}, the frame is {}x{}", i,
                                                set[i].cols, set[i].rows, frames[i].cols, frames[i].rows));
  }
  if (flat_sets.empty()) return frames;
  std::vector<cv::Mat> out(frames.size());
  tbb::parallel_for(size_t{0}, frames.size(), [&](size_t i) {
    cv::Mat flat = decode_linear(flat_sets[0][i]);
    for (size_t s = 1; s < flat_sets.size(); ++s) flat += decode_linear(flat_sets[s][i]);
    cv::GaussianBlur(flat, flat, cv::Size(), sigma_px, sigma_px, cv::BORDER_REPLICATE);
    double hi = 0;
    cv::minMaxLoc(flat.reshape(1), nullptr, &hi);
    flat = cv::max(flat / hi, 1e-3);
    cv::Mat lin = decode_linear(frames[i]) / flat, enc(lin.size(), CV_16UC3);
    for (int r = 0; r < lin.rows; ++r) {
      const float* src = lin.ptr<float>(r);
      uint16_t* dst = enc.ptr<uint16_t>(r);
      for (int k = 0; k < lin.cols * 3; ++k)
        dst[k] = uint16_t(std::lround(65535.0f * linear_to_srgb(src[k])));
    }
    out[i] = enc;
  });
  return out;
}

Photometric photometric_from_lens(const RigCamera& camera, const Lens& beta,
                                  const std::array<double, 3>& gains, double* max_error) {
  Photometric p;
  p.gains = gains;
  const int W = camera.in.width, H = camera.in.height;
  p.center_px = Vec2(camera.in.cu - W / 2.0, camera.in.cv - H / 2.0);
  const CameraModel m = camera.model();
  auto v_lens = [&](double c, double r) { return lens_falloff(beta.data(), tan2_angle(m, Vec2(c, r))); };
  const int step = std::max(1, std::min(W, H) / 64);
  std::vector<double> ss, vs;
  auto add = [&](double c, double r) {
    const double rad = vignetting_radius(p, W, H, c, r);
    ss.push_back(rad * rad);
    vs.push_back(v_lens(c, r));
  };
  for (int r = 0; r < H; r += step)
    for (int c = 0; c < W; c += step) add(c + 0.5, r + 0.5);
  for (double c : {0.5, W / 2.0, W - 0.5})  // the outermost pixels
    for (double r : {0.5, H / 2.0, H - 0.5}) add(c, r);
  p.vignetting = fit_vignetting(ss, vs);
  if (max_error) {
    double mx = 0;
    for (int r = 0; r < H; r += 2)
      for (int c = 0; c < W; c += 2)
        mx = std::max(mx,
                      std::abs(vignetting_falloff(p, W, H, c + 0.5, r + 0.5) / v_lens(c + 0.5, r + 0.5) - 1));
    *max_error = mx;
  }
  return p;
}

namespace {

// The overlap samples of cameras a and b in one frame set (prepared): the usable pixels of a grid
// in camera a (every grid_step_px pixels) that camera b sees usable too.
std::vector<Sample> pair_samples(const Rig& rig, const std::vector<CameraModel>& model,
                                 const std::vector<Prepared>& prep, const PhotometricOptions& o, int a,
                                 int b) {
  const RigCamera& ca = rig.cameras[a];
  const RigCamera& cb = rig.cameras[b];
  std::vector<Sample> pair;
  for (int r = o.grid_step_px / 2; r < ca.in.height; r += o.grid_step_px)
    for (int c = o.grid_step_px / 2; c < ca.in.width; c += o.grid_step_px) {
      const Vec2 pa(c + 0.5, r + 0.5);
      if (!prep[a].usable.at<uint8_t>(r, c)) continue;
      const Vec3 w = model[a].unproject(pa);
      if (w.dot(cb.frame.t) <= 0.1) continue;
      const auto pb = model[b].project(w);
      if (!pb || pb->x() < 2 || pb->y() < 2 || pb->x() > cb.in.width - 2 || pb->y() > cb.in.height - 2)
        continue;
      if (!usable_at(prep[b].usable, *pb)) continue;
      Sample s;
      s.a = a, s.b = b;
      const cv::Vec3f va = prep[a].log.at<cv::Vec3f>(r, c), vb = bilinear(prep[b].log, *pb);
      for (int k = 0; k < 3; ++k) s.la[k] = va[k], s.lb[k] = vb[k];
      s.qa = tan2_angle(model[a], pa);
      s.qb = tan2_angle(model[b], *pb);
      pair.push_back(s);
    }
  return pair;
}

// The samples from every overlapping pair of every set (at most max_samples_per_pair per pair
// and set); marks the pairs that gave samples in pair_used (n x n, a < b).
std::vector<Sample> overlap_samples(const Rig& rig, const std::vector<CameraModel>& model,
                                    const std::vector<std::vector<cv::Mat>>& sets,
                                    const PhotometricOptions& o, std::vector<char>& pair_used) {
  const int n = static_cast<int>(rig.cameras.size());
  std::vector<Sample> samples;
  Progress progress("photometric: overlaps", sets.size() * size_t(n));
  for (const auto& frames : sets) {
    std::vector<Prepared> prep(n);
    tbb::parallel_for(0, n, [&](int i) { prep[size_t(i)] = prepare(frames[size_t(i)], o); });
    std::mutex mutex;
    tbb::parallel_for(0, n, [&](int a) {
      std::vector<Sample> mine;
      const RigCamera& ca = rig.cameras[a];
      for (int b = a + 1; b < n; ++b) {
        const RigCamera& cb = rig.cameras[b];
        if (ca.frame.t.dot(cb.frame.t) < std::cos(std::min(kPi * 0.9, ca.in.aov + 0.6))) continue;
        std::vector<Sample> pair = pair_samples(rig, model, prep, o, a, b);
        if (pair.size() < 20) continue;
        const size_t keep = std::min<size_t>(pair.size(), size_t(o.max_samples_per_pair));
        for (size_t k = 0; k < keep; ++k) mine.push_back(pair[k * pair.size() / keep]);
        std::lock_guard<std::mutex> lock(mutex);
        pair_used[size_t(a) * n + b] = 1;
      }
      std::lock_guard<std::mutex> lock(mutex);
      samples.insert(samples.end(), mine.begin(), mine.end());
      progress.step();
    });
  }
  progress.finish();
  return samples;
}

// Per camera, whether it has at least min_samples samples (those that have not go to
// res.uncalibrated_ids); sets res.samples_per_camera. Throws if fewer than 2 cameras have.
std::vector<char> active_cameras(const Rig& rig, const std::vector<Sample>& samples,
                                 const PhotometricOptions& o, PhotometricSummary& res) {
  const int n = static_cast<int>(rig.cameras.size());
  res.samples_per_camera.assign(n, 0);
  for (const Sample& s : samples) ++res.samples_per_camera[s.a], ++res.samples_per_camera[s.b];
  std::vector<char> active(n, 0);
  for (int i = 0; i < n; ++i) {
    active[i] = res.samples_per_camera[i] >= o.min_samples;
    if (!active[i]) res.uncalibrated_ids.push_back(rig.cameras[i].id);
  }
  if (std::count(active.begin(), active.end(), 1) < 2)
    throw std::runtime_error(fmt::format(
        "photometric calibration: too little overlap to calibrate ({} usable samples over {} camera pairs; "
        "every "
        "camera needs {}): are the frames dark, saturated or flat, or does the rig not match them?",
        samples.size(), res.pairs, o.min_samples));
  return active;
}

// The RMS overlap residual (log units) of the samples under log gains lg and lens falloff beta.
double rms_log_residual(const std::vector<Sample>& samples, const std::vector<std::array<double, 3>>& lg,
                        const Lens& beta) {
  double s2 = 0;
  for (const Sample& s : samples) {
    double r[3] = {1, 1, 1};  // a falloff <= 0 (rejected by the solver) counts as a unit error
    if (!OverlapCost{{s.la[0], s.la[1], s.la[2]}, {s.lb[0], s.lb[1], s.lb[2]}, s.qa, s.qb, 1.0}(
            lg[s.a].data(), lg[s.b].data(), beta.data(), r))
      r[0] = r[1] = r[2] = 1;
    s2 += r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
  }
  return samples.empty() ? 0.0 : std::sqrt(s2 / (3.0 * samples.size()));
}

// Joint fit of the lens falloff beta and the log gains lg (per camera and channel, the mean over
// the active cameras 0), starting from their values; throws if the solver fails.
void fit_lens_and_gains(const std::vector<Sample>& samples, const std::vector<char>& active,
                        const PhotometricOptions& o, std::vector<std::array<double, 3>>& lg, Lens& beta) {
  const int n = static_cast<int>(active.size());
  ceres::Problem problem;
  for (const Sample& s : samples) {
    // Dark samples are noisy in log units (and the log of a noisy value is biased): weight
    // signal / sqrt(signal^2 + noise_signal^2) by the darkest channel of the two.
    const double lo = std::exp(double(std::min({s.la[0], s.la[1], s.la[2], s.lb[0], s.lb[1], s.lb[2]})));
    const double w = lo / std::sqrt(lo * lo + o.noise_signal * o.noise_signal);
    auto* cost = new ceres::AutoDiffCostFunction<OverlapCost, 3, 3, 3, kLensTerms>(
        new OverlapCost{{s.la[0], s.la[1], s.la[2]}, {s.lb[0], s.lb[1], s.lb[2]}, s.qa, s.qb, w});
    problem.AddResidualBlock(cost, new ceres::CauchyLoss(o.loss_scale), lg[s.a].data(), lg[s.b].data(),
                             beta.data());
  }
  auto* gauge = new GaugeCost;
  auto* gcost = new ceres::DynamicAutoDiffCostFunction<GaugeCost>(gauge);
  std::vector<double*> blocks;
  for (int i = 0; i < n; ++i)
    if (active[i]) {
      gcost->AddParameterBlock(3);
      blocks.push_back(lg[i].data());
    }
  gauge->n = static_cast<int>(blocks.size());
  gcost->SetNumResiduals(3);
  problem.AddResidualBlock(gcost, nullptr, blocks);
  if (!o.estimate_vignetting) problem.SetParameterBlockConstant(beta.data());
  ceres::Solver::Options so;
  solver_options(o, &so);
  so.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  if (!ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE) &&
      !ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::EIGEN_SPARSE))
    so.linear_solver_type = ceres::DENSE_QR;
  ceres::Solver::Summary sum;
  ceres::Solve(so, &problem, &sum);
  if (!sum.IsSolutionUsable())
    throw std::runtime_error("photometric calibration: the solver failed: " + sum.BriefReport());
}

}  // namespace

PhotometricSummary calibrate_photometric(const Rig& rig, const std::vector<std::vector<cv::Mat>>& sets,
                                         const PhotometricOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw std::invalid_argument("photometric calibration: " + why);
  check_sets(rig, sets, "photometric calibration");
  const int n = static_cast<int>(rig.cameras.size());
  if (n < 2) throw std::invalid_argument("photometric calibration: the rig needs at least 2 cameras");
  std::vector<CameraModel> model(n);
  for (int i = 0; i < n; ++i) model[i] = rig.cameras[i].model();

  // 1. Samples from every overlapping pair of every set.
  PhotometricSummary res;
  res.rig = rig;
  std::vector<char> pair_used(size_t(n) * n, 0);
  std::vector<Sample> samples = overlap_samples(rig, model, sets, o, pair_used);
  res.pairs = static_cast<int>(std::count(pair_used.begin(), pair_used.end(), 1));
  const std::vector<char> active = active_cameras(rig, samples, o, res);
  samples.erase(std::remove_if(samples.begin(), samples.end(),
                               [&](const Sample& s) { return !active[s.a] || !active[s.b]; }),
                samples.end());
  res.samples = static_cast<int>(samples.size());
  if (!res.uncalibrated_ids.empty()) {
    std::string ids;
    for (int id : res.uncalibrated_ids) ids += (ids.empty() ? "" : ", ") + std::to_string(id);
    res.warnings.push_back(fmt::format(
        "cameras with fewer than {} usable overlap samples keep unit gains (and the lens's falloff): {}",
        o.min_samples, ids));
    spdlog::warn("photometric: {}", res.warnings.back());
  }

  // 2. Joint fit of the lens falloff and the gains.
  std::vector<std::array<double, 3>> lg(n, {0, 0, 0});
  Lens beta{};
  res.initial_rms_log = rms_log_residual(samples, lg, beta);
  fit_lens_and_gains(samples, active, o, lg, beta);
  res.rms_log = rms_log_residual(samples, lg, beta);
  res.lens = beta;
  for (int i = 0; i < n; ++i) {
    double err = 0;
    const std::array<double, 3> g = {std::exp(lg[i][0]), std::exp(lg[i][1]), std::exp(lg[i][2])};
    res.rig.cameras[i].photometric = photometric_from_lens(rig.cameras[i], beta, g, &err);
    res.max_fit_error = std::max(res.max_fit_error, err);
  }
  try {
    res.rig.validate();
  } catch (const RigError& e) {
    throw std::runtime_error(std::string("photometric calibration gave an invalid model: ") + e.what());
  }
  spdlog::info(
      "photometric: {} samples over {} pairs, RMS {:.4f} -> {:.4f} (log), lens falloff at the corners {:.3f}",
      res.samples, res.pairs, res.initial_rms_log, res.rms_log,
      lens_falloff(beta.data(), 0.78));  // q = 0.78: the corners of the prototype's cameras
  return res;
}

PhotometricSummary calibrate_flat_field(const Rig& rig, const std::vector<std::vector<cv::Mat>>& sets,
                                        const PhotometricOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw std::invalid_argument("flat-field calibration: " + why);
  check_sets(rig, sets, "flat-field calibration");
  const int n = static_cast<int>(rig.cameras.size());
  PhotometricSummary res;
  res.rig = rig;
  res.samples_per_camera.assign(n, 0);
  std::vector<std::array<double, 3>> gain(n);
  std::vector<Lens> beta(n);
  std::vector<std::string> errors(n);
  tbb::parallel_for(0, n, [&](int i) {
    const RigCamera& cam = rig.cameras[i];
    cv::Mat mean;
    for (const auto& set : sets) {
      const cv::Mat lin = decode_linear(set[i]);
      if (mean.empty())
        mean = lin.clone();
      else
        mean += lin;
    }
    mean /= double(sets.size());
    cv::Mat sm;
    cv::GaussianBlur(mean, sm, cv::Size(), std::max(1.0, o.smooth_sigma_px), std::max(1.0, o.smooth_sigma_px),
                     cv::BORDER_REPLICATE);
    const CameraModel m = cam.model();
    // Sum of the channels = A (1 + beta1 q + beta2 q^2 + beta3 q^3): linear in (A, A beta).
    std::vector<std::array<double, 5>> rows;
    int bad = 0;
    const int step = 2;
    for (int r = 1; r < cam.in.height - 1; r += step)
      for (int c = 1; c < cam.in.width - 1; c += step) {
        const cv::Vec3f v = sm.at<cv::Vec3f>(r, c);
        const cv::Vec3f raw = mean.at<cv::Vec3f>(r, c);
        if (std::min({raw[0], raw[1], raw[2]}) < o.min_signal ||
            std::max({raw[0], raw[1], raw[2]}) > o.max_signal) {
          ++bad;
          continue;
        }
        const double q = tan2_angle(m, Vec2(c + 0.5, r + 0.5));
        rows.push_back({q, double(v[0]), double(v[1]), double(v[2]), 0});
      }
    const size_t total = rows.size() + size_t(bad);
    if (rows.size() < total / 2) {
      errors[i] = fmt::format(
          "camera {}: the flat-field frame is too dark or saturated ({} of {} pixels outside [{}, {}] "
          "linear)",
          cam.id, bad, total, o.min_signal, o.max_signal);
      return;
    }
    Eigen::MatrixXd a(Eigen::Index(rows.size()), kLensTerms + 1);
    Eigen::VectorXd y(Eigen::Index(rows.size()));
    for (size_t k = 0; k < rows.size(); ++k) {
      const double q = rows[k][0];
      double qp = 1;
      for (int j = 0; j <= kLensTerms; ++j, qp *= q) a(Eigen::Index(k), j) = qp;
      y(Eigen::Index(k)) = rows[k][1] + rows[k][2] + rows[k][3];
    }
    const Eigen::VectorXd x = a.colPivHouseholderQr().solve(y);
    for (int j = 0; j < kLensTerms; ++j) beta[i][j] = x[j + 1] / x[0];
    // Per channel: the mean of I / V (robust enough for a flat target: the median).
    for (int ch = 0; ch < 3; ++ch) {
      std::vector<double> ratio;
      ratio.reserve(rows.size());
      for (const auto& row : rows) ratio.push_back(row[1 + ch] / lens_falloff(beta[i].data(), row[0]));
      std::nth_element(ratio.begin(), ratio.begin() + ratio.size() / 2, ratio.end());
      gain[i][ch] = ratio[ratio.size() / 2];
    }
    res.samples_per_camera[i] = static_cast<int>(rows.size());
  });
  for (const auto& e : errors)
    if (!e.empty()) throw std::runtime_error("flat-field calibration: " + e);
  // One global scale: the geometric mean of every gain is 1 (the target is white).
  double lsum = 0;
  for (const auto& g : gain)
    for (double v : g) lsum += std::log(v);
  const double scale = std::exp(lsum / (3.0 * n));
  res.lens = {};
  for (int i = 0; i < n; ++i) {
    double err = 0;
    const std::array<double, 3> g = {gain[i][0] / scale, gain[i][1] / scale, gain[i][2] / scale};
    res.rig.cameras[i].photometric = photometric_from_lens(rig.cameras[i], beta[i], g, &err);
    res.max_fit_error = std::max(res.max_fit_error, err);
    for (int k = 0; k < kLensTerms; ++k) res.lens[k] += beta[i][k] / n;
    res.samples += res.samples_per_camera[i];
  }
  try {
    res.rig.validate();
  } catch (const RigError& e) {
    throw std::runtime_error(std::string("flat-field calibration gave an invalid model: ") + e.what());
  }
  return res;
}

}  // namespace omma::calib
