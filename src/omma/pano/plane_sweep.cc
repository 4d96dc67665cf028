#include "omma/pano/plane_sweep.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "omma/core/valid.h"
#include "omma/pano/stitch.h"

namespace omma::pano {

bool PlaneSweepOptions::IsValid(std::string* why) const {
  if (!(near_mm > 0 && near_mm <= kMaxSweepMm))
    return invalid(why, fmt::format("near distance must be in (0, {}] mm", kMaxSweepMm));
  if (!(far_mm > near_mm))
    return invalid(why, fmt::format("far distance {} mm must exceed near {} mm", far_mm, near_mm));
  if (!(far_mm <= kMaxSweepMm) && !std::isinf(far_mm))
    return invalid(why, fmt::format("far distance must be at most {} mm, or inf", kMaxSweepMm));
  // far_mm may be +infinity (the last candidate is then the scene at infinity, s = 0)
  if (steps < 2 || steps > kMaxSteps)
    return invalid(why, fmt::format("steps must be 2..{}, got {}", kMaxSteps, steps));
  if (factor < 0 || factor > 64)
    return invalid(why, fmt::format("coarse factor must be 0..64, got {}", factor));
  if (factor == 0 && !(pitch_deg > 0)) return invalid(why, "coarse pitch must be positive");
  if (window < 1 || window > 8) return invalid(why, fmt::format("patch radius must be 1..8, got {}", window));
  if (band_ratio != 0 && !(band_ratio > 1)) return invalid(why, "band-pass ratio must be 0 (none) or > 1");
  if (paths != 4 && paths != 8) return invalid(why, "paths must be 4 or 8");
  if (grid_camera < -1)
    return invalid(why, fmt::format("grid camera must be -1 or an index, got {}", grid_camera));
  if (!(noise_sigma > 0) || !(w0 > 0) || !(p1 >= 0) || !(p2 >= p1) || !(edge_gray > 0) ||
      !(margin_scale > 0) || !(fill_sigma > 0) || !(fill_lambda > 0) || !(prior_mm >= 0) ||
      !(temporal_weight >= 0))
    return invalid(why, "sweep weights must be positive (p2 >= p1)");
  return true;
}

namespace {

// Where camera i sees the surface point of every coarse pixel of `rect` at one candidate depth:
// map_x / map_y in cv::remap's convention (pixel centres at integers), valid = 255 where camera i
// sees the point (eq. 2.3 on its own ray, inside its image).
struct Layer {
  cv::Rect rect;
  cv::Mat map_x, map_y;  // CV_32FC1
  cv::Mat valid;         // CV_8UC1
  bool empty() const { return rect.area() == 0; }
};

// Sums over the (2r+1)^2 window around every pixel (zero outside), separable running sums.
void box_sum(const float* in, int w, int h, int r, float* tmp, float* out) {
  for (int y = 0; y < h; ++y) {
    const float* a = in + size_t(y) * w;
    float* t = tmp + size_t(y) * w;
    double s = 0;
    for (int x = 0; x < std::min(r, w); ++x) s += a[x];
    for (int x = 0; x < w; ++x) {
      if (x + r < w) s += a[x + r];
      t[x] = static_cast<float>(s);
      if (x - r >= 0) s -= a[x - r];
    }
  }
  std::vector<double> s(w, 0.0);
  for (int y = 0; y < std::min(r, h); ++y)
    for (int x = 0; x < w; ++x) s[x] += tmp[size_t(y) * w + x];
  for (int y = 0; y < h; ++y) {
    if (y + r < h)
      for (int x = 0; x < w; ++x) s[x] += tmp[size_t(y + r) * w + x];
    for (int x = 0; x < w; ++x) out[size_t(y) * w + x] = static_cast<float>(s[x]);
    if (y - r >= 0)
      for (int x = 0; x < w; ++x) s[x] -= tmp[size_t(y - r) * w + x];
  }
}

}  // namespace

struct DepthSweep::Impl {
  Rig rig;
  PanoGrid grid, coarse;
  PlaneSweepOptions opt;
  std::vector<Vec3> dirs;     // per coarse pixel
  std::vector<double> inv;    // per candidate, 1/mm
  std::vector<double> sigma;  // per camera: blur to the coarse pitch, camera pixels
  std::vector<int> level;     // per camera: pyramid level the gray levels are computed at (see estimate)
  bool cached = false;
  std::vector<Layer> layers;             // [k * cameras + i] when cached
  std::optional<CameraModel> on_camera;  // the camera grid's camera (plane_sweep.h), if any
  int factor = 1;
  int cams() const { return static_cast<int>(rig.cameras.size()); }
  // Continuous coarse pixel of direction w (from q). On a projection's grid: nullopt outside it. On a
  // camera grid: clamped to the grid's bounds (a footprint that leaves the camera's image still
  // bounds the part inside it), nullopt behind the camera.
  std::optional<Vec2> coarse_pixel(const Vec3& w) const {
    if (!on_camera) return coarse.pixel(w);
    const auto px = on_camera->project(w);
    if (!px) return std::nullopt;
    return Vec2(std::clamp(px->x() / factor, 0.0, coarse.width - 1e-6),
                std::clamp(px->y() / factor, 0.0, coarse.height - 1e-6));
  }

