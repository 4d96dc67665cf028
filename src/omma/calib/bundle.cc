#include "omma/calib/bundle.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <ceres/ceres.h>
#include <ceres/rotation.h>
#include <fmt/format.h>

#include "omma/calib/bundle_problem.h"
#include "omma/core/log.h"

namespace omma::calib {
namespace {

// eq. 5.21-5.26 on a camera-frame point p = (p_t, p_u, p_v).
template <typename T>
void project_camera_point(const T* fcc, const T* k, const T* p, T* px) {
  const T x = p[1] / p[0], y = p[2] / p[0];
  const T r2 = x * x + y * y;
  const T rad = T(1) + k[0] * r2 + k[1] * r2 * r2 + k[4] * r2 * r2 * r2;
  const T xd = rad * x + T(2) * k[3] * x * y + k[2] * (r2 + T(2) * x * x);
  const T yd = rad * y + T(2) * k[2] * x * y + k[3] * (r2 + T(2) * y * y);
  px[0] = fcc[2] + fcc[0] * xd;
  px[1] = fcc[3] + fcc[1] * yd;
}

// Far field: the scene point is a unit direction s (dome frame).
struct FarCost {
  Vec2 obs;
  Eigen::Matrix2d wt;  // residual whitening (TrackObservation::weight)
  Mat3 r_nom;
  template <typename T>
  bool operator()(const T* delta, const T* fcc, const T* k, const T* s, T* res) const {
    T p0[3], p[3], px[2];
    for (int r = 0; r < 3; ++r) p0[r] = T(r_nom(r, 0)) * s[0] + T(r_nom(r, 1)) * s[1] + T(r_nom(r, 2)) * s[2];
    ceres::AngleAxisRotatePoint(delta, p0, p);
    if (p[0] < T(1e-3)) p[0] = T(1e-3);  // behind the camera: clamp (see NearCost)
    project_camera_point(fcc, k, p, px);
    const T e0 = px[0] - T(obs.x()), e1 = px[1] - T(obs.y());
    res[0] = T(wt(0, 0)) * e0 + T(wt(0, 1)) * e1;
    res[1] = T(wt(1, 0)) * e0 + T(wt(1, 1)) * e1;
    return true;
  }
};

// Near field: homogeneous scene point X = (P, h), camera centre c fixed: w = P - h c.
struct NearCost {
  Vec2 obs;
  Eigen::Matrix2d wt;  // residual whitening (TrackObservation::weight)
  Mat3 r_nom;
  Vec3 c;
  template <typename T>
  bool operator()(const T* delta, const T* fcc, const T* k, const T* x, T* res) const {
    T w[3], p0[3], p[3], px[2];
    for (int i = 0; i < 3; ++i) w[i] = x[i] - x[3] * T(c[i]);
    for (int r = 0; r < 3; ++r) p0[r] = T(r_nom(r, 0)) * w[0] + T(r_nom(r, 1)) * w[1] + T(r_nom(r, 2)) * w[2];
    ceres::AngleAxisRotatePoint(delta, p0, p);
    // Points at or behind the camera: clamp the depth (a large residual the robust loss caps)
    // rather than failing the evaluation.
    const T n = ceres::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) + T(1e-12);
    if (p[0] < T(1e-3) * n) p[0] = T(1e-3) * n;
    project_camera_point(fcc, k, p, px);
    const T e0 = px[0] - T(obs.x()), e1 = px[1] - T(obs.y());
    res[0] = T(wt(0, 0)) * e0 + T(wt(0, 1)) * e1;
    res[1] = T(wt(1, 0)) * e0 + T(wt(1, 1)) * e1;
    return true;
  }
};

// Near field with the camera position estimated (CalibrationOptions::estimate_position): the centre
// is c = c_ref + len * dir (c_ref the reference camera's fixed centre, len the fixed distance from
// it, dir a unit vector on S^2); w = P - h c = (P - h len dir) - h c_ref, i.e. NearCost (with
// c = c_ref) on the point (P - h len dir, h).
struct NearPosCost {
  NearCost near;  // near.c = the reference camera's centre
  double len;     // mm
  template <typename T>
  bool operator()(const T* delta, const T* fcc, const T* k, const T* x, const T* dir, T* res) const {
    const T xs[4] = {x[0] - x[3] * T(len) * dir[0], x[1] - x[3] * T(len) * dir[1],
                     x[2] - x[3] * T(len) * dir[2], x[3]};
    return near(delta, fcc, k, xs, res);
  }
};

// Near field on the calibration tube (CalibrationOptions::tube_diameter_mm): the scene point lies on
// the tube's wall, a cylinder of radius R about the axis (ox + tx z, oy + ty z, z) (the dome axis,
// offset and tilted by the estimated axis = (ox, oy, tx, ty); first order in the small tilt), at
// the surface coordinates (phi, z): P = (ox + tx z + R cos phi, oy + ty z + R sin phi, z).
struct TubeCost {
  NearCost near;
  double radius;
  template <typename T>
  bool operator()(const T* delta, const T* fcc, const T* k, const T* uv, const T* axis, T* res) const {
    const T x[4] = {axis[0] + axis[2] * uv[1] + T(radius) * ceres::cos(uv[0]),
                    axis[1] + axis[3] * uv[1] + T(radius) * ceres::sin(uv[0]), uv[1], T(1)};
    return near(delta, fcc, k, x, res);
  }
};

struct RotationPrior {
  double inv_sigma;
  template <typename T>
  bool operator()(const T* delta, T* res) const {
    for (int i = 0; i < 3; ++i) res[i] = delta[i] * T(inv_sigma);
    return true;
  }
};

// The mean relative focal length over cameras, pulled to 1: residuals (mean fu/fu_nom - 1, mean
// fv/fv_nom - 1) / sigma; one parameter block (fu, fv, cu, cv) per camera.
struct MeanFocalPrior {
  std::vector<double> fu_nom, fv_nom;
  double inv_sigma;
  template <typename T>
  bool operator()(T const* const* fcc, T* res) const {
    T su(0), sv(0);
    const int m = static_cast<int>(fu_nom.size());
    for (int i = 0; i < m; ++i) {
      su += fcc[i][0] / fu_nom[i];
      sv += fcc[i][1] / fv_nom[i];
    }
    res[0] = (su / T(m) - T(1)) * T(inv_sigma);
    res[1] = (sv / T(m) - T(1)) * T(inv_sigma);
    return true;
  }
};

Mat3 exp_rotation(const double* delta, const Mat3& r_nom) {
  double rm[9];
  ceres::AngleAxisToRotationMatrix(delta, ceres::ColumnMajorAdapter3x3(rm));
  Mat3 r;
  for (int c = 0; c < 3; ++c)
    for (int rr = 0; rr < 3; ++rr) r(rr, c) = rm[c * 3 + rr];
  return r * r_nom;
}

// Midpoint triangulation of rays (c_i + l d_i); false if ill-conditioned or behind a camera.
bool triangulate(const std::vector<Vec3>& c, const std::vector<Vec3>& d, Vec3* p) {
  Mat3 a = Mat3::Zero();
  Vec3 b = Vec3::Zero();
  for (size_t i = 0; i < c.size(); ++i) {
    const Mat3 m = Mat3::Identity() - d[i] * d[i].transpose();
    a += m;
    b += m * c[i];
  }
  Eigen::SelfAdjointEigenSolver<Mat3> es(a);
  if (es.eigenvalues()(0) < 1e-6) return false;
  *p = a.ldlt().solve(b);
  for (size_t i = 0; i < c.size(); ++i)
    if ((*p - c[i]).dot(d[i]) <= 0) return false;
  return true;
}

}  // namespace

