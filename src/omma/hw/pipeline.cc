#include "omma/hw/pipeline.h"

#include <algorithm>
#include <atomic>
#include <stdexcept>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "omma/core/progress.h"
#include "omma/hw/fixed.h"

namespace omma::hw {

std::vector<uint16_t> frame_to_rgb565(const cv::Mat& frame) {
  cv::Mat f = frame;
  if (f.depth() == CV_16U) {  // the 8 most significant bits (§5.2): v >> 8, truncation
    const cv::Mat src = f.isContinuous() ? f : f.clone();
    cv::Mat out(f.size(), CV_8UC(f.channels()));
    const size_t n = src.total() * src.channels();
    const uint16_t* s = src.ptr<uint16_t>();
    uint8_t* d = out.ptr<uint8_t>();
    for (size_t i = 0; i < n; ++i) d[i] = static_cast<uint8_t>(s[i] >> 8);
    f = out;
  }
  if (f.depth() != CV_8U) throw std::invalid_argument("frames must be 8- or 16-bit");
  if (f.channels() == 1) cv::cvtColor(f, f, cv::COLOR_GRAY2BGR);
  if (f.channels() != 3) throw std::invalid_argument("frames must have 1 or 3 channels");
  std::vector<uint16_t> words(static_cast<size_t>(f.rows) * f.cols);
  for (int r = 0; r < f.rows; ++r) {
    const cv::Vec3b* p = f.ptr<cv::Vec3b>(r);
    for (int c = 0; c < f.cols; ++c)
      words[static_cast<size_t>(r) * f.cols + c] = rgb888_to_rgb565(p[c][2], p[c][1], p[c][0]);
  }
  return words;
}

std::vector<cv::Mat> rgb565_frames(const std::vector<cv::Mat>& frames) {
  std::vector<cv::Mat> out;
  for (const auto& f : frames) {
    const std::vector<uint16_t> w = frame_to_rgb565(f);
    cv::Mat m(f.rows, f.cols, CV_8UC3);
    for (int r = 0; r < f.rows; ++r)
      for (int c = 0; c < f.cols; ++c) {
        const auto rgb = rgb565_to_rgb888(w[static_cast<size_t>(r) * f.cols + c]);
        m.at<cv::Vec3b>(r, c) = cv::Vec3b(rgb[2], rgb[1], rgb[0]);
      }
    out.push_back(m);
  }
  return out;
}

Pipeline::Pipeline(const HwConfig& cfg, const Rig& rig, const PanoGrid& grid,
                   const VignettingTables* vignetting)
    : cfg_(cfg), grid_(grid), mem_(cfg, static_cast<int>(rig.cameras.size())) {
  check_rig(cfg_, rig);
  check_grid(cfg_, grid_);
  regs_ = angle_regs(cfg_, grid_);
  cams_ = camera_regs(cfg_, rig);
  rom_ = make_sincos_rom(cfg_);
  vig_ = vignetting ? *vignetting : make_vignetting_tables(cfg_, rig);
  if (vig_.radial.size() != cams_.size() || vig_.channel.size() != cams_.size())
    throw std::invalid_argument("vignetting tables: one table per camera needed");
  for (const auto& t : vig_.radial)
    if (static_cast<int>(t.size()) != cfg_.vig_entries())
      throw std::invalid_argument(
          fmt::format("vignetting tables: {} entries per camera needed (vig_addr_bits)", cfg_.vig_entries()));
}

void Pipeline::load_frames(const std::vector<cv::Mat>& frames) {
  if (frames.size() != cams_.size())
    throw std::invalid_argument(
        fmt::format("{} frames for a rig of {} cameras", frames.size(), cams_.size()));
  for (size_t i = 0; i < frames.size(); ++i) {
    if (frames[i].cols != cams_[i].width || frames[i].rows != cams_[i].height)
      throw std::invalid_argument(fmt::format("frame {} is {}x{}, the rig says {}x{}", i, frames[i].cols,
                                              frames[i].rows, cams_[i].width, cams_[i].height));
    mem_.load(static_cast<int>(i), frame_to_rgb565(frames[i]));
  }
}

ThroughputOptions Pipeline::timing() const {
  ThroughputOptions t;
  t.cameras = static_cast<int>(cams_.size());
  t.max_contributors = std::min(cfg_.max_contributors, t.cameras);
  t.width = grid_.width;
  t.height = grid_.height;
  return t;
}

namespace {

struct Ctx {
  const HwConfig& cfg;
  const AngleRegs& regs;
  const std::vector<CameraRegs>& cams;
  const SinCosRom& rom;
  const VignettingTables& vig;
  const FrameMemory& mem;
  ThroughputOptions timing;
};

Omega omega_at(const Ctx& x, int64_t col, int64_t row) {
  const uint32_t mask = x.cfg.angle_bits >= 32 ? 0xFFFFFFFFu : (uint32_t{1} << x.cfg.angle_bits) - 1;
  Angles a;  // (min + n k) mod 2^M; n may be -1 or N for the MRF neighbours (two's complement wrap)
  a.theta = static_cast<uint32_t>(static_cast<int64_t>(x.regs.theta_min) + row * x.regs.k_theta) & mask;
  a.phi = static_cast<uint32_t>(static_cast<int64_t>(x.regs.phi_min) + col * x.regs.k_phi) & mask;
  return cartesian(x.cfg, x.rom, a, x.regs.axes);
}

// The cameras whose projection of a direction is valid (B4): their ids, pixel positions and B3
// distances, the first n entries used.
struct Contributors {
  int n = 0;
  std::array<int, 8> cam{};
  std::array<PixelPos, 8> pos{};
  std::array<uint32_t, 8> dist{};
};

// Per contributor (up to 8), its samples (R, G, B).
using Samples = std::array<std::array<uint32_t, 3>, 8>;

// The contributors of direction o among the cameras found by the search sr (B4 + B3 distance).
Contributors contributors(const Ctx& x, const Omega& o, const SearchResult& sr) {
  const HwConfig& cfg = x.cfg;
  Contributors ct;
  for (int i = 0; i < sr.count; ++i) {
    const CameraRegs& c = x.cams[sr.camera[i]];
    const PixelPos p = project(cfg, c, o, sr.dot_t[i]);  // B4
    if (!p.valid) continue;
    ct.cam[ct.n] = sr.camera[i];
    ct.pos[ct.n] = p;
    ct.dist[ct.n] = distance_unit(cfg, c.c, o);  // B3 distance
    ++ct.n;
  }
  return ct;
}

// The vignetting-corrected bilinear samples of every contributor (B5 + B6); records the tap
// addresses in `tr` when given.
Samples contributor_samples(const Ctx& x, const Contributors& ct, PixelTrace* tr) {
  const HwConfig& cfg = x.cfg;
  const int n = ct.n;
  const auto& cam = ct.cam;
  const auto& pos = ct.pos;
  // B5 + B6 samples (R, G, B), uQ8.S (or uQ5.S / uQ6.S with expand_at_output)
  Samples smp{};
  const uint32_t max8 = 255;
  for (int i = 0; i < n; ++i) {
    const TapAddress ta = tap_address(cfg, x.cams[cam[i]], cam[i], pos[i]);
    std::array<std::array<uint32_t, 3>, 4> q{};
    for (int k = 0; k < 4; ++k) {
      const uint16_t w = x.mem.read(ta.frame_addr[k]);
      q[k] = cfg.expand_at_output ? rgb565_fields(w) : rgb565_to_rgb888(w);
    }
    for (int ch = 0; ch < 3; ++ch) {
      uint32_t s = bilinear_sample(cfg, {q[0][ch], q[1][ch], q[2][ch], q[3][ch]}, ta.fx, ta.fy);
      const uint32_t g = vignetting_gain(cfg, x.vig, x.cams[cam[i]], cam[i], ta.pixel_x, ta.pixel_y, ch);
      if (g != (1u << 14)) {
        const uint32_t chmax = cfg.expand_at_output ? (ch == 1 ? 63u : 31u) : max8;
        s = static_cast<uint32_t>(
            std::min<int64_t>(rshift_round(int64_t{s} * g, 14), int64_t{chmax} << cfg.sample_frac_bits));
      }
      smp[i][ch] = s;
    }
    if (tr) tr->addr[i] = ta;
  }
  return smp;
}

// The MRF distance products (block float) of the contributors that see all the pixel's grid
// neighbours, written to D; false if none does.
bool mrf_distances(const Ctx& x, int col, int row, const Contributors& ct, std::array<BlockFloat, 8>& D) {
  const HwConfig& cfg = x.cfg;
  const int n = ct.n;
  const auto& cam = ct.cam;
  const auto& dist = ct.dist;
  bool used_mrf = false;
  // Neighbours (left, right, up, down) that exist on the grid.
  const std::array<std::array<int, 2>, 4> nb{
      {{col - 1, row}, {col + 1, row}, {col, row - 1}, {col, row + 1}}};
  std::array<bool, 4> exists{};
  std::array<Omega, 4> onb{};
  for (int k = 0; k < 4; ++k) {
    const int c = nb[k][0], r = nb[k][1];
    exists[k] = r >= 0 && r < x.regs.rows && ((c >= 0 && c < x.regs.cols) || x.regs.wrap_cols);
    if (exists[k]) onb[k] = omega_at(x, c, r);
  }
  for (int i = 0; i < n; ++i) {
    const CameraRegs& c = x.cams[cam[i]];
    BlockFloat p = block_float(cfg, dist[i]);
    bool complete = true;
    for (int k = 0; k < 4 && complete; ++k) {
      if (!exists[k]) continue;
      if (!cone_test(cfg, dot_omega(onb[k], c.t), c.cos_half_aov)) {
        complete = false;
        break;
      }
      p = block_float_mul(cfg, p, distance_unit(cfg, c.c, onb[k]));
    }
    if (complete) {
      D[i] = p;
      used_mrf = true;
    }
  }
  return used_mrf;
}

// The contributors' blend weights for `method`; sets *fallback when MRF falls back to distances.
std::array<uint32_t, 8> blend_weights(const Ctx& x, int col, int row, pano::Method method,
                                      const Contributors& ct, bool* fallback) {
  const HwConfig& cfg = x.cfg;
  // At most 8 contributors (Contributors); the bound is stated for the compiler, which cannot see it.
  const int n = std::min(ct.n, static_cast<int>(ct.dist.size()));
  const auto& dist = ct.dist;
  std::array<uint32_t, 8> w{};
  if (method == pano::Method::kNearest) {
    int best = 0;
    for (int i = 1; i < n; ++i)
      if (dist[i] < dist[best]) best = i;  // strict: the lowest index wins ties
    w[best] = 1;
  } else {
    std::array<BlockFloat, 8> D{};
    bool used_mrf = false;
    if (method == pano::Method::kMrf) {
      used_mrf = mrf_distances(x, col, row, ct, D);
      if (!used_mrf) *fallback = true;
    }
    if (!used_mrf)
      for (int i = 0; i < n; ++i) D[i] = block_float(cfg, dist[i]);
    reciprocal_weights(cfg, D.data(), n, w.data());
  }
  return w;
}

// The blended output pixel (R, G, B), 8 bits per channel (B8 expansion included).
std::array<uint32_t, 3> blended_rgb(const HwConfig& cfg, const std::array<uint32_t, 8>& w, const Samples& smp,
                                    int n) {
  const uint32_t max8 = 255;
  std::array<uint32_t, 3> rgb{};
  for (int ch = 0; ch < 3; ++ch) {
    std::array<uint32_t, 8> s{};
    for (int i = 0; i < n; ++i) s[i] = smp[i][ch];
    const uint32_t chmax = cfg.expand_at_output ? (ch == 1 ? 63u : 31u) : max8;
    rgb[ch] = blend(cfg, w.data(), s.data(), n, chmax);
  }
  if (cfg.expand_at_output) {  // B8 RGB565 -> RGB888 at the output (thesis order)
    rgb = rgb565_to_rgb888(static_cast<uint16_t>((rgb[0] << 11) | (rgb[1] << 5) | rgb[2]));
  }
  return rgb;
}

// One output pixel through every block. Fills `tr` when given.
std::array<uint32_t, 3> process(const Ctx& x, int col, int row, pano::Method method, bool boundary_on,
                                PixelTrace* tr, bool* boundary_hit, bool* fallback, int* n_out,
                                int* cone_out) {
  const HwConfig& cfg = x.cfg;
  const Omega o = omega_at(x, col, row);                  // B1 + B2
  const SearchResult sr = camera_search(cfg, x.cams, o);  // B3
  const Contributors ct = contributors(x, o, sr);
  const int n = ct.n;
  const auto& dist = ct.dist;
  *n_out = n;
  *cone_out = sr.cone_count;
  if (tr) {
    tr->angles = angles_at(cfg, x.regs, col, row);
    tr->omega = o;
    tr->search = sr;
    tr->n = n;
    tr->camera = ct.cam;
    tr->pos = ct.pos;
    tr->dist = dist;
    tr->cycles = pixel_cycles(x.timing, n);
  }
  if (n == 0) return {0, 0, 0};
  const Samples smp = contributor_samples(x, ct, tr);
  // Weights
  const std::array<uint32_t, 8> w = blend_weights(x, col, row, method, ct, fallback);
  std::array<uint32_t, 3> rgb = blended_rgb(cfg, w, smp, n);
  BoundaryResult br;
  if (boundary_on && n >= 2) {  // B7
    std::array<uint32_t, 8> gray{};
    for (int i = 0; i < n; ++i) gray[i] = gray_level(smp[i][0], smp[i][1], smp[i][2]);
    br = boundary_unit(cfg, dist.data(), gray.data(), n);
    if (br.boundary) {
      rgb = {0, 255, 0};
      *boundary_hit = true;
    }
  }
  if (tr) {
    tr->sample = smp;
    tr->weight = w;
    tr->mrf_fallback = *fallback;
    tr->boundary = br;
    tr->rgb = rgb;
  }
  return rgb;
}

void check_method(pano::Method m) {
  if (m != pano::Method::kNearest && m != pano::Method::kLinear && m != pano::Method::kMrf)
    throw std::invalid_argument("the hardware pixel value unit implements nn, linear and mrf (got " +
                                pano::to_string(m) + ")");
}

}  // namespace

PipelineSummary Pipeline::render(pano::Method method, bool boundary, bool progress_on) const {
  check_method(method);
  const Ctx x{cfg_, regs_, cams_, rom_, vig_, mem_, timing()};
  PipelineSummary res;
  res.pano = cv::Mat(grid_.height, grid_.width, CV_8UC3, cv::Scalar::all(0));
  if (boundary) res.boundary = cv::Mat(grid_.height, grid_.width, CV_8UC1, cv::Scalar(0));
  Progress progress("hw pipeline", grid_.height, progress_on);
  struct RowStats {
    PipelineCounters s;
  };
  std::vector<PipelineCounters> rows(grid_.height);
  tbb::parallel_for(tbb::blocked_range<int>(0, grid_.height, 4), [&](const tbb::blocked_range<int>& rr) {
    for (int row = rr.begin(); row < rr.end(); ++row) {
      PipelineCounters& st = rows[row];
      cv::Vec3b* out = res.pano.ptr<cv::Vec3b>(row);
      for (int col = 0; col < grid_.width; ++col) {
        bool hit = false, fb = false;
        int n = 0, cone = 0;
        const auto rgb = process(x, col, row, method, boundary, nullptr, &hit, &fb, &n, &cone);
        out[col] =
            cv::Vec3b(static_cast<uchar>(rgb[2]), static_cast<uchar>(rgb[1]), static_cast<uchar>(rgb[0]));
        st.cycles += pixel_cycles(x.timing, n);
        ++st.contributors[std::min(n, 8)];
        ++st.cone_cameras[std::min(cone, 32)];
        if (cone > cfg_.max_contributors) ++st.dropped_by_encoder;
        if (hit) {
          ++st.boundary_pixels;
          res.boundary.at<uchar>(row, col) = 255;
        }
        if (fb) ++st.mrf_fallback_pixels;
      }
      progress.step();
    }
  });
  progress.finish();
  for (const auto& s : rows) {
    res.stats.cycles += s.cycles;
    for (size_t i = 0; i < s.contributors.size(); ++i) res.stats.contributors[i] += s.contributors[i];
    for (size_t i = 0; i < s.cone_cameras.size(); ++i) res.stats.cone_cameras[i] += s.cone_cameras[i];
    res.stats.dropped_by_encoder += s.dropped_by_encoder;
    res.stats.boundary_pixels += s.boundary_pixels;
    res.stats.mrf_fallback_pixels += s.mrf_fallback_pixels;
  }
  return res;
}

PixelTrace Pipeline::trace(int col, int row, pano::Method method, bool boundary) const {
  check_method(method);
  if (col < 0 || row < 0 || col >= grid_.width || row >= grid_.height)
    throw std::invalid_argument(
        fmt::format("pixel ({}, {}) is outside the {}x{} panorama", col, row, grid_.width, grid_.height));
  const Ctx x{cfg_, regs_, cams_, rom_, vig_, mem_, timing()};
  PixelTrace t;
  bool hit = false, fb = false;
  int n = 0, cone = 0;
  process(x, col, row, method, boundary, &t, &hit, &fb, &n, &cone);
  return t;
}

}  // namespace omma::hw