  // Fills L (reusing its buffers).
  void make_layer(int k, int i, Layer& L) const;
  // The phases of estimate(), in order (see plane_sweep.h).
  // Per camera: the gray levels blurred to the coarse pitch, and their band-pass.
  void gray_levels(const std::vector<cv::Mat>& frames, std::vector<cv::Mat>& gray,
                   std::vector<cv::Mat>& band) const;
  // The pair sums num = sum w (1 - ZNCC), den = sum w, candidate-major (K x N); guide = G, the mean
  // gray level of the cameras at the middle candidate.
  void pair_costs(const std::vector<cv::Mat>& gray, const std::vector<cv::Mat>& band, std::vector<float>& num,
                  std::vector<float>& den, cv::Mat& guide) const;
  // The cost C(u, k), pixel-major (N x K), with the unknown candidates continued flat and the
  // temporal term; evidence = the mean sum_ij w_ij per pixel.
  std::vector<float> final_costs(const std::vector<float>& num, const std::vector<float>& den,
                                 const cv::Mat& previous, std::vector<float>& evidence) const;
  // k* refined by the parabola (s_best, 1/mm), the confidence, the median filter.
  void winners(const std::vector<float>& S, const std::vector<float>& evidence, cv::Mat& s_best,
               cv::Mat& conf, std::vector<int>& kbest) const;
  // The prior, the counts at the range's ends, and the fallback: out's coarse fields.
  void fallback(const cv::Mat& s_best, const cv::Mat& conf, const std::vector<int>& kbest,
                DepthEstimate& out) const;
  // depth and confidence on the output grid (bilinear in inverse depth).
  void upsample_to_output(DepthEstimate& out) const;
};

void DepthSweep::Impl::make_layer(int k, int i, Layer& L) const {
  L.rect = cv::Rect();
  const RigCamera& rc = rig.cameras[i];
  const CameraModel cam = rc.model();
  const Vec3 q = opt.search.q;
  const double D = inv[k] > 0 ? 1 / inv[k] : 0;
  // Footprint: rays through a 9 x 9 lattice of the camera's pixels (border included) meet the
  // sphere |X - q| = D; their directions from q bound the rect (with a margin).
  int c0 = coarse.width, r0 = coarse.height, c1 = -1, r1 = -1;
  bool wraps = false;
  std::vector<double> cols;
  for (int a = 0; a <= 8; ++a)
    for (int b = 0; b <= 8; ++b) {
      const Vec3 d = cam.unproject(Vec2(rc.in.width * a / 8.0, rc.in.height * b / 8.0));
      Vec3 w = d;  // at infinity the direction from q is the ray's own
      if (inv[k] > 0) {
        const Vec3 o = rc.position_mm - q;  // |o + t d| = D, t > 0
        const double bb = o.dot(d), cc = o.squaredNorm() - D * D;
        if (cc >= 0) continue;
        const double t = -bb + std::sqrt(bb * bb - cc);
        w = (o + t * d).normalized();
      }
      const auto px = coarse_pixel(w);
      if (!px) continue;
      c0 = std::min(c0, int(std::floor(px->x())));
      c1 = std::max(c1, int(std::floor(px->x())));
      r0 = std::min(r0, int(std::floor(px->y())));
      r1 = std::max(r1, int(std::floor(px->y())));
      cols.push_back(px->x());
    }
  if (c1 < 0) return;
  // On the 360-degree grids a footprint across phi = 0 spans the whole width.
  if (!on_camera && coarse.projection != Projection::kVr180 && c1 - c0 > coarse.width / 2) wraps = true;
  // A footprint around a pole of the grid (its top row, and the bottom row of vr180 and
  // equirect-full, where every column is one direction) spans the whole width down to that row.
  const Vec3 b = q - rc.position_mm;
  auto sees_point = [&](const Vec3& w) {
    const Vec3 ray = (w + inv[k] * b).normalized();
    if (!cam.sees(ray)) return false;
    const auto px = cam.project(ray);
    return px && cam.inside(*px);
  };
  if (!on_camera && sees_point(coarse.direction(0.5 * coarse.width, 0))) {
    wraps = true;
    r0 = 0;
  }
  if (!on_camera && coarse.projection != Projection::kEquirect &&
      sees_point(coarse.direction(0.5 * coarse.width, coarse.height))) {
    wraps = true;
    r1 = coarse.height - 1;
  }
  const int m = 3;
  if (wraps) {
    c0 = 0;
    c1 = coarse.width - 1;
  }
  c0 = std::max(0, c0 - m);
  r0 = std::max(0, r0 - m);
  c1 = std::min(coarse.width - 1, c1 + m);
  r1 = std::min(coarse.height - 1, r1 + m);
  L.rect = cv::Rect(c0, r0, c1 - c0 + 1, r1 - r0 + 1);
  L.map_x.create(L.rect.size(), CV_32FC1);
  L.map_y.create(L.rect.size(), CV_32FC1);
  L.valid.create(L.rect.size(), CV_8UC1);
  const double scale = 1.0 / (1 << level[i]);
  const bool image_field = cam.in.field == Intrinsics::Field::kImage;
  int any = 0;
  for (int r = 0; r < L.rect.height; ++r)
    for (int c = 0; c < L.rect.width; ++c) {
      const Vec3& w = dirs[size_t(r + r0) * coarse.width + (c + c0)];
      const Vec3 ray = (w + inv[k] * b).normalized();  // contributors.h: w + s (q - c_i)
      std::optional<Vec2> px;
      if (image_field)  // sees() is project() inside the image: project once
        px = cam.project(ray);
      else if (cam.sees(ray))
        px = cam.project(ray);
      const bool ok = px && cam.inside(*px);
      L.valid.at<uint8_t>(r, c) = ok ? 255 : 0;
      // cv::remap's convention (centres at integers) at the camera's pyramid level: pyrDown's pixel j
      // is centred on its source's pixel 2j.
      L.map_x.at<float>(r, c) = ok ? static_cast<float>((px->x() - 0.5) * scale) : -1.f;
      L.map_y.at<float>(r, c) = ok ? static_cast<float>((px->y() - 0.5) * scale) : -1.f;
      any += ok;
    }
  if (any == 0) L.rect = cv::Rect();
}

DepthSweep::DepthSweep(const Rig& rig, const PanoGrid& grid, const PlaneSweepOptions& opt)
    : impl_(std::make_unique<Impl>()) {
  std::string why;
  if (!opt.IsValid(&why)) throw std::invalid_argument("depth sweep: " + why);
  if (rig.cameras.empty()) throw std::invalid_argument("depth sweep: the rig has no cameras");
  if (grid.width <= 0 || grid.height <= 0) throw std::invalid_argument("depth sweep: empty grid");
  double inner = 0;
  for (const auto& c : rig.cameras) inner = std::max(inner, (c.position_mm - opt.search.q).norm());
  if (opt.near_mm <= inner)
    throw std::invalid_argument(fmt::format(
        "depth sweep: near distance {} mm lies inside the dome (cameras up to {:.2f} mm from the observer)",
        opt.near_mm, inner));
  Impl& m = *impl_;
  m.rig = rig;
  m.grid = grid;
  m.opt = opt;
  double cam_pitch = 0;  // camera grid: the camera's pixel pitch at its centre, radians
  if (opt.grid_camera >= 0) {
    if (opt.grid_camera >= m.cams())
      throw std::invalid_argument(fmt::format(
          "depth sweep: grid camera {} is not one of the rig's {} cameras", opt.grid_camera, m.cams()));
    const RigCamera& gc = rig.cameras[opt.grid_camera];
    if (grid.width != gc.in.width || grid.height != gc.in.height)
      throw std::invalid_argument(
          fmt::format("depth sweep: on camera {}'s grid the output grid must be its image ({}x{}), got {}x{}",
                      gc.id, gc.in.width, gc.in.height, grid.width, grid.height));
    m.on_camera = gc.model();
    cam_pitch = std::atan(1 / std::max(gc.in.fu, gc.in.fv));
  }
  int factor = opt.factor;
  if (factor == 0) {
    const AngularSpan span = angular_span(grid.projection);
    const double out_pitch =
        m.on_camera ? rad2deg(cam_pitch)
                    : rad2deg(std::max(span.width / grid.width, span.height / grid.height));  // degrees
    factor = std::clamp(static_cast<int>(std::lround(opt.pitch_deg / out_pitch)), 1, 64);
  }
  m.factor = factor;
  m.coarse = PanoGrid{grid.projection, std::max(1, (grid.width + factor / 2) / factor),
                      std::max(1, (grid.height + factor / 2) / factor)};
  m.dirs.resize(size_t(m.coarse.width) * m.coarse.height);
  for (int r = 0; r < m.coarse.height; ++r)
    for (int c = 0; c < m.coarse.width; ++c)
      m.dirs[size_t(r) * m.coarse.width + c] =
          m.on_camera ? m.on_camera->unproject(Vec2((c + 0.5) * factor, (r + 0.5) * factor))
                      : m.coarse.pixel_direction(c, r);
  for (int k = 0; k < opt.steps; ++k) {
    const double t = double(k) / (opt.steps - 1);
    m.inv.push_back((1 - t) / opt.near_mm + t / opt.far_mm);
  }
  // Coarse pitch (rad): the larger of the two axes' spacing.
  const AngularSpan span = angular_span(grid.projection);
  const double pitch =
      m.on_camera ? factor * cam_pitch : std::max(span.width / m.coarse.width, span.height / m.coarse.height);
  for (const auto& c : rig.cameras) {
    m.sigma.push_back(0.5 * pitch * std::max(c.in.fu, c.in.fv));
    // The blur to the coarse pitch makes full resolution unnecessary: each halving (cv::pyrDown, a
    // binomial blur of sigma 1 source pixel) is taken while 2^level stays under sigma / 1.5, so that a
    // blurred pixel still spans under 1/1.5 of the final sigma (the engine's 2 deg grid: level 1).
    int l = 0;
    while (l < 4 && double(2 << l) <= m.sigma.back() / 1.5) ++l;
    m.level.push_back(l);
  }
  // Cache the layers when they are small (the engine's coarse grids); else build them per call.
  // (a footprint holds about 15 % of a projection's grid, and most of a camera grid)
  const double px_per_layer = double(m.coarse.width) * m.coarse.height * (m.on_camera ? 1.0 : 0.15);
  const double bytes = px_per_layer * 9 * opt.steps * m.cams();
  m.cached = bytes < 96e6;
  if (m.cached) {
    m.layers.resize(size_t(opt.steps) * m.cams());
    tbb::parallel_for(0, opt.steps * m.cams(),
                      [&](int ki) { m.make_layer(ki / m.cams(), ki % m.cams(), m.layers[ki]); });
  }
}

DepthSweep::~DepthSweep() = default;
DepthSweep::DepthSweep(DepthSweep&&) noexcept = default;
DepthSweep& DepthSweep::operator=(DepthSweep&&) noexcept = default;
const PanoGrid& DepthSweep::coarse_grid() const { return impl_->coarse; }
const PanoGrid& DepthSweep::grid() const { return impl_->grid; }
const PlaneSweepOptions& DepthSweep::options() const { return impl_->opt; }
double DepthSweep::inverse_depth(int k) const { return impl_->inv.at(k); }

namespace detail {

std::vector<float> aggregate_sgm(const std::vector<float>& C, int W, int H, int K, const cv::Mat& guide,
                                 double p1, double p2, double edge_gray, int paths) {
  const int N = W * H;
  if (W < 1 || H < 1 || K < 1 || C.size() != size_t(N) * K)
    throw std::invalid_argument("aggregate_sgm: the cost volume is not W x H x K");
  if (guide.type() != CV_32FC1 || guide.cols != W || guide.rows != H)
    throw std::invalid_argument("aggregate_sgm: the guide is not a CV_32FC1 image of W x H");
  if (paths != 4 && paths != 8) throw std::invalid_argument("aggregate_sgm: paths must be 4 or 8");
  std::vector<float> S(size_t(N) * K, 0.f);
  const int dirs8[8][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}, {1, 1}, {-1, -1}, {1, -1}, {-1, 1}};
  const float P1 = float(p1);
  auto run_path = [&](int dx, int dy, std::vector<float>& out) {
    std::vector<float> prev(size_t(W) * K), cur(size_t(W) * K);
    std::vector<float> prev_min(W), cur_min(W);
    const int y0 = dy >= 0 ? 0 : H - 1, ys = dy >= 0 ? 1 : -1;
    const int x0 = dx >= 0 ? 0 : W - 1, xs = dx >= 0 ? 1 : -1;
    for (int yi = 0, y = y0; yi < H; ++yi, y += ys) {
      for (int xi = 0, x = x0; xi < W; ++xi, x += xs) {
        const int u = y * W + x;
        const float* c = &C[size_t(u) * K];
        float* L = &cur[size_t(x) * K];
        const int px = x - dx, py = y - dy;
        const bool has = px >= 0 && px < W && py >= 0 && py < H && (dy == 0 || yi > 0);
        float mn = std::numeric_limits<float>::max();
        if (!has) {
          for (int k = 0; k < K; ++k) {
            L[k] = c[k];
            mn = std::min(mn, L[k]);
          }
        } else {
          const float* Lp = dy == 0 ? &cur[size_t(px) * K] : &prev[size_t(px) * K];
          const float mp = dy == 0 ? cur_min[px] : prev_min[px];
          const float dg = std::abs(guide.at<float>(y, x) - guide.at<float>(py, px));
          const float P2 = std::max(P1, float(p2 / (1 + dg / edge_gray)));
          for (int k = 0; k < K; ++k) {
            float best = std::min(Lp[k], mp + P2);
            if (k > 0) best = std::min(best, Lp[k - 1] + P1);
            if (k + 1 < K) best = std::min(best, Lp[k + 1] + P1);
            L[k] = c[k] + best - mp;
            mn = std::min(mn, L[k]);
          }
        }
        cur_min[x] = mn;
        float* o2 = &out[size_t(u) * K];
        for (int k = 0; k < K; ++k) o2[k] += L[k];
      }
      std::swap(prev, cur);
      std::swap(prev_min, cur_min);
    }
  };
  // Paths on two workers, each summing its paths into its own buffer.
  std::vector<float> part(size_t(N) * K, 0.f);
  tbb::parallel_for(0, 2, [&](int g) {
    std::vector<float>& dst = g == 0 ? S : part;
    for (int d = g; d < paths; d += 2) run_path(dirs8[d][0], dirs8[d][1], dst);
  });
  for (size_t t = 0; t < S.size(); ++t) S[t] += part[t];
  return S;
}

}  // namespace detail