namespace detail {

double* BundleBlocks::fcc_block(int i) { return fcc[share_intrinsics ? 0 : i].data(); }
double* BundleBlocks::k_block(int i) { return kk[share_distortion ? 0 : i].data(); }
bool BundleBlocks::moves(int i) const { return position && i != ref && len[i] > 0; }
Vec3 BundleBlocks::centre(int i) const {
  return moves(i) ? Vec3(c[ref] + len[i] * Vec3(dir[i][0], dir[i][1], dir[i][2])) : c[i];
}

BundleBlocks init_bundle_blocks(const Rig& nominal, const Rig& start,
                                const std::vector<std::vector<TrackObservation>>& tracks, SceneModel scene,
                                const CalibrationOptions& opt,
                                const std::optional<std::array<double, 4>>& tube_axis) {
  const int n = static_cast<int>(nominal.cameras.size());
  BundleBlocks b;
  b.r_nom.resize(n);
  b.delta.assign(n, {0, 0, 0});
  b.fcc.resize(n);
  b.kk.resize(n);
  for (int i = 0; i < n; ++i) {
    const auto& c = start.cameras[i];
    b.r_nom[i] = c.frame.dome_to_camera();
    b.fcc[i] = {c.in.fu, c.in.fv, c.in.cu, c.in.cv};
    b.kk[i] = c.in.k;
    b.c.push_back(c.position_mm);
  }
  // Camera positions (near field, estimate_position): the first camera with observations is the
  // reference (position and rotation held: the gauge); every other keeps its distance from it.
  b.position = opt.estimate_position && scene == SceneModel::kNear;
  b.len.assign(n, 0.0);
  b.dir.assign(n, {0, 0, 1});
  if (b.position) {
    b.ref = n;
    for (const auto& t : tracks)
      for (const auto& o : t) b.ref = std::min(b.ref, o.cam);
    if (b.ref == n) b.ref = 0;
    for (int i = 0; i < n; ++i) {
      const Vec3 d = b.c[i] - b.c[b.ref];
      if (i == b.ref || d.norm() < 1e-9) continue;  // coincident centres: no direction to estimate
      b.len[i] = d.norm();
      b.dir[i] = {d.x() / b.len[i], d.y() / b.len[i], d.z() / b.len[i]};
    }
  }
  // Sharing focal and centre is handled with one block for both when either is shared (documented
  // simplification: sharing one of them shares both).
  b.share_intrinsics = opt.share_focal || opt.share_center;
  b.share_distortion = opt.share_distortion;

  b.near = scene == SceneModel::kNear;
  b.points.resize(tracks.size());
  for (size_t ti = 0; ti < tracks.size(); ++ti) {
    std::vector<Vec3> cs, ds;
    Vec3 mean = Vec3::Zero();
    for (const auto& o : tracks[ti]) {
      const Vec3 d = start.cameras[o.cam].model().unproject(o.px);
      cs.push_back(b.c[o.cam]);
      ds.push_back(d);
      mean += d;
    }
    mean.normalize();
    Vec3 p;
    if (b.near && triangulate(cs, ds, &p)) {
      Eigen::Vector4d x(p.x(), p.y(), p.z(), 1.0);
      x.normalize();
      b.points[ti] = {x[0], x[1], x[2], x[3]};
    } else {
      b.points[ti] = {mean.x(), mean.y(), mean.z(), 0.0};
    }
  }

  // The calibration tube: tracks whose point lies near its wall are constrained to it (surface
  // coordinates (phi, z) in `uv`), the others (its closed ends) stay free.
  b.tube = b.near && opt.tube_diameter_mm > 0;
  b.tube_r = opt.tube_diameter_mm / 2;
  b.on_tube.assign(tracks.size(), 0);
  b.uv.assign(tracks.size(), {0, 0});
  b.axis = tube_axis ? *tube_axis : std::array<double, 4>{0, 0, 0, 0};
  if (b.tube)
    for (size_t ti = 0; ti < tracks.size(); ++ti) {
      const auto& x = b.points[ti];
      if (std::abs(x[3]) < 1e-9) continue;
      const Vec3 p = Vec3(x[0], x[1], x[2]) / x[3];
      const Vec2 c(p.x() - b.axis[0] - b.axis[2] * p.z(), p.y() - b.axis[1] - b.axis[3] * p.z());
      // The first solve starts from the nominal rig (points off by millimetres): a wide band; later
      // solves start from a solution (points within ~0.1 mm): a narrow one, which keeps the points
      // of the closed ends near the rim off the wall.
      const double tol = tube_axis ? opt.tube_tolerance_refined : opt.tube_tolerance;
      if (std::abs(c.norm() - b.tube_r) > tol * b.tube_r) continue;
      b.on_tube[ti] = 1;
      b.uv[ti] = {std::atan2(c.y(), c.x()), p.z()};
    }
  if (b.tube)
    spdlog::info("calibrate: {} of {} tracks on the {} mm tube's wall",
                 std::count(b.on_tube.begin(), b.on_tube.end(), 1), tracks.size(), opt.tube_diameter_mm);

  for (int j = opt.radial_terms; j < 3; ++j) b.k_const.push_back(j == 0 ? 0 : j == 1 ? 1 : 4);
  if (!opt.estimate_tangential) b.k_const.insert(b.k_const.end(), {2, 3});
  if (!opt.estimate_focal) b.fcc_const.insert(b.fcc_const.end(), {0, 1});
  if (!opt.estimate_center) b.fcc_const.insert(b.fcc_const.end(), {2, 3});
  return b;
}

BundleManifolds::BundleManifolds(const BundleBlocks& b) : tube_offset_only(4, {2, 3}) {
  if (!b.k_const.empty() && b.k_const.size() < 5) k = std::make_unique<ceres::SubsetManifold>(5, b.k_const);
  if (!b.fcc_const.empty() && b.fcc_const.size() < 4)
    fcc = std::make_unique<ceres::SubsetManifold>(4, b.fcc_const);
}

int build_bundle_problem(ceres::Problem& problem, BundleManifolds& m, BundleBlocks& b,
                         const std::vector<std::vector<TrackObservation>>& tracks,
                         const std::vector<std::vector<char>>& keep, const Rig& nominal,
                         const CalibrationOptions& opt, bool intrinsics_free) {
  const int n = static_cast<int>(b.delta.size());
  const std::string loss = opt.loss != "auto" ? opt.loss : b.near ? "cauchy" : "huber";
  auto make_loss = [&]() -> ceres::LossFunction* {
    if (loss == "huber") return new ceres::HuberLoss(opt.loss_scale_px);
    if (loss == "cauchy") return new ceres::CauchyLoss(opt.loss_scale_px);
    return nullptr;
  };
  // Observations: one reprojection residual each, in tracks with >= 2 kept observations.
  int added = 0;
  for (size_t ti = 0; ti < tracks.size(); ++ti) {
    int kept = 0;
    for (size_t oi = 0; oi < tracks[ti].size(); ++oi) kept += keep[ti][oi];
    if (kept < 2) continue;
    for (size_t oi = 0; oi < tracks[ti].size(); ++oi) {
      if (!keep[ti][oi]) continue;
      const auto& o = tracks[ti][oi];
      const int i = o.cam;
      if (b.on_tube[ti]) {
        auto* cost = new ceres::AutoDiffCostFunction<TubeCost, 2, 3, 4, 5, 2, 4>(
            new TubeCost{{o.px, o.weight, b.r_nom[i], b.c[i]}, b.tube_r});
        problem.AddResidualBlock(cost, make_loss(), b.delta[i].data(), b.fcc_block(i), b.k_block(i),
                                 b.uv[ti].data(), b.axis.data());
      } else if (b.near && b.moves(i)) {
        auto* cost = new ceres::AutoDiffCostFunction<NearPosCost, 2, 3, 4, 5, 4, 3>(
            new NearPosCost{{o.px, o.weight, b.r_nom[i], b.c[b.ref]}, b.len[i]});
        problem.AddResidualBlock(cost, make_loss(), b.delta[i].data(), b.fcc_block(i), b.k_block(i),
                                 b.points[ti].data(), b.dir[i].data());
        problem.SetManifold(b.dir[i].data(), &m.sphere3);
      } else if (b.near) {
        auto* cost = new ceres::AutoDiffCostFunction<NearCost, 2, 3, 4, 5, 4>(
            new NearCost{o.px, o.weight, b.r_nom[i], b.c[i]});
        problem.AddResidualBlock(cost, make_loss(), b.delta[i].data(), b.fcc_block(i), b.k_block(i),
                                 b.points[ti].data());
      } else {
        auto* cost =
            new ceres::AutoDiffCostFunction<FarCost, 2, 3, 4, 5, 3>(new FarCost{o.px, o.weight, b.r_nom[i]});
        problem.AddResidualBlock(cost, make_loss(), b.delta[i].data(), b.fcc_block(i), b.k_block(i),
                                 b.points[ti].data());
      }
      ++added;
    }
    if (problem.HasParameterBlock(b.points[ti].data()))
      problem.SetManifold(b.points[ti].data(),
                          b.near ? static_cast<ceres::Manifold*>(&m.sphere4) : &m.sphere3);
  }
  if (b.tube && !opt.tube_tilt && problem.HasParameterBlock(b.axis.data()))
    problem.SetManifold(b.axis.data(), &m.tube_offset_only);
  // Priors: the rotations (gauge), the mean focal length (near field without the tube).
  for (int i = 0; i < n; ++i) {
    if (!problem.HasParameterBlock(b.delta[i].data())) continue;
    if (!opt.estimate_rotation || (b.position && i == b.ref)) {
      // Positions estimated: the reference camera's rotation is the gauge (no prior on the others).
      problem.SetParameterBlockConstant(b.delta[i].data());
    } else if (b.position) {
      continue;
    } else if (opt.prior_rotation_deg > 0) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<RotationPrior, 3, 3>(
                                   new RotationPrior{1.0 / deg2rad(opt.prior_rotation_deg)}),
                               nullptr, b.delta[i].data());
    }
  }
  if (b.near && !b.tube && intrinsics_free && opt.prior_mean_focal > 0 && opt.estimate_focal &&
      !b.share_intrinsics) {
    auto* prior = new MeanFocalPrior{{}, {}, 1.0 / opt.prior_mean_focal};
    auto* cost = new ceres::DynamicAutoDiffCostFunction<MeanFocalPrior>(prior);
    std::vector<double*> blocks;
    for (int i = 0; i < n; ++i) {
      if (!problem.HasParameterBlock(b.fcc_block(i))) continue;
      prior->fu_nom.push_back(nominal.cameras[i].in.fu);
      prior->fv_nom.push_back(nominal.cameras[i].in.fv);
      cost->AddParameterBlock(4);
      blocks.push_back(b.fcc_block(i));
    }
    cost->SetNumResiduals(2);
    if (blocks.empty())
      delete cost;
    else
      problem.AddResidualBlock(cost, nullptr, blocks);
  }
  // Intrinsics: constant in pass 0, else the parts not estimated held by a subset manifold.
  for (int i = 0; i < n; ++i) {
    for (double* blk : {b.fcc_block(i), b.k_block(i)}) {
      if (!problem.HasParameterBlock(blk)) continue;
      if (!intrinsics_free) {
        problem.SetParameterBlockConstant(blk);
        continue;
      }
      const bool is_k = blk == b.k_block(i);
      const auto& cst = is_k ? b.k_const : b.fcc_const;
      if (cst.size() == (is_k ? 5u : 4u))
        problem.SetParameterBlockConstant(blk);
      else if (!cst.empty())
        problem.SetManifold(blk, is_k ? m.k.get() : m.fcc.get());
    }
  }
  return added;
}

}  // namespace detail

