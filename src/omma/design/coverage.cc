#include "omma/design/coverage.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <opencv2/imgproc.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "omma/design/dome.h"

namespace omma::design {
namespace {

// Per-camera constants of the cone test, precomputed once.
struct Cone {
  Vec3 p, t;
  double c = 0, s = 0;  // cos and sin of the half angle of view
  double c2 = 0;
  bool radial = false;  // p = rho t with rho >= 0
  double rho = 0;
  bool image = false;  // rectangular field (Intrinsics::Field::kImage): the pyramid below
  Vec3 n[4];           // inward normals of the planes through p and the image edges
};

// at_infinity: the cameras' positions do not matter (the pinholes collapse to the centre).
std::vector<Cone> make_cones(const Rig& rig, bool at_infinity = false) {
  std::vector<Cone> cones;
  for (const RigCamera& cam : rig.cameras) {
    Cone k;
    k.p = at_infinity ? Vec3::Zero() : cam.position_mm;
    k.t = cam.frame.t.normalized();
    k.c = std::cos(cam.in.aov / 2);
    k.s = std::sin(cam.in.aov / 2);
    k.c2 = k.c * k.c;
    k.rho = k.p.dot(k.t);
    k.radial = k.rho >= 0 && (k.p - k.rho * k.t).norm() <= 1e-9 * (1 + k.p.norm());
    if (cam.in.field == Intrinsics::Field::kImage) {
      // d = X - p is inside when x = d.u / d.t lies in [xl, xr] and y = d.v / d.t in [yt, yb]
      // (normalised coordinates of the image edges, undistorted): four half-spaces n . d >= 0.
      const Intrinsics& in = cam.in;
      const Vec2 tl = undistort(in.k, Vec2(-in.cu / in.fu, -in.cv / in.fv));
      const Vec2 br = undistort(in.k, Vec2((in.width - in.cu) / in.fu, (in.height - in.cv) / in.fv));
      const Frame& f = cam.frame;
      k.image = true;
      k.n[0] = f.u - tl.x() * f.t;
      k.n[1] = br.x() * f.t - f.u;
      k.n[2] = f.v - tl.y() * f.t;
      k.n[3] = br.y() * f.t - f.v;
    }
    cones.push_back(k);
  }
  return cones;
}

inline bool sees(const Cone& k, const Vec3& X) {
  const Vec3 d = X - k.p;
  const double dt = d.dot(k.t);
  if (k.image) {
    const double tol = -1e-12 * d.norm();
    return dt > 0 && k.n[0].dot(d) >= tol && k.n[1].dot(d) >= tol && k.n[2].dot(d) >= tol &&
           k.n[3].dot(d) >= tol;
  }
  // Inclusive cone (relative tolerance 1e-9): a point exactly on the rim, e.g. at R_vir, is seen.
  return dt >= 0 && dt * dt >= k.c2 * d.squaredNorm() * (1 - 1e-9);
}

struct Interval {
  double lo, hi;
};

// The distances R >= 0 at which R w lies in cone k: at most two intervals (the cone is convex, so
// in fact at most one; two guard against rounding at a touching point).
int cone_intervals(const Cone& k, const Vec3& w, std::array<Interval, 3>& out) {
  const double a = w.dot(k.t);
  if (k.image) {
    // The pyramid is convex: every half-space n . (R w - p) >= 0 bounds R on one side.
    double lo = 0, hi = kInfinity;
    auto half = [&](const Vec3& n, bool strict) {
      const double an = n.dot(w), bn = n.dot(k.p);
      if (an > 0)
        lo = std::max(lo, bn / an);
      else if (an < 0)
        hi = std::min(hi, bn / an);
      else if (bn > 0 || (strict && bn >= 0))
        hi = -1;  // never (or only at R where it is 0)
    };
    half(k.t, true);
    for (const Vec3& n : k.n) half(n, false);
    if (!(lo <= hi) || (std::isinf(hi) && a <= 0)) return 0;
    out[0] = {lo, hi};
    return 1;
  }
  if (k.radial) {
    if (a <= k.c) return 0;  // angle(w, t) >= h: the ray never enters the cone (see header)
    if (k.rho <= 0) {
      out[0] = {0, kInfinity};
      return 1;
    }
    const double sin_h_minus = k.s * a - k.c * std::sqrt(std::max(0.0, 1 - a * a));
    out[0] = {k.rho * k.s / sin_h_minus, kInfinity};  // eq. 3.1 solved for R_vir
    return 1;
  }
  // General camera: seen iff g(R) = a R - b >= 0 and f(R) = A R^2 - 2 B R + C >= 0.
  const double b = k.p.dot(k.t), e = w.dot(k.p), q = k.p.squaredNorm();
  const double A = a * a - k.c2, B = a * b - k.c2 * e, C = b * b - k.c2 * q;
  std::array<double, 5> br{};
  int n = 0;
  br[n++] = 0;
  if (a > 0 && b / a > 0) br[n++] = b / a;
  if (std::abs(A) > 1e-15) {
    const double disc = B * B - A * C;
    if (disc >= 0) {
      const double r = std::sqrt(disc);
      for (double x : {(B - r) / A, (B + r) / A})
        if (x > 0) br[n++] = x;
    }
  } else if (std::abs(B) > 1e-15) {
    const double x = C / (2 * B);
    if (x > 0) br[n++] = x;
  }
  for (int i = 1; i < n; ++i)  // insertion sort of at most 4 breakpoints
    for (int j = i; j > 0 && br[j] < br[j - 1]; --j) std::swap(br[j], br[j - 1]);
  auto inside = [&](double R) {
    const double g = a * R - b;
    return g >= 0 && (A * R - 2 * B) * R + C >= -1e-12 * (1 + R * R);
  };
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const double lo = br[i];
    const bool last = i + 1 == n;
    const double hi = last ? kInfinity : br[i + 1];
    const double mid = last ? 2 * lo + 1 : 0.5 * (lo + hi);
    if (!inside(mid)) continue;
    if (m > 0 && out[m - 1].hi >= lo) {
      out[m - 1].hi = hi;
    } else if (m < 3) {
      out[m++] = {lo, hi};
    }
  }
  return m;
}

double covered_from_cones(const std::vector<Cone>& cones, const Vec3& w) {
  // Radial cameras only give unbounded intervals; general ones may add bounded pieces.
  double r = kInfinity;
  std::array<Interval, 3> iv;
  std::vector<Interval> bounded;
  for (const Cone& k : cones) {
    const int n = cone_intervals(k, w, iv);
    for (int i = 0; i < n; ++i) {
      if (std::isinf(iv[i].hi))
        r = std::min(r, iv[i].lo);
      else
        bounded.push_back(iv[i]);
    }
  }
  for (bool changed = !bounded.empty(); changed;) {
    changed = false;
    for (const Interval& b : bounded)
      if (b.lo < r && b.hi >= r) {
        r = b.lo;
        changed = true;
      }
  }
  return r;
}

}  // namespace