namespace {

// Adds one camera pair's term of the cost (see "Cost" in plane_sweep.h) at one candidate:
// num += w_ij (1 - ZNCC_ij), den += w_ij over the coarse pixels both cameras see. li, lj: the two
// layers, vi, vj: their band-pass values; nk, dk: the candidate's rows of num and den (W wide).
// ch, sum, tmp: scratch buffers kept between calls.
void add_pair_cost(const Layer& li, const Layer& lj, const cv::Mat& vi_val, const cv::Mat& vj_val, int r,
                   float win_area, float sn2, int W, float* nk, float* dk, std::vector<float> (&ch)[6],
                   std::vector<float> (&sum)[6], std::vector<float>& tmp) {
  const cv::Rect R = li.rect & lj.rect;
  if (R.area() == 0) return;
  // The pixels both cameras see lie in a box much smaller than the two footprints' common
  // rectangle (which spans the whole width where a footprint wraps round or holds a pole):
  // everything below runs on that box I (outside it the channels are zero).
  int bx0 = R.width, by0 = R.height, bx1 = -1, by1 = -1;
  for (int y = 0; y < R.height; ++y) {
    const uint8_t* vi = li.valid.ptr<uint8_t>(R.y - li.rect.y + y) + (R.x - li.rect.x);
    const uint8_t* vj = lj.valid.ptr<uint8_t>(R.y - lj.rect.y + y) + (R.x - lj.rect.x);
    for (int x = 0; x < R.width; ++x)
      if (vi[x] & vj[x]) {
        bx0 = std::min(bx0, x);
        bx1 = std::max(bx1, x);
        by0 = std::min(by0, y);
        by1 = y;
      }
  }
  if (bx1 < 0) return;
  const cv::Rect I(R.x + bx0, R.y + by0, bx1 - bx0 + 1, by1 - by0 + 1);
  const int w = I.width, h = I.height, n = w * h;
  for (auto& v : ch) v.assign(n, 0.f);
  for (auto& v : sum) v.resize(n);
  tmp.resize(n);
  const cv::Point oi = I.tl() - li.rect.tl(), oj = I.tl() - lj.rect.tl();
  for (int y = 0; y < h; ++y) {
    const uint8_t* vi = li.valid.ptr<uint8_t>(y + oi.y) + oi.x;
    const uint8_t* vj = lj.valid.ptr<uint8_t>(y + oj.y) + oj.x;
    const float* ai = vi_val.ptr<float>(y + oi.y) + oi.x;
    const float* bj = vj_val.ptr<float>(y + oj.y) + oj.x;
    for (int x = 0; x < w; ++x) {
      if (!(vi[x] & vj[x])) continue;
      const float a = ai[x], b = bj[x];
      const int p = y * w + x;
      ch[0][p] = 1;
      ch[1][p] = a;
      ch[2][p] = b;
      ch[3][p] = a * a;
      ch[4][p] = b * b;
      ch[5][p] = a * b;
    }
  }
  for (int c = 0; c < 6; ++c) box_sum(ch[c].data(), w, h, r, tmp.data(), sum[c].data());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int p = y * w + x;
      if (ch[0][p] == 0) continue;
      const float cnt = sum[0][p];
      if (cnt < 0.5f * win_area) continue;
      const float ma = sum[1][p] / cnt, mb = sum[2][p] / cnt;
      const float va = std::max(0.f, sum[3][p] / cnt - ma * ma),
                  vb = std::max(0.f, sum[4][p] / cnt - mb * mb);
      const float cov = sum[5][p] / cnt - ma * mb;
      const float zncc = std::clamp(cov / std::sqrt(va * vb + 1e-12f), -1.f, 1.f);
      const float v = std::min(va, vb);
      const float wt = (cnt / win_area) * (cnt / win_area) * v / (v + sn2);
      const size_t u = size_t(y + I.y) * W + (x + I.x);
      nk[u] += wt * (1 - zncc);
      dk[u] += wt;
    }
}

}  // namespace