namespace {

using detail::BundleBlocks;

// Step 4: cameras with too few observations keep their nominal values (a warning names them); their
// observations and the tracks left with fewer than two are removed. Returns the active flags.
std::vector<char> drop_inactive_cameras(const Rig& nominal,
                                        std::vector<std::vector<TrackObservation>>& tracks,
                                        const CalibrationOptions& opt, CalibrationSummary& res) {
  const int n = static_cast<int>(nominal.cameras.size());
  std::vector<int> obs_count(n, 0);
  for (const auto& t : tracks)
    for (const auto& o : t) ++obs_count[o.cam];
  std::vector<char> active(n, 0);
  for (int i = 0; i < n; ++i) {
    active[i] = obs_count[i] >= opt.min_observations;
    if (!active[i]) res.uncalibrated_ids.push_back(nominal.cameras[i].id);
  }
  if (std::count(active.begin(), active.end(), 1) < 2) {
    // Name the cameras: every camera's matched observations, and the pairs (the worst first).
    std::string cams, pairs;
    for (int i = 0; i < n; ++i)
      cams += fmt::format("{}camera {}: {}", i ? ", " : "", nominal.cameras[i].id, obs_count[i]);
    auto pp = res.per_pair;
    std::sort(pp.begin(), pp.end(),
              [](const PairReport& a, const PairReport& b) { return a.inliers < b.inliers; });
    for (size_t p = 0; p < pp.size() && p < 8; ++p)
      pairs += fmt::format("{}cameras {} and {}: {} matches, {} RANSAC inliers", p ? "; " : "", pp[p].cam_a,
                           pp[p].cam_b, pp[p].matches, pp[p].inliers);
    if (pp.size() > 8) pairs += fmt::format("; ... ({} pairs)", pp.size());
    throw std::runtime_error(fmt::format(
        "calibrate: too few feature matches to calibrate anything: fewer than 2 cameras have {} matched "
        "observations ({}){}{}; are the frames textureless, do the cameras see different scenes, or do the "
        "frames not belong to this rig?",
        opt.min_observations, cams, pairs.empty() ? "" : "; ", pairs));
  }
  if (!res.uncalibrated_ids.empty()) {
    std::string ids;
    for (int id : res.uncalibrated_ids) ids += (ids.empty() ? "" : ", ") + std::to_string(id);
    const std::string w =
        fmt::format("cameras with fewer than {} matched observations keep their nominal values: {}",
                    opt.min_observations, ids);
    if (std::find(res.warnings.begin(), res.warnings.end(), w) == res.warnings.end()) {
      res.warnings.push_back(w);
      spdlog::warn("calibrate: {}", w);
    }
  }
  for (auto& t : tracks)
    t.erase(std::remove_if(t.begin(), t.end(), [&](const TrackObservation& o) { return !active[o.cam]; }),
            t.end());
  tracks.erase(std::remove_if(tracks.begin(), tracks.end(), [](const auto& t) { return t.size() < 2; }),
               tracks.end());
  return active;
}

// Squared reprojection errors of every observation, in pixels (weighted = false) or whitened (the
// solver's units), in track order.
std::vector<double> squared_errors(BundleBlocks& b, const std::vector<std::vector<TrackObservation>>& tracks,
                                   const Rig& nominal, bool weighted = false) {
  std::vector<double> err2;
  const Eigen::Matrix2d id = Eigen::Matrix2d::Identity();
  for (size_t ti = 0; ti < tracks.size(); ++ti)
    for (const auto& o : tracks[ti]) {
      double r[2] = {1e3, 1e3};
      const int i = o.cam;
      const Vec2 obs = o.px;
      const Eigen::Matrix2d& w = weighted ? o.weight : id;
      bool ok;
      if (b.on_tube[ti])
        ok = TubeCost{{obs, w, b.r_nom[i], b.c[i]}, b.tube_r}(b.delta[i].data(), b.fcc_block(i), b.k_block(i),
                                                              b.uv[ti].data(), b.axis.data(), r);
      else if (b.near)
        ok = NearCost{obs, w, b.r_nom[i], b.centre(i)}(b.delta[i].data(), b.fcc_block(i), b.k_block(i),
                                                       b.points[ti].data(), r);
      else
        ok = FarCost{obs, w, b.r_nom[i]}(b.delta[i].data(), b.fcc_block(i), b.k_block(i), b.points[ti].data(),
                                         r);
      err2.push_back(ok ? r[0] * r[0] + r[1] * r[1] : 1e6);
    }
  return err2;
}

// Step 5: the three passes. Pass 0: intrinsics held at nominal, rotations and scene points only (a
// good start: with all parameters free from the nominal start the near-field problem slides into a
// wrong valley where focal length trades against depth). Pass 1: everything free; then outliers are
// dropped (keep); pass 2: final solve.
void run_passes(BundleBlocks& b, const std::vector<std::vector<TrackObservation>>& tracks,
                std::vector<std::vector<char>>& keep, const Rig& nominal, const CalibrationOptions& opt,
                CalibrationSummary& res) {
  for (int pass = 0; pass < 3; ++pass) {
    ceres::Problem::Options popt;
    popt.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(popt);
    detail::BundleManifolds manifolds(b);
    detail::build_bundle_problem(problem, manifolds, b, tracks, keep, nominal, opt,
                                 /*intrinsics_free=*/pass > 0);
    ceres::Solver::Options so;
    so.linear_solver_type = ceres::SPARSE_SCHUR;
    if (!ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE) &&
        !ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::EIGEN_SPARSE))
      so.linear_solver_type = ceres::DENSE_SCHUR;
    so.max_num_iterations = opt.max_iterations;