double Sampling::theta(int row) const { return std::min(row * step_rad, theta_max()); }

Vec3 Sampling::direction(int row, int col) const { return direction_from_spherical(theta(row), phi(col)); }

double Sampling::weight(int row) const {
  const double lo = row == 0 ? 0.0 : 0.5 * (theta(row - 1) + theta(row));
  const double hi = row + 1 >= rows ? theta_max() : 0.5 * (theta(row) + theta(row + 1));
  return 2 * kPi * (std::cos(lo) - std::cos(hi)) / cols;
}

Sampling make_sampling(double step_rad, bool sphere, double theta_limit) {
  if (!(step_rad > 0) || step_rad > deg2rad(45))
    throw std::invalid_argument("coverage step must be in (0, 45] degrees");
  if (!(theta_limit >= 0 && theta_limit <= kPi))
    throw std::invalid_argument("coverage polar limit must be in (0, 180] degrees");
  Sampling s;
  s.step_rad = step_rad;
  s.sphere = sphere;
  s.theta_limit = theta_limit;
  s.rows = static_cast<int>(std::ceil(s.theta_max() / step_rad - 1e-9)) + 1;
  s.cols = std::max(1, static_cast<int>(std::lround(2 * kPi / step_rad)));
  for (int k = 0; k < s.cols; ++k) {
    s.cos_phi.push_back(std::cos(s.phi(k)));
    s.sin_phi.push_back(std::sin(s.phi(k)));
  }
  return s;
}

bool camera_sees_point(const RigCamera& cam, const Vec3& X) {
  const Vec3 d = X - cam.position_mm;
  if (d.norm() == 0) return true;
  if (cam.in.field == Intrinsics::Field::kImage) return cam.model().sees(d);  // the image bounds
  // Reference form of the cone test: angle(X - p, t) <= aov / 2.
  return angle_between(d, cam.frame.t) <= cam.in.aov / 2;
}