void DepthSweep::Impl::gray_levels(const std::vector<cv::Mat>& frames, std::vector<cv::Mat>& gray,
                                   std::vector<cv::Mat>& band) const {
  const int nc = cams();
  gray.assign(nc, cv::Mat());
  band.assign(nc, cv::Mat());
  tbb::parallel_for(0, nc, [&](int i) {
    cv::Mat f = frames[i], g;
    if (f.channels() == 3) cv::cvtColor(f, f, cv::COLOR_BGR2GRAY);  // BT.601 luma
    f.convertTo(g, CV_32F, f.depth() == CV_8U ? 1 / 255.0 : f.depth() == CV_16U ? 1 / 65535.0 : 1.0);
    // sigma (camera pixels) = the pyramid's (pyrDown: sigma^2 = (4^level - 1) / 3) + the rest.
    const int lv = level[i];
    for (int l = 0; l < lv; ++l) cv::pyrDown(g, g);
    const double at = 1.0 / (1 << lv);  // camera pixels -> pixels of the level
    const double rest = std::sqrt(std::max(0.0, sigma[i] * sigma[i] - ((1 << 2 * lv) - 1) / 3.0)) * at;
    if (rest > 0.3) cv::GaussianBlur(g, g, cv::Size(), rest);
    gray[i] = g;
    if (opt.band_ratio > 0) {
      cv::Mat lo;
      cv::GaussianBlur(g, lo, cv::Size(), std::max(1.0, sigma[i]) * opt.band_ratio * at);
      band[i] = g - lo;
    } else {
      band[i] = g;
    }
  });
}