    so.num_threads = opt.threads;
    so.minimizer_progress_to_stdout = false;
    so.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(so, &problem, &summary);
    spdlog::info(
        "calibrate: bundle adjustment pass {}: {} residual blocks, {} iterations, cost {:.4g} -> {:.4g}",
        pass + 1, summary.num_residual_blocks, summary.iterations.size(), summary.initial_cost,
        summary.final_cost);
    if (pass == 1) {
      // Outliers (wrong matches that passed RANSAC, e.g. along an epipolar line) are dropped once
      // the intrinsics are free, before the final solve. Not after pass 0: with the intrinsics still
      // nominal, the observations near the image edges (where focal length, principal point and k1
      // errors add up to several pixels) look like outliers but are the ones that determine the
      // intrinsics. Dropping them there left ~11 % of perfect near-field observations out and
      // doubled the errors (model check: 0.21 instead of 0.07 deg at 0.05 px noise; colon: focal
      // error 0.92 % instead of 0.50 %); the robust loss keeps real outliers in check until here.
      const std::vector<double> e2 = squared_errors(b, tracks, nominal, true);
      const double thr2 = opt.outlier_px * opt.outlier_px;
      size_t idx = 0;
      for (size_t ti = 0; ti < tracks.size(); ++ti)
        for (size_t oi = 0; oi < tracks[ti].size(); ++oi, ++idx)
          if (keep[ti][oi] && e2[idx] > thr2) keep[ti][oi] = 0, ++res.rejected;
    }
  }
}