int cameras_seeing(const Rig& rig, const Vec3& w, double distance_mm) {
  int n = 0;
  for (const RigCamera& cam : rig.cameras) {
    if (std::isinf(distance_mm)) {
      RigCamera at_centre = cam;
      at_centre.position_mm = Vec3::Zero();
      n += camera_sees_point(at_centre, w);
    } else {
      n += camera_sees_point(cam, distance_mm * w);
    }
  }
  return n;
}

double covered_from(const Rig& rig, const Vec3& w) {
  return covered_from_cones(make_cones(rig), w.normalized());
}

namespace {

struct RowResult {
  int min_count = std::numeric_limits<int>::max(), max_count = 0;
  double weighted_count = 0, covered_weight = 0, max_covered_from = 0;
  std::vector<double> by_count;  // solid angle seen by exactly n cameras
};

// One pass over the sampling: counts at `distance` (if count) and R_vir (if rvir).
std::vector<RowResult> scan(const Rig& rig, const Sampling& s, double distance, bool count, bool rvir) {
  const bool inf = std::isinf(distance);
  const std::vector<Cone> cones = make_cones(rig, inf && !rvir);
  const std::vector<double>& cphi = s.cos_phi;
  const std::vector<double>& sphi = s.sin_phi;
  std::vector<RowResult> rows(s.rows);
  tbb::parallel_for(tbb::blocked_range<int>(0, s.rows), [&](const tbb::blocked_range<int>& range) {
    for (int j = range.begin(); j != range.end(); ++j) {
      const double th = s.theta(j), st = std::sin(th), ct = std::cos(th);
      const double wgt = s.weight(j);
      RowResult r;
      r.by_count.assign(cones.size() + 1, 0.0);
      // At the poles every phi gives the same direction: one sample stands for the row.
      const int ncols = (st < 1e-12) ? 1 : s.cols;
      const double scale = static_cast<double>(s.cols) / ncols;
      for (int k = 0; k < ncols; ++k) {
        const Vec3 w(st * cphi[k], st * sphi[k], ct);
        if (count) {
          const Vec3 X = inf ? w : Vec3(distance * w);
          int n = 0;
          for (const Cone& c : cones) n += sees(c, X);
          r.by_count[n] += wgt * scale;
          r.min_count = std::min(r.min_count, n);
          r.max_count = std::max(r.max_count, n);
          r.weighted_count += wgt * scale * n;
          if (n > 0) r.covered_weight += wgt * scale;
        }
        if (rvir) r.max_covered_from = std::max(r.max_covered_from, covered_from_cones(cones, w));
      }
      rows[j] = r;
    }
  });
  return rows;
}

}  // namespace

CoverageSummary analyze_coverage(const Rig& rig, double distance_mm, double step_rad, double theta_max_rad) {
  if (!(distance_mm > 0)) throw std::invalid_argument("coverage distance must be > 0 mm");
  const Sampling s = make_sampling(step_rad, rig.dome.sphere, theta_max_rad);
  // At infinity the counts use directions only; R_vir needs the positions (a second scan).
  const bool inf = std::isinf(distance_mm);
  const auto rows = scan(rig, s, distance_mm, true, !inf);
  CoverageSummary st;
  st.distance_mm = distance_mm;
  st.step_deg = rad2deg(step_rad);
  st.theta_max_deg = rad2deg(s.theta_max());
  st.min_cameras = std::numeric_limits<int>::max();
  st.solid_angle_by_count.assign(rig.cameras.size() + 1, 0.0);
  double total = 0, covered = 0, weighted = 0;
  for (int j = 0; j < s.rows; ++j) {
    const RowResult& r = rows[j];
    st.min_cameras = std::min(st.min_cameras, r.min_count);
    st.max_cameras = std::max(st.max_cameras, r.max_count);
    weighted += r.weighted_count;
    covered += r.covered_weight;
    total += s.weight(j) * s.cols;
    st.r_virtual_mm = std::max(st.r_virtual_mm, r.max_covered_from);
    for (size_t n = 0; n < r.by_count.size(); ++n) st.solid_angle_by_count[n] += r.by_count[n];
    st.row_theta_rad.push_back(s.theta(j));
    st.row_min.push_back(r.min_count);
    st.row_max.push_back(r.max_count);
  }
  if (inf)
    for (const RowResult& r : scan(rig, s, 1.0, false, true))
      st.r_virtual_mm = std::max(st.r_virtual_mm, r.max_covered_from);
  // Exactly 1 when no sample has a gap (the weighted sum itself carries rounding).
  st.covered_fraction = st.min_cameras >= 1 ? 1.0 : covered / total;
  st.mean_cameras = weighted / total;
  return st;
}

