#include "omma/hw/width_sweep.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "omma/core/frames.h"
#include "omma/core/valid.h"
#include "omma/design/svg_plot.h"
#include "omma/hw/pipeline.h"
#include "omma/pano/quality.h"
#include "omma/pano/stitch.h"

namespace omma::hw {

bool WidthSweepOptions::IsValid(std::string* why) const {
  std::string sub;
  if (!base.IsValid(&sub)) return invalid(why, "hardware configuration: " + sub);
  if (grid.width <= 0 || grid.height <= 0) return invalid(why, "panorama size must be positive");
  if (!std::isfinite(target_db)) return invalid(why, "target PSNR must be finite");
  for (const auto& p : params) {
    if (p.values.empty()) return invalid(why, "parameter " + p.name + " has no values");
    if (!std::is_sorted(p.values.begin(), p.values.end()))
      return invalid(why, "the values of parameter " + p.name + " must be ascending");
  }
  return true;
}

namespace {

int* field(HwConfig& c, const std::string& n) {
  if (n == "angle_bits") return &c.angle_bits;
  if (n == "sincos_addr_bits") return &c.sincos_addr_bits;
  if (n == "sincos_word_bits") return &c.sincos_word_bits;
  if (n == "vec_frac_bits") return &c.vec_frac_bits;
  if (n == "pos_frac_bits") return &c.pos_frac_bits;
  if (n == "dist_frac_bits") return &c.dist_frac_bits;
  if (n == "proj_frac_bits") return &c.proj_frac_bits;
  if (n == "k_frac_bits") return &c.k_frac_bits;
  if (n == "focal_frac_bits") return &c.focal_frac_bits;
  if (n == "centre_frac_bits") return &c.centre_frac_bits;
  if (n == "pix_frac_bits") return &c.pix_frac_bits;
  if (n == "sample_frac_bits") return &c.sample_frac_bits;
  if (n == "weight_mant_bits") return &c.weight_mant_bits;
  if (n == "recip_bits") return &c.recip_bits;
  return nullptr;
}

}  // namespace

std::vector<SweepParam> default_sweep_params() {
  auto range = [](int lo, int hi, int step = 1) {
    std::vector<int> v;
    for (int x = lo; x <= hi; x += step) v.push_back(x);
    return v;
  };
  return {{"angle_bits", range(12, 26, 2)},      {"sincos_addr_bits", range(6, 14)},
          {"sincos_word_bits", range(8, 20, 2)}, {"proj_frac_bits", range(6, 16, 2)},
          {"pix_frac_bits", range(2, 8)},        {"dist_frac_bits", range(4, 14, 2)},
          {"vec_frac_bits", range(8, 14, 2)},    {"recip_bits", range(4, 16, 2)},
          {"sample_frac_bits", range(0, 6, 2)},  {"weight_mant_bits", range(6, 20, 2)}};
}

HwConfig with_param(HwConfig c, const std::string& name, int value) {
  int* f = field(c, name);
  if (!f) throw std::invalid_argument("unknown hardware width '" + name + "'");
  *f = value;
  if (name == "proj_frac_bits") c.proj_bits = std::max(c.proj_bits, value + 4);
  if (name == "dist_frac_bits") c.pos_frac_bits = std::min(c.pos_frac_bits, value);
  if (name == "angle_bits") c.sincos_addr_bits = std::min(c.sincos_addr_bits, value - 2);
  if (name == "sincos_addr_bits") c.angle_bits = std::max(c.angle_bits, value + 2);
  if (name == "pix_frac_bits") c.sample_frac_bits = std::min(c.sample_frac_bits, 2 * value);
  return c;
}

int get_param(const HwConfig& cfg, const std::string& name) {
  HwConfig c = cfg;
  const int* f = field(c, name);
  if (!f) throw std::invalid_argument("unknown hardware width '" + name + "'");
  return *f;
}

double psnr_against(const HwConfig& cfg, const Rig& rig, const std::vector<cv::Mat>& frames,
                    const PanoGrid& grid, pano::Method method, const cv::Mat& reference) {
  Pipeline p(cfg, rig, grid);
  p.load_frames(frames);
  return pano::psnr_db(p.render(method, false).pano, reference);
}

WidthSweepSummary run_sweep(const Rig& rig, const std::vector<cv::Mat>& frames, const WidthSweepOptions& o) {
  o.base.Check();
  std::string why;
  if (!o.IsValid(&why)) throw std::invalid_argument("width sweep: " + why);
  pano::StitchOptions so;
  so.method = o.method;
  so.grid = o.grid;
  so.progress = false;
  const cv::Mat ref = to_u8(pano::stitch(rig, rgb565_frames(frames), so));
  WidthSweepSummary r;
  auto eval = [&](const HwConfig& c, const std::string& what) {
    if (o.progress) o.progress(what);
    return psnr_against(c, rig, frames, o.grid, o.method, ref);
  };
  r.base_psnr_db = eval(o.base, "base");
  for (const SweepParam& p : o.params) {
    for (int v : p.values) {
      SweepPoint pt{p.name, v, 0, true};
      try {
        const HwConfig c = with_param(o.base, p.name, v);
        c.Check();
        check_rig(c, rig);
        check_grid(c, o.grid);
        pt.psnr_db = eval(c, fmt::format("{} = {}", p.name, v));
      } catch (const std::invalid_argument&) {
        pt.valid = false;
        pt.psnr_db = std::nan("");
      }
      r.points.push_back(pt);
    }
  }
  // Smallest set. Errors of independent widths add as noise powers: with MSE_base the base
  // configuration's and MSE_target the target's, each of the n parameters may add at most
  // (MSE_target - MSE_base) / n. Take each parameter's smallest value within its share, then raise
  // the parameter with the largest single-step gain until the combination meets the target.
  auto mse = [](double db) { return std::pow(10.0, -db / 10); };
  const double share = (mse(o.target_db) - mse(r.base_psnr_db)) / std::max<size_t>(1, o.params.size());
  HwConfig m = o.base;
  for (const SweepParam& p : o.params) {
    int best = get_param(o.base, p.name), alone = best;
    for (const auto& pt : r.points) {
      if (pt.param != p.name || !pt.valid) continue;
      if (pt.psnr_db >= o.target_db) alone = std::min(alone, pt.value);
      if (mse(pt.psnr_db) - mse(r.base_psnr_db) <= share) best = std::min(best, pt.value);
    }
    m = with_param(m, p.name, best);
    r.minimal_steps.push_back(fmt::format("{}: smallest alone {}, within its share {}", p.name, alone, best));
  }
  double psnr = eval(m, "minimal set");
  for (int iter = 0; iter < 32 && psnr < o.target_db; ++iter) {
    double best_gain = -1e9;
    std::string best_name;
    HwConfig best_cfg = m;
    for (const SweepParam& p : o.params) {
      const int cur = get_param(m, p.name);
      auto next = std::upper_bound(p.values.begin(), p.values.end(), cur);
      if (next == p.values.end()) continue;
      HwConfig c = with_param(m, p.name, *next);
      try {
        c.Check();
        const double q = eval(c, fmt::format("minimal set, {} = {}", p.name, *next));
        if (q - psnr > best_gain) best_gain = q - psnr, best_name = p.name, best_cfg = c;
      } catch (const std::invalid_argument&) {
      }
    }
    if (best_name.empty()) break;
    m = best_cfg;
    psnr += best_gain;
    r.minimal_steps.push_back(
        fmt::format("raised {} to {}: {:.2f} dB", best_name, get_param(m, best_name), psnr));
  }
  // Then lower one width at a time (the one whose step down costs least) while the target holds.
  for (int iter = 0; iter < 64 && psnr >= o.target_db; ++iter) {
    double best_q = -1;
    std::string best_name;
    HwConfig best_cfg = m;
    for (const SweepParam& p : o.params) {
      const int cur = get_param(m, p.name);
      auto it = std::lower_bound(p.values.begin(), p.values.end(), cur);
      if (it == p.values.begin()) continue;
      HwConfig c = with_param(m, p.name, *std::prev(it));
      try {
        c.Check();
        const double q = eval(c, fmt::format("minimal set, {} = {}", p.name, *std::prev(it)));
        if (q >= o.target_db && q > best_q) best_q = q, best_name = p.name, best_cfg = c;
      } catch (const std::invalid_argument&) {
      }
    }
    if (best_name.empty()) break;
    m = best_cfg;
    psnr = best_q;
    r.minimal_steps.push_back(
        fmt::format("lowered {} to {}: {:.2f} dB", best_name, get_param(m, best_name), psnr));
  }
  r.minimal = m;
  r.minimal_psnr_db = psnr;
  return r;
}

std::string sweep_csv(const WidthSweepSummary& r, double target_db) {
  std::string s = "param,value,psnr_db,meets_target\n";
  for (const auto& p : r.points)
    s +=
        fmt::format("{},{},{},{}\n", p.param, p.value, p.valid ? fmt::format("{:.3f}", p.psnr_db) : "invalid",
                    p.valid && p.psnr_db >= target_db ? 1 : 0);
  return s;
}

std::string sweep_svg(const WidthSweepSummary& r, double target_db) {
  std::vector<design::Plot> plots;
  std::vector<std::string> names;
  for (const auto& p : r.points)
    if (std::find(names.begin(), names.end(), p.param) == names.end()) names.push_back(p.param);
  for (const auto& n : names) {
    design::Plot pl;
    pl.title = n;
    pl.x_label = "bits";
    pl.y_label = "PSNR vs float (dB)";
    design::PlotSeries s{"pipeline", "#1f77b4", {}, {}, false},
        t{fmt::format("{} dB", target_db), "#d62728", {}, {}, false};
    for (const auto& p : r.points)
      if (p.param == n) {
        s.x.push_back(p.value);
        s.y.push_back(p.valid ? std::min(p.psnr_db, 99.0) : std::nan(""));
      }
    if (!s.x.empty()) t.x = {s.x.front(), s.x.back()}, t.y = {target_db, target_db};
    pl.series = {s, t};
    plots.push_back(pl);
  }
  return design::svg_plot_grid(plots, 3,
                               "omma hw sweep: PSNR of the bit-accurate pipeline against the float stitch");
}

}  // namespace omma::hw
