#include "omma/calib/rig_diff.h"

#include <algorithm>
#include <map>
#include <stdexcept>

#include <fmt/format.h>

namespace omma::calib {

Stat make_stat(std::vector<double> v) {
  Stat s;
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  s.median = n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
  s.max = v.back();
  double sum = 0;
  for (double x : v) sum += x;
  s.mean = sum / n;
  return s;
}

namespace {
const RigCamera& find_camera(const Rig& rig, int id, const char* which) {
  for (const auto& c : rig.cameras)
    if (c.id == id) return c;
  throw std::invalid_argument(fmt::format("rig-diff: camera {} is missing from rig {}", id, which));
}
}  // namespace

Mat3 best_alignment(const Rig& a, const Rig& b) {
  // Camera coords: p = R_a w. If a is b rotated by G (w_a = G w_b), then R_a = R_b G^T.
  // Minimise sum |R_a - R_b G^T|^2  ->  G^T = polar(sum R_b^T R_a). Robust: a second round drops
  // the cameras whose residual angle exceeds 3x the median (e.g. cameras left uncalibrated).
  std::vector<char> use(a.cameras.size(), 1);
  Mat3 gt = Mat3::Identity();
  for (int round = 0; round < 2; ++round) {
    Mat3 m = Mat3::Zero();
    for (size_t i = 0; i < a.cameras.size(); ++i) {
      if (!use[i]) continue;
      const auto& ca = a.cameras[i];
      const auto& cb = find_camera(b, ca.id, "B");
      m += cb.frame.dome_to_camera().transpose() * ca.frame.dome_to_camera();
    }
    Eigen::JacobiSVD<Mat3> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Mat3 d = Mat3::Identity();
    if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0) d(2, 2) = -1;
    gt = svd.matrixU() * d * svd.matrixV().transpose();
    std::vector<double> err(a.cameras.size());
    for (size_t i = 0; i < a.cameras.size(); ++i) {
      const auto& cb = find_camera(b, a.cameras[i].id, "B");
      const Mat3 rel = a.cameras[i].frame.dome_to_camera() * (cb.frame.dome_to_camera() * gt).transpose();
      err[i] = Eigen::AngleAxisd(rel).angle();
    }
    const double med = make_stat(err).median;
    for (size_t i = 0; i < err.size(); ++i) use[i] = err[i] <= std::max(3 * med, 1e-9);
  }
  return gt.transpose();
}

Rig rotate_rig(const Rig& rig, const Mat3& g) {
  Rig out = rig;
  for (auto& c : out.cameras) {
    c.frame.t = g * c.frame.t;
    c.frame.u = g * c.frame.u;
    c.frame.v = g * c.frame.v;
    c.position_mm = g * c.position_mm;
  }
  return out;
}

double ray_error_deg(const RigCamera& a, const RigCamera& b) {
  const CameraModel ma = a.model(), mb = b.model();
  constexpr int kN = 9;
  double sum = 0;
  int n = 0;
  for (int j = 0; j < kN; ++j)
    for (int i = 0; i < kN; ++i) {
      const Vec2 px((i + 0.5) * b.in.width / kN, (j + 0.5) * b.in.height / kN);
      const Vec3 wb = mb.unproject(px);
      if (!mb.sees(wb)) continue;
      const double e = angle_between(ma.unproject(px), wb);
      sum += e * e;
      ++n;
    }
  return n ? rad2deg(std::sqrt(sum / n)) : 0.0;
}

RigDiff diff_rigs(const Rig& a_in, const Rig& b, bool align) {
  if (a_in.cameras.size() != b.cameras.size())
    throw std::invalid_argument(
        fmt::format("rig-diff: rig A has {} cameras, rig B has {}", a_in.cameras.size(), b.cameras.size()));
  RigDiff d;
  Rig a = a_in;
  if (align) {
    // a is (approximately) b rotated by G; undo it: a' = G^T a.
    d.alignment = best_alignment(a_in, b).transpose();
    a = rotate_rig(a_in, d.alignment);
  }
  std::vector<double> orient, focal, center, ray;
  for (const auto& ca : a.cameras) {
    const auto& cb = find_camera(b, ca.id, "B");
    const Mat3 rel = ca.frame.dome_to_camera() * cb.frame.dome_to_camera().transpose();
    const double angle = Eigen::AngleAxisd(rel).angle();
    orient.push_back(rad2deg(angle));
    focal.push_back(
        std::max(std::abs(ca.in.fu - cb.in.fu) / cb.in.fu, std::abs(ca.in.fv - cb.in.fv) / cb.in.fv));
    center.push_back(std::hypot(ca.in.cu - cb.in.cu, ca.in.cv - cb.in.cv));
    ray.push_back(ray_error_deg(ca, cb));
  }
  d.per_camera_orientation_deg = orient;
  d.orientation_error_deg = make_stat(orient);
  d.focal_error_rel = make_stat(focal);
  d.center_error_px = make_stat(center);
  d.ray_error_deg = make_stat(ray);
  return d;
}

}  // namespace omma::calib