double CoverageSummary::solid_angle_at_least(int n) const {
  double a = 0;
  for (size_t k = std::max(0, n); k < solid_angle_by_count.size(); ++k) a += solid_angle_by_count[k];
  return a;
}

PolarBand CoverageSummary::polar_band(int n) const {
  PolarBand best;
  size_t best_len = 0;
  for (size_t j = 0; j < row_min.size();) {
    if (row_min[j] < n) {
      ++j;
      continue;
    }
    size_t e = j;
    PolarBand b;
    b.min_cameras = row_min[j];
    while (e < row_min.size() && row_min[e] >= n) {
      b.min_cameras = std::min(b.min_cameras, row_min[e]);
      b.max_cameras = std::max(b.max_cameras, row_max[e]);
      ++e;
    }
    if (e - j > best_len) {
      best_len = e - j;
      best = b;
      best.from_rad = row_theta_rad[j];
      best.to_rad = row_theta_rad[e - 1];
    }
    j = e;
  }
  return best;
}

double virtual_radius(const Rig& rig, double step_rad) {
  const Sampling s = make_sampling(step_rad, rig.dome.sphere);
  double r = 0;
  for (const RowResult& row : scan(rig, s, 1.0, false, true)) r = std::max(r, row.max_covered_from);
  return r;
}

double virtual_radius_bisection(const Rig& rig, double step_rad, double tol_mm, double hi_mm) {
  const Sampling s = make_sampling(step_rad, rig.dome.sphere);
  auto all_covered = [&](double R) {
    for (int j = 0; j < s.rows; ++j)
      for (int k = 0; k < s.cols; ++k)
        if (cameras_seeing(rig, s.direction(j, k), R) == 0) return false;
    return true;
  };
  if (!all_covered(hi_mm)) return kInfinity;
  double lo = 0, hi = hi_mm;
  while (hi - lo > tol_mm) {
    const double mid = 0.5 * (lo + hi);
    (all_covered(mid) ? hi : lo) = mid;
  }
  return hi;
}

cv::Mat coverage_count_map(const Rig& rig, const PanoGrid& grid, double distance_mm) {
  const bool inf = std::isinf(distance_mm);
  const std::vector<Cone> cones = make_cones(rig, inf);
  cv::Mat counts(grid.height, grid.width, CV_32SC1);
  tbb::parallel_for(0, grid.height, [&](int row) {
    int* out = counts.ptr<int>(row);
    for (int col = 0; col < grid.width; ++col) {
      const Vec3 w = grid.pixel_direction(col, row);
      const Vec3 X = inf ? w : Vec3(distance_mm * w);
      int n = 0;
      for (const Cone& c : cones) n += sees(c, X);
      out[col] = n;
    }
  });
  return counts;
}

cv::Vec3b coverage_color(int count, int max_count) {
  if (count <= 0) return {0, 0, 0};
  static const cv::Mat lut = [] {
    cv::Mat ramp(1, 256, CV_8UC1);
    for (int i = 0; i < 256; ++i) ramp.at<uchar>(0, i) = static_cast<uchar>(i);
    cv::Mat colored;
    cv::applyColorMap(ramp, colored, cv::COLORMAP_TURBO);
    return colored;
  }();
  const int m = std::max(max_count, 2);
  const int index = 40 + static_cast<int>(std::lround(200.0 * (count - 1) / (m - 1)));
  return lut.at<cv::Vec3b>(0, std::clamp(index, 0, 255));
}