// Step 6: statistics over the kept observations of tracks with >= 2 kept observations, and the
// calibrated rig (the active cameras' solved parameters).
void write_solution(BundleBlocks& b, const std::vector<std::vector<TrackObservation>>& tracks,
                    const std::vector<std::vector<char>>& keep, const std::vector<char>& active,
                    const Rig& nominal, CalibrationSummary& res) {
  const int n = static_cast<int>(nominal.cameras.size());
  const std::vector<double> e2 = squared_errors(b, tracks, nominal);
  std::vector<double> cam_sum(n, 0);
  std::vector<int> cam_n(n, 0);
  double sum = 0;
  size_t idx = 0;
  for (size_t ti = 0; ti < tracks.size(); ++ti) {
    int kept = 0;
    for (char k : keep[ti]) kept += k;
    bool counted = kept >= 2;
    if (counted) ++res.tracks;
    for (size_t oi = 0; oi < tracks[ti].size(); ++oi, ++idx) {
      if (!counted || !keep[ti][oi]) continue;
      cam_sum[tracks[ti][oi].cam] += e2[idx];
      ++cam_n[tracks[ti][oi].cam];
      sum += e2[idx];
      ++res.observations;
    }
  }
  res.rms_px = res.observations ? std::sqrt(sum / res.observations) : 0;
  for (int i = 0; i < n; ++i) {
    RigCamera& c = res.rig.cameras[i];
    CameraReport rep;
    rep.id = c.id;
    rep.matches = cam_n[i];
    rep.rms_px = cam_n[i] ? std::sqrt(cam_sum[i] / cam_n[i]) : 0;
    rep.calibrated = active[i];
    res.per_camera.push_back(rep);
    if (!active[i]) continue;
    const Mat3 r = exp_rotation(b.delta[i].data(), b.r_nom[i]);
    c.frame.t = r.row(0).transpose();
    c.frame.u = r.row(1).transpose();
    c.frame.v = r.row(2).transpose();
    const double* f = b.fcc_block(i);
    c.in.fu = f[0], c.in.fv = f[1], c.in.cu = f[2], c.in.cv = f[3];
    c.position_mm = b.centre(i);
    const double* k = b.k_block(i);
    for (int j = 0; j < 5; ++j) c.in.k[j] = k[j];
    try {
      validate_camera(c);
    } catch (const std::exception& e) {
      // The matches did not hold the model (e.g. distortion from one narrow overlap): say so and how
      // to ask for less, rather than write a lens that folds back.
      throw std::runtime_error(fmt::format(
          "calibrate: the adjustment gave camera {} a model that is not a lens ({}): the matches do not "
          "determine that many parameters; ask for fewer (--distortion fixed, --center fixed, --focal "
          "shared) "
          "or give more overlap",
          c.id, e.what()));
    }
  }
  res.rig.validate();
}

}  // namespace