void DepthSweep::Impl::pair_costs(const std::vector<cv::Mat>& gray, const std::vector<cv::Mat>& band,
                                  std::vector<float>& num, std::vector<float>& den, cv::Mat& guide) const {
  const int W = coarse.width, H = coarse.height, K = opt.steps, N = W * H, nc = cams();
  num.assign(size_t(K) * N, 0.f);
  den.assign(size_t(K) * N, 0.f);
  cv::Mat guide_sum(H, W, CV_32FC1, cv::Scalar(0)), guide_n(H, W, CV_32FC1, cv::Scalar(0));
  const int kmid = K / 2;
  const int r = opt.window;
  const float win_area = float((2 * r + 1) * (2 * r + 1));
  const float sn2 = float(opt.noise_sigma * opt.noise_sigma);
  // Candidates in chunks, each with its own buffers kept from one candidate to the next.
  tbb::parallel_for(tbb::blocked_range<int>(0, K), [&](const tbb::blocked_range<int>& range) {
    std::vector<Layer> own(cached ? 0 : nc);
    std::vector<const Layer*> lay(nc);
    std::vector<cv::Mat> val(nc);
    std::vector<float> ch[6], sum[6], tmp;
    for (int k = range.begin(); k != range.end(); ++k) {
      for (int i = 0; i < nc; ++i) {
        if (cached) {
          lay[i] = &layers[size_t(k) * nc + i];
        } else {
          make_layer(k, i, own[i]);
          lay[i] = &own[i];
        }
      }
      for (int i = 0; i < nc; ++i)
        if (!lay[i]->empty())
          cv::remap(band[i], val[i], lay[i]->map_x, lay[i]->map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
      if (k == kmid)
        for (int i = 0; i < nc; ++i) {
          if (lay[i]->empty() || (on_camera && i != opt.grid_camera)) continue;
          cv::Mat gv;
          cv::remap(gray[i], gv, lay[i]->map_x, lay[i]->map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
          cv::Mat gs = guide_sum(lay[i]->rect), gn = guide_n(lay[i]->rect);
          cv::add(gs, gv, gs, lay[i]->valid);
          cv::add(gn, cv::Scalar(1), gn, lay[i]->valid);
        }
      float* nk = num.data() + size_t(k) * N;
      float* dk = den.data() + size_t(k) * N;
      for (int i = 0; i < nc; ++i)
        for (int j = i + 1; j < nc; ++j) {
          if (lay[i]->empty() || lay[j]->empty()) continue;
          add_pair_cost(*lay[i], *lay[j], val[i], val[j], r, win_area, sn2, W, nk, dk, ch, sum, tmp);
        }
    }
  });
  cv::divide(guide_sum, cv::max(guide_n, 1.0), guide);
}

std::vector<float> DepthSweep::Impl::final_costs(const std::vector<float>& num, const std::vector<float>& den,
                                                 const cv::Mat& previous,
                                                 std::vector<float>& evidence) const {
  const int K = opt.steps, N = coarse.width * coarse.height;
  std::vector<float> C(size_t(N) * K);
  evidence.assign(N, 0.f);
  const float w0 = float(opt.w0), neutral = float(opt.neutral_cost);
  const float unknown = float(opt.unknown_cost);
  constexpr float kEvidence = 0.05f;  // pair weight below which a candidate has no evidence
  const double srange = inv.front() - inv.back();
  tbb::parallel_for(0, N, [&](int u) {
    float e = 0;
    const float sp = previous.empty() ? 0.f : previous.ptr<float>()[u];
    // Candidates without evidence (no pair of cameras sees the point there: overlaps shrink as the
    // surface comes nearer) are "unknown", not "bad": they get the best cost among the candidates
    // with evidence, so that the smoothness term decides, not where the overlap happens to begin.
    float best = std::numeric_limits<float>::max();
    for (int k = 0; k < K; ++k) {
      const float d = den[size_t(k) * N + u];
      if (d >= kEvidence) best = std::min(best, num[size_t(k) * N + u] / d);
    }
    const float fill =
        best == std::numeric_limits<float>::max() ? neutral : std::min(neutral, best + unknown);
    // An unknown candidate next to candidates with evidence takes the cost of the nearest of them (in
    // candidate index), at most `fill`: the cost curve is continued flat, so that neither end of the
    // overlap (nearer: overlaps shrink; farther: at infinity the footprints of a far-field scene's
    // cameras part at the edge of the coverage) pulls the winner towards it.
    std::array<float, kMaxSteps> ext;  // on the stack: this runs for every coarse pixel of every frame
    std::fill_n(ext.begin(), K, fill);
    if (best != std::numeric_limits<float>::max()) {
      int below = -1;
      std::array<int, kMaxSteps> nearest;
      std::fill_n(nearest.begin(), K, -1);
      for (int k = 0; k < K; ++k) {
        if (den[size_t(k) * N + u] >= kEvidence) below = k;
        nearest[k] = below;
      }
      int above = -1;
      for (int k = K - 1; k >= 0; --k) {
        if (den[size_t(k) * N + u] >= kEvidence) above = k;
        if (above >= 0 && (nearest[k] < 0 || above - k < k - nearest[k])) nearest[k] = above;
        if (nearest[k] >= 0) {
          const size_t j = size_t(nearest[k]) * N + u;
          ext[k] = std::min(fill, (num[j] + w0 * neutral) / (den[j] + w0));
        }
      }
    }
    for (int k = 0; k < K; ++k) {
      const float d = den[size_t(k) * N + u];
      float c = d >= kEvidence ? (num[size_t(k) * N + u] + w0 * neutral) / (d + w0) : ext[k];
      if (opt.temporal_weight > 0 && sp > 0)
        c += float(opt.temporal_weight * std::min(1.0, std::abs(inv[k] - sp) / srange * (K - 1)));
      C[size_t(u) * K + k] = c;
      e += d;
    }
    evidence[u] = e / K;
  });
  return C;
}

void DepthSweep::Impl::winners(const std::vector<float>& S, const std::vector<float>& evidence,
                               cv::Mat& s_best, cv::Mat& conf, std::vector<int>& kbest) const {
  const int W = coarse.width, H = coarse.height, K = opt.steps, N = W * H;
  s_best.create(H, W, CV_32FC1);
  conf.create(H, W, CV_32FC1);
  kbest.assign(N, 0);
  const double dinv = (inv.back() - inv.front()) / (K - 1);
  tbb::parallel_for(0, N, [&](int u) {
    const float* s = &S[size_t(u) * K];
    int kb = int(std::min_element(s, s + K) - s);
    double kf = kb;
    if (kb > 0 && kb + 1 < K) {
      const double a = s[kb - 1], b = s[kb], c = s[kb + 1], den2 = a - 2 * b + c;
      if (den2 > 1e-9) kf = kb + std::clamp(0.5 * (a - c) / den2, -0.5, 0.5);
    }
    float second = std::numeric_limits<float>::max();
    for (int k = 0; k < K; ++k)
      if (std::abs(k - kb) >= 2) second = std::min(second, s[k]);
    const double margin = second == std::numeric_limits<float>::max() ? 0 : second - s[kb];
    const double e = evidence[u];
    const double c = (1 - std::exp(-margin / (opt.paths * opt.margin_scale))) * e / (e + opt.w0);
    kbest[u] = kb;
    s_best.ptr<float>()[u] = float(inv.front() + kf * dinv);
    conf.ptr<float>()[u] = float(std::clamp(c, 0.0, 1.0));
  });
  if (opt.median > 0) {  // outliers of the winner-take-all (isolated wrong minima)
    cv::Mat med;
    cv::medianBlur(s_best, med, 2 * opt.median + 1);
    s_best = med;
  }
}

void DepthSweep::Impl::fallback(const cv::Mat& s_best, const cv::Mat& conf, const std::vector<int>& kbest,
                                DepthEstimate& out) const {
  const int K = opt.steps, N = coarse.width * coarse.height;
  // Prior: the median confident estimate (or the option), and the ends of the range.
  std::vector<float> good;
  long near_n = 0, far_n = 0;
  for (int u = 0; u < N; ++u)
    if (conf.ptr<float>()[u] > 0.3f) {
      good.push_back(s_best.ptr<float>()[u]);
      near_n += kbest[u] == 0;
      far_n += kbest[u] == K - 1;
    }
  out.confident = long(good.size());
  out.at_near = good.empty() ? 0 : double(near_n) / good.size();
  out.at_far = good.empty() ? 0 : double(far_n) / good.size();
  double s_prior;
  if (opt.prior_mm > 0) {
    s_prior = 1 / opt.prior_mm;
  } else if (!good.empty()) {
    std::nth_element(good.begin(), good.begin() + good.size() / 2, good.end());
    s_prior = good[good.size() / 2];
  } else {
    s_prior = 0.5 * (inv.front() + inv.back());
  }
  out.prior_mm = 1 / s_prior;
  // Fallback by normalised convolution towards the prior.
  cv::Mat cs = conf.mul(s_best), cs_blur, c_blur;
  cv::GaussianBlur(cs, cs_blur, cv::Size(), opt.fill_sigma, opt.fill_sigma, cv::BORDER_REPLICATE);
  cv::GaussianBlur(conf, c_blur, cv::Size(), opt.fill_sigma, opt.fill_sigma, cv::BORDER_REPLICATE);
  cv::Mat fill = (cs_blur + opt.fill_lambda * s_prior) / (c_blur + opt.fill_lambda);
  out.coarse_inverse = conf.mul(s_best) + (1 - conf).mul(fill);
  out.coarse_confidence = conf;
}

void DepthSweep::Impl::upsample_to_output(DepthEstimate& out) const {
  cv::Mat s_up, c_up;
  cv::resize(out.coarse_inverse, s_up, cv::Size(grid.width, grid.height), 0, 0, cv::INTER_LINEAR);
  cv::resize(out.coarse_confidence, c_up, cv::Size(grid.width, grid.height), 0, 0, cv::INTER_LINEAR);
  out.depth.create(s_up.size(), CV_32FC1);
  const float s_min = float(inv.back());
  for (int r = 0; r < s_up.rows; ++r)
    for (int c = 0; c < s_up.cols; ++c) {
      const float s = std::max(s_min, s_up.at<float>(r, c));
      out.depth.at<float>(r, c) = s > 0 ? 1 / s : std::numeric_limits<float>::infinity();
    }
  out.confidence = c_up;
}

DepthEstimate DepthSweep::estimate(const std::vector<cv::Mat>& frames_in, const cv::Mat& previous,
                                   bool upsample) const {
  const Impl& m = *impl_;
  check_frames(m.rig, frames_in);
  const PlaneSweepOptions& o = m.opt;
  const int W = m.coarse.width, H = m.coarse.height;
  if (!previous.empty() && (previous.type() != CV_32FC1 || previous.cols != W || previous.rows != H))
    throw std::invalid_argument("depth sweep: the previous estimate is not on this sweep's coarse grid");
  DepthEstimate out;
  auto t = std::chrono::steady_clock::now();
  auto lap = [&](double& ms) {
    const auto now = std::chrono::steady_clock::now();
    ms = std::chrono::duration<double, std::milli>(now - t).count();
    t = now;
  };
  // Gray levels, blurred to the coarse pitch (the guide of the edge-aware penalty), and their band-pass
  // (minus a blur band_ratio times wider: the signal that is matched).
  std::vector<cv::Mat> gray, band;
  m.gray_levels(frames_in, gray, band);
  lap(out.timing.gray_ms);
  // Cost volume, candidate-major while it is filled: num = sum w (1 - zncc), den = sum w.
  std::vector<float> num, den;
  cv::Mat guide;
  m.pair_costs(gray, band, num, den, guide);
  lap(out.timing.cost_ms);
  // Final cost C(u, k), pixel-major; evidence per pixel.
  std::vector<float> evidence;
  std::vector<float> C = m.final_costs(num, den, previous, evidence);
  num = {};
  den = {};
  // Semi-global aggregation.
  const std::vector<float> S =
      detail::aggregate_sgm(C, W, H, o.steps, guide, o.p1, o.p2, o.edge_gray, o.paths);
  C = {};
  lap(out.timing.aggregate_ms);
  // Winner, sub-candidate refinement, confidence; the fallback towards the prior.
  cv::Mat s_best, conf;
  std::vector<int> kbest;
  m.winners(S, evidence, s_best, conf, kbest);
  m.fallback(s_best, conf, kbest, out);
  if (upsample) m.upsample_to_output(out);
  lap(out.timing.rest_ms);
  return out;
}

double camera_pitch_deg(const Rig& rig) {
  if (rig.cameras.empty()) throw std::invalid_argument("camera pitch: the rig has no cameras");
  double f = 0;
  for (const auto& c : rig.cameras) f = std::max({f, c.in.fu, c.in.fv});
  return rad2deg(std::atan(1 / f));
}

Rig rectified_pair_rig(int width, int height, double focal_px, double baseline_mm) {
  if (!(focal_px > 0) || !(baseline_mm > 0))
    throw std::invalid_argument(fmt::format("rectified pair: focal {} px and baseline {} mm must be positive",
                                            focal_px, baseline_mm));
  Rig rig;
  rig.name = "rectified pair";
  for (int i = 0; i < 2; ++i) {
    RigCamera c;
    c.id = i;
    c.frame.t = Vec3::UnitZ();  // looking along +z, image right +x, image down +y: u x v = t
    c.frame.u = Vec3::UnitX();
    c.frame.v = Vec3::UnitY();
    c.position_mm = Vec3(i * baseline_mm, 0, 0);
    c.in.width = width;
    c.in.height = height;
    c.in.fu = c.in.fv = focal_px;
    c.in.cu = 0.5 * width;
    c.in.cv = 0.5 * height;
    c.in.field = Intrinsics::Field::kImage;
    c.in.aov = c.in.bounding_aov();
    try {
      validate_camera(c);
    } catch (const std::exception& e) {
      throw std::invalid_argument(fmt::format("rectified pair: camera {}: {}", i, e.what()));
    }
    rig.cameras.push_back(c);
  }
  return rig;
}

namespace {
// f B of a rectified_pair_rig (px mm), checked.
double pair_fb(const Rig& pair) {
  if (pair.cameras.size() != 2) throw std::invalid_argument("rectified pair: the rig must have two cameras");
  const double b = (pair.cameras[1].position_mm - pair.cameras[0].position_mm).norm();
  return pair.cameras[0].in.fu * b;
}
}  // namespace

PlaneSweepOptions rectified_sweep_options(const Rig& pair, double d_min, double d_max, double step_px,
                                          PlaneSweepOptions base) {
  const double fb = pair_fb(pair);
  if (!(d_min > 0) || !(d_max > d_min) || !(step_px > 0))
    throw std::invalid_argument(fmt::format(
        "rectified sweep: disparities must satisfy 0 < d_min < d_max and step > 0, got {}..{} by {}", d_min,
        d_max, step_px));
  const CameraModel cam = pair.cameras[0].model();
  double wt_min = 1;  // the smallest w.t over the image: at a corner
  for (double x : {0.0, double(cam.in.width)})
    for (double y : {0.0, double(cam.in.height)}) wt_min = std::min(wt_min, cam.unproject(Vec2(x, y)).z());
  base.grid_camera = 0;
  base.factor = 1;
  base.search.q = pair.cameras[0].position_mm;
  base.near_mm = fb / d_max;
  base.far_mm = fb / (d_min * wt_min);
  const double span = d_max - d_min * wt_min;  // f B (s_near - s_far), px on the axis
  const double steps = std::ceil(span / step_px - 1e-9) + 1;
  if (steps > kMaxSteps)
    throw std::invalid_argument(
        fmt::format("rectified sweep: disparities {}..{} px at {} px steps need {} candidates, more than {}",
                    d_min, d_max, step_px, steps, kMaxSteps));
  base.steps = std::max(2, int(steps));
  std::string why;
  if (!base.IsValid(&why)) throw std::invalid_argument("rectified sweep: " + why);
  return base;
}

cv::Mat disparity_from_depth(const Rig& pair, const cv::Mat& depth_mm) {
  const double fb = pair_fb(pair);
  const CameraModel cam = pair.cameras[0].model();
  if (depth_mm.type() != CV_32FC1 || depth_mm.cols != cam.in.width || depth_mm.rows != cam.in.height)
    throw std::invalid_argument("disparity_from_depth: the depth is not a CV_32FC1 map of the left image");
  cv::Mat d(depth_mm.size(), CV_32FC1);
  for (int r = 0; r < d.rows; ++r)
    for (int c = 0; c < d.cols; ++c) {
      const double D = depth_mm.at<float>(r, c);
      const double wt = cam.unproject(Vec2(c + 0.5, r + 0.5)).dot(cam.frame.t);
      d.at<float>(r, c) = std::isfinite(D) && D > 0 ? float(fb / (D * wt)) : 0.f;
    }
  return d;
}

PlaneSweepOptions stereo_sweep_defaults(int window) {
  PlaneSweepOptions o;
  o.window = window;
  o.band_ratio = 4;
  o.p1 = 0.8;
  o.p2 = 4.0 * window;
  o.edge_gray = 0.1;
  return o;
}

RectifiedDisparity rectified_disparity(const Rig& pair, const cv::Mat& left, const cv::Mat& right,
                                       const PlaneSweepOptions& opt, double lr_tolerance_px) {
  pair_fb(pair);  // checks the rig
  const int W = pair.cameras[0].in.width, H = pair.cameras[0].in.height;
  const PanoGrid grid{Projection::kVr180, W, H};
  PlaneSweepOptions lo = opt, ro = opt;
  lo.grid_camera = 0;
  lo.search.q = pair.cameras[0].position_mm;
  ro.grid_camera = 1;
  ro.search.q = pair.cameras[1].position_mm;
  const cv::Mat dl = disparity_from_depth(pair, DepthSweep(pair, grid, lo).estimate({left, right}).depth);
  // The right sweep's depth is along the right camera's rays; its disparity d = f B / (D (w.t)) with the
  // same intrinsics (disparity_from_depth evaluates w.t on camera 0's pixels, which are the same rays).
  const cv::Mat dr = disparity_from_depth(pair, DepthSweep(pair, grid, ro).estimate({left, right}).depth);
  RectifiedDisparity out;
  out.left_only = dl;
  out.consistent = cv::Mat(H, W, CV_8UC1, cv::Scalar(0));
  for (int r = 0; r < H; ++r)
    for (int c = 0; c < W; ++c) {
      const float d = dl.at<float>(r, c);
      const int xr = int(std::lround(c - d));
      if (xr < 0 || xr >= W) continue;
      if (std::abs(dr.at<float>(r, xr) - d) <= lr_tolerance_px) out.consistent.at<uint8_t>(r, c) = 255;
    }
  out.disparity = dl.clone();
  for (int r = 0; r < H; ++r) {
    const uint8_t* ok = out.consistent.ptr<uint8_t>(r);
    const float* d = dl.ptr<float>(r);
    float* o = out.disparity.ptr<float>(r);
    std::vector<float> from_left(W, -1.f);
    float last = -1.f;
    for (int c = 0; c < W; ++c) {
      if (ok[c]) last = d[c];
      from_left[c] = last;
    }
    last = -1.f;
    for (int c = W - 1; c >= 0; --c) {
      if (ok[c]) {
        last = d[c];
        continue;
      }
      const float a = from_left[c], b = last;
      if (a >= 0 && b >= 0)
        o[c] = std::min(a, b);
      else if (a >= 0 || b >= 0)
        o[c] = std::max(a, b);
    }
  }
  return out;
}

DepthEstimate estimate_depth(const Rig& rig, const std::vector<cv::Mat>& frames, const PanoGrid& grid,
                             const PlaneSweepOptions& opt) {
  return DepthSweep(rig, grid, opt).estimate(frames);
}

}  // namespace omma::pano