cv::Mat render_coverage_map(const cv::Mat& counts, const std::string& title) {
  if (counts.empty() || counts.type() != CV_32SC1)
    throw std::invalid_argument("render_coverage_map: expects a non-empty CV_32SC1 count map");
  double maxv = 0;
  cv::minMaxLoc(counts, nullptr, &maxv);
  const int max_count = static_cast<int>(maxv);
  const int W = std::max(counts.cols, 480);
  const double font = std::clamp(W / 1400.0, 0.45, 1.2);
  const int line = static_cast<int>(std::lround(30 * font / 0.6));
  const int legend_h = 3 * line;
  cv::Mat out(counts.rows + legend_h, W, CV_8UC3, cv::Scalar(40, 40, 40));
  for (int r = 0; r < counts.rows; ++r)
    for (int c = 0; c < counts.cols; ++c)
      out.at<cv::Vec3b>(r, c) = coverage_color(counts.at<int>(r, c), max_count);
  const int y0 = counts.rows;
  cv::putText(out, title, {line / 2, y0 + line}, cv::FONT_HERSHEY_SIMPLEX, font, cv::Scalar(255, 255, 255), 1,
              cv::LINE_AA);
  int x = line / 2;
  const int sw = static_cast<int>(0.7 * line);
  cv::putText(out, "cameras:", {x, y0 + 2 * line + sw / 2}, cv::FONT_HERSHEY_SIMPLEX, font,
              cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  x += static_cast<int>(5.5 * line * font / 0.6 * 0.6) + line;
  for (int n = 0; n <= max_count && x + 3 * line < W; ++n) {
    const cv::Vec3b col = coverage_color(n, max_count);
    cv::rectangle(out, cv::Rect(x, y0 + 2 * line - sw / 2, sw, sw), cv::Scalar(col[0], col[1], col[2]),
                  cv::FILLED);
    cv::rectangle(out, cv::Rect(x, y0 + 2 * line - sw / 2, sw, sw), cv::Scalar(200, 200, 200), 1);
    const std::string label = n == 0 ? "0 (gap)" : std::to_string(n);
    cv::putText(out, label, {x + sw + 4, y0 + 2 * line + sw / 2}, cv::FONT_HERSHEY_SIMPLEX, font,
                cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
    x += sw + 8 + static_cast<int>((n == 0 ? 4.5 : 1.6) * line * font / 0.6 * 0.6) + line / 2;
  }
  return out;
}

double covering_radius(const std::vector<Vec3>& axes, const Sampling& s) {
  if (axes.empty()) return kPi;
  std::vector<double> row_min(s.rows, 1.0);
  const std::vector<double>& cphi = s.cos_phi;
  const std::vector<double>& sphi = s.sin_phi;
  tbb::parallel_for(tbb::blocked_range<int>(0, s.rows), [&](const tbb::blocked_range<int>& range) {
    for (int j = range.begin(); j != range.end(); ++j) {
      const double th = s.theta(j), st = std::sin(th), ct = std::cos(th);
      const int ncols = (st < 1e-12) ? 1 : s.cols;
      double worst = 1.0;
      for (int k = 0; k < ncols; ++k) {
        const Vec3 w(st * cphi[k], st * sphi[k], ct);
        double best = -1.0;
        for (const Vec3& a : axes) best = std::max(best, w.dot(a));
        worst = std::min(worst, best);
      }
      row_min[j] = worst;
    }
  });
  return std::acos(std::clamp(*std::min_element(row_min.begin(), row_min.end()), -1.0, 1.0));
}

namespace {

// Index of an axis within reach of w (cos_reach = cos(reach)), or -1. Tries `hint` first: the
// neighbouring sample is usually covered by the same axis.
inline int find_cover(const std::vector<Vec3>& axes, const Vec3& w, double cos_reach, int hint) {
  if (hint >= 0 && w.dot(axes[hint]) >= cos_reach) return hint;
  for (size_t i = 0; i < axes.size(); ++i)
    if (w.dot(axes[i]) >= cos_reach) return static_cast<int>(i);
  return -1;
}

// First row (from the pole) with an uncovered sample, or s.rows; rows scanned in order.
int first_uncovered_row(const std::vector<Vec3>& axes, const Sampling& s, double reach, int from_row) {
  if (axes.empty()) return 0;
  const double cr = std::cos(reach);
  int hint = -1;
  for (int j = std::max(0, from_row); j < s.rows; ++j) {
    const double th = s.theta(j), st = std::sin(th), ct = std::cos(th);
    const int ncols = (st < 1e-12) ? 1 : s.cols;
    for (int k = 0; k < ncols; ++k) {
      const Vec3 w(st * s.cos_phi[k], st * s.sin_phi[k], ct);
      hint = find_cover(axes, w, cr, hint);
      if (hint < 0) return j;
    }
  }
  return s.rows;
}

}  // namespace

bool covers(const std::vector<Vec3>& axes, const Sampling& s, double reach) {
  return first_uncovered_row(axes, s, reach, 0) == s.rows;
}

double first_uncovered_theta(const std::vector<Vec3>& axes, const Sampling& s, double reach,
                             double from_theta) {
  const int from = std::isinf(from_theta) ? s.rows : static_cast<int>(std::floor(from_theta / s.step_rad));
  const int j = first_uncovered_row(axes, s, reach, std::min(from, s.rows));
  return j == s.rows ? kInfinity : s.theta(j);
}

double sampling_radius(const Sampling& s) {
  // Half the diagonal of a sample cell (phi spacing on the sphere is sin(theta) step <= step).
  return std::sqrt(0.5) * std::max(s.step_rad, 2 * kPi / s.cols);
}

}  // namespace omma::design