CalibrationSummary solve_tracks(const Rig& nominal, const Rig& start,
                                std::vector<std::vector<TrackObservation>> tracks, SceneModel scene,
                                const CalibrationOptions& opt, CalibrationSummary res, SolveState* state) {
  res.uncalibrated_ids.clear();
  res.per_camera.clear();
  res.tracks = res.observations = res.rejected = 0;
  // 4. Cameras with too few observations keep their nominal values.
  const std::vector<char> active = drop_inactive_cameras(nominal, tracks, opt, res);
  // 5. Parameters, then the passes.
  BundleBlocks b =
      detail::init_bundle_blocks(nominal, start, tracks, scene, opt, state ? state->tube_axis : std::nullopt);
  // Per-observation keep mask (outlier removal between the solves).
  std::vector<std::vector<char>> keep(tracks.size());
  for (size_t ti = 0; ti < tracks.size(); ++ti) keep[ti].assign(tracks[ti].size(), 1);
  {
    const std::vector<double> e2 = squared_errors(b, tracks, nominal);
    double s = 0;
    for (double v : e2) s += std::min(v, 1e4);
    res.initial_rms_px = e2.empty() ? 0 : std::sqrt(s / e2.size());
  }
  run_passes(b, tracks, keep, nominal, opt, res);
  // 6. Statistics and the calibrated rig.
  write_solution(b, tracks, keep, active, nominal, res);
  for (size_t ti = 0; ti < tracks.size(); ++ti) {
    if (!b.on_tube[ti]) continue;
    Eigen::Vector4d x(b.axis[0] + b.axis[2] * b.uv[ti][1] + b.tube_r * std::cos(b.uv[ti][0]),
                      b.axis[1] + b.axis[3] * b.uv[ti][1] + b.tube_r * std::sin(b.uv[ti][0]), b.uv[ti][1],
                      1.0);
    x.normalize();
    b.points[ti] = {x[0], x[1], x[2], x[3]};
  }
  if (b.tube)
    spdlog::info("calibrate: tube axis offset ({:.3f}, {:.3f}) mm, tilt ({:.4f}, {:.4f})", b.axis[0],
                 b.axis[1], b.axis[2], b.axis[3]);
  if (state) {
    state->tracks = tracks;
    state->points = b.points;
    if (b.tube) state->tube_axis = b.axis;
  }
  spdlog::info(
      "calibrate: reprojection RMS {:.3f} px (nominal rig {:.3f} px), {} tracks, {} observations, {} "
      "rejected",
      res.rms_px, res.initial_rms_px, res.tracks, res.observations, res.rejected);
  return res;
}

CalibrationSummary calibrate_from_tracks(const Rig& nominal,
                                         std::vector<std::vector<TrackObservation>> tracks, SceneModel scene,
                                         const CalibrationOptions& opt) {
  if (scene == SceneModel::kAuto)
    throw std::invalid_argument("calibrate_from_tracks: scene must be far or near");
  std::string why;
  if (!opt.IsValid(&why)) throw std::invalid_argument("calibrate_from_tracks: " + why);
  const int n = static_cast<int>(nominal.cameras.size());
  for (const auto& t : tracks)
    for (const auto& o : t)
      if (o.cam < 0 || o.cam >= n)
        throw std::invalid_argument(
            fmt::format("calibrate_from_tracks: camera index {} out of range", o.cam));
  CalibrationSummary res;
  res.rig = nominal;
  res.scene = scene;
  return solve_tracks(nominal, nominal, std::move(tracks), scene, opt, std::move(res));
}

}  // namespace omma::calib
