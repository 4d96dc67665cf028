#include "omma/calib/calibrate.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <numeric>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <ceres/ceres.h>
#include <ceres/rotation.h>
#include <fmt/format.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/utility.hpp>

#include "omma/calib/photometric.h"
#include "omma/calib/subpixel.h"
#include "omma/core/srgb.h"
#include "omma/core/log.h"
#include "omma/core/progress.h"

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

using Observation = TrackObservation;

struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(int n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(int a, int b) { parent[find(a)] = find(b); }
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

// What a solve leaves for the subpixel refinement: the tracks it used (observations of uncalibrated
// cameras and short tracks removed, outliers kept) and their scene points (near: (P, h), far: unit
// direction in the first three entries).
struct SolveState {
  std::vector<std::vector<TrackObservation>> tracks;
  std::vector<std::array<double, 4>> points;
};

// Steps 4-6 of calibrate_rig on given tracks: cameras with too few observations, bundle
// adjustment, statistics and the calibrated rig. The parameters start from `start` (the nominal rig,
// or a previous solution); the priors refer to `nominal`.
CalibrationResult solve_tracks(const Rig& nominal, const Rig& start, std::vector<std::vector<TrackObservation>> tracks,
                               SceneModel scene, const CalibrationOptions& opt, CalibrationResult res,
                               SolveState* state = nullptr) {
  const int n = static_cast<int>(nominal.cameras.size());
  res.uncalibrated_ids.clear();
  res.per_camera.clear();
  res.tracks = res.observations = res.rejected = 0;
  // 4. Cameras with too few observations keep their nominal values.
  std::vector<int> obs_count(n, 0);
  for (const auto& t : tracks)
    for (const auto& o : t) ++obs_count[o.cam];
  std::vector<char> active(n, 0);
  for (int i = 0; i < n; ++i) {
    active[i] = obs_count[i] >= opt.min_observations;
    if (!active[i]) res.uncalibrated_ids.push_back(nominal.cameras[i].id);
  }
  if (std::count(active.begin(), active.end(), 1) < 2)
    throw std::runtime_error(fmt::format(
        "calibrate: too few feature matches to calibrate anything ({} matches, {} inliers over {} camera "
        "pairs); are the frames textureless, or do they not belong to this rig?",
        res.matches, res.inliers, res.pairs));
  if (!res.uncalibrated_ids.empty()) {
    std::string ids;
    for (int id : res.uncalibrated_ids) ids += (ids.empty() ? "" : ", ") + std::to_string(id);
    const std::string w = fmt::format("cameras with fewer than {} matched observations keep their nominal values: {}",
                                      opt.min_observations, ids);
    if (std::find(res.warnings.begin(), res.warnings.end(), w) == res.warnings.end()) {
      res.warnings.push_back(w);
      spdlog::warn("calibrate: {}", w);
    }
  }
  for (auto& t : tracks)
    t.erase(std::remove_if(t.begin(), t.end(), [&](const Observation& o) { return !active[o.cam]; }), t.end());
  tracks.erase(std::remove_if(tracks.begin(), tracks.end(), [](const auto& t) { return t.size() < 2; }),
               tracks.end());

  // 5. Parameters.
  std::vector<Mat3> r_nom(n);
  std::vector<std::array<double, 3>> delta(n, {0, 0, 0});
  std::vector<std::array<double, 4>> fcc(n);
  std::vector<std::array<double, 5>> kk(n);
  for (int i = 0; i < n; ++i) {
    const auto& c = start.cameras[i];
    r_nom[i] = c.frame.dome_to_camera();
    fcc[i] = {c.in.fu, c.in.fv, c.in.cu, c.in.cv};
    kk[i] = c.in.k;
  }
  auto fcc_block = [&](int i) { return fcc[opt.share_focal || opt.share_center ? 0 : i].data(); };
  auto k_block = [&](int i) { return kk[opt.share_distortion ? 0 : i].data(); };
  // Sharing focal and centre is handled with one block for both when either is shared (documented
  // simplification: sharing one of them shares both).

  const bool near = scene == SceneModel::kNear;
  std::vector<std::array<double, 4>> points(tracks.size());
  for (size_t ti = 0; ti < tracks.size(); ++ti) {
    std::vector<Vec3> cs, ds;
    Vec3 mean = Vec3::Zero();
    for (const auto& o : tracks[ti]) {
      const Vec3 d = start.cameras[o.cam].model().unproject(o.px);
      cs.push_back(nominal.cameras[o.cam].position_mm);
      ds.push_back(d);
      mean += d;
    }
    mean.normalize();
    Vec3 p;
    if (near && triangulate(cs, ds, &p)) {
      Eigen::Vector4d x(p.x(), p.y(), p.z(), 1.0);
      x.normalize();
      points[ti] = {x[0], x[1], x[2], x[3]};
    } else {
      points[ti] = {mean.x(), mean.y(), mean.z(), 0.0};
    }
  }

  // Squared reprojection errors, in pixels (weighted = false) or whitened (the solver's units).
  auto evaluate = [&](std::vector<double>* err2, bool weighted = false) {
    err2->clear();
    const Eigen::Matrix2d id = Eigen::Matrix2d::Identity();
    for (size_t ti = 0; ti < tracks.size(); ++ti)
      for (const auto& o : tracks[ti]) {
        double r[2] = {1e3, 1e3};
        const int i = o.cam;
        const Vec2 obs = o.px;
        const Eigen::Matrix2d& w = weighted ? o.weight : id;
        bool ok;
        if (near) ok = NearCost{obs, w, r_nom[i], nominal.cameras[i].position_mm}(delta[i].data(), fcc_block(i), k_block(i), points[ti].data(), r);
        else ok = FarCost{obs, w, r_nom[i]}(delta[i].data(), fcc_block(i), k_block(i), points[ti].data(), r);
        err2->push_back(ok ? r[0] * r[0] + r[1] * r[1] : 1e6);
      }
  };
  // Per-observation keep mask (outlier removal between the solves).
  std::vector<std::vector<char>> keep(tracks.size());
  for (size_t ti = 0; ti < tracks.size(); ++ti) keep[ti].assign(tracks[ti].size(), 1);
  {
    std::vector<double> e2;
    evaluate(&e2);
    double s = 0;
    for (double v : e2) s += std::min(v, 1e4);
    res.initial_rms_px = e2.empty() ? 0 : std::sqrt(s / e2.size());
  }

  std::vector<int> k_const;
  for (int j = opt.radial_terms; j < 3; ++j) k_const.push_back(j == 0 ? 0 : j == 1 ? 1 : 4);
  if (!opt.estimate_tangential) k_const.insert(k_const.end(), {2, 3});
  std::vector<int> fcc_const;
  if (!opt.estimate_focal) fcc_const.insert(fcc_const.end(), {0, 1});
  if (!opt.estimate_center) fcc_const.insert(fcc_const.end(), {2, 3});

  // Pass 0: intrinsics held at nominal, rotations and scene points only (a good start: with all
  // parameters free from the nominal start the near-field problem slides into a wrong valley
  // where focal length trades against depth). Pass 1: everything free; then outliers are dropped;
  // pass 2: final solve.
  for (int pass = 0; pass < 3; ++pass) {
    const bool intrinsics_free = pass > 0;
    ceres::Problem::Options popt;
    popt.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(popt);
    ceres::SphereManifold<3> sphere3;
    ceres::SphereManifold<4> sphere4;
    std::unique_ptr<ceres::Manifold> k_manifold, fcc_manifold;
    if (!k_const.empty() && k_const.size() < 5) k_manifold = std::make_unique<ceres::SubsetManifold>(5, k_const);
    if (!fcc_const.empty() && fcc_const.size() < 4) fcc_manifold = std::make_unique<ceres::SubsetManifold>(4, fcc_const);
    const std::string loss = opt.loss != "auto" ? opt.loss : near ? "cauchy" : "huber";
    auto make_loss = [&]() -> ceres::LossFunction* {
      if (loss == "huber") return new ceres::HuberLoss(opt.loss_scale_px);
      if (loss == "cauchy") return new ceres::CauchyLoss(opt.loss_scale_px);
      return nullptr;
    };
    for (size_t ti = 0; ti < tracks.size(); ++ti) {
      int kept = 0;
      for (size_t oi = 0; oi < tracks[ti].size(); ++oi) kept += keep[ti][oi];
      if (kept < 2) continue;
      for (size_t oi = 0; oi < tracks[ti].size(); ++oi) {
        if (!keep[ti][oi]) continue;
        const auto& o = tracks[ti][oi];
        const int i = o.cam;
        if (near) {
          auto* cost = new ceres::AutoDiffCostFunction<NearCost, 2, 3, 4, 5, 4>(
              new NearCost{o.px, o.weight, r_nom[i], nominal.cameras[i].position_mm});
          problem.AddResidualBlock(cost, make_loss(), delta[i].data(), fcc_block(i), k_block(i), points[ti].data());
        } else {
          auto* cost = new ceres::AutoDiffCostFunction<FarCost, 2, 3, 4, 5, 3>(new FarCost{o.px, o.weight, r_nom[i]});
          problem.AddResidualBlock(cost, make_loss(), delta[i].data(), fcc_block(i), k_block(i), points[ti].data());
        }
      }
      if (problem.HasParameterBlock(points[ti].data()))
        problem.SetManifold(points[ti].data(), near ? static_cast<ceres::Manifold*>(&sphere4) : &sphere3);
    }
    for (int i = 0; i < n; ++i) {
      if (!problem.HasParameterBlock(delta[i].data())) continue;
      if (!opt.estimate_rotation) {
        problem.SetParameterBlockConstant(delta[i].data());
      } else if (opt.prior_rotation_deg > 0) {
        problem.AddResidualBlock(new ceres::AutoDiffCostFunction<RotationPrior, 3, 3>(
                                     new RotationPrior{1.0 / deg2rad(opt.prior_rotation_deg)}),
                                 nullptr, delta[i].data());
      }
    }
    if (near && intrinsics_free && opt.prior_mean_focal > 0 && opt.estimate_focal && !(opt.share_focal || opt.share_center)) {
      auto* prior = new MeanFocalPrior{{}, {}, 1.0 / opt.prior_mean_focal};
      auto* cost = new ceres::DynamicAutoDiffCostFunction<MeanFocalPrior>(prior);
      std::vector<double*> blocks;
      for (int i = 0; i < n; ++i) {
        if (!problem.HasParameterBlock(fcc_block(i))) continue;
        prior->fu_nom.push_back(nominal.cameras[i].in.fu);
        prior->fv_nom.push_back(nominal.cameras[i].in.fv);
        cost->AddParameterBlock(4);
        blocks.push_back(fcc_block(i));
      }
      cost->SetNumResiduals(2);
      if (blocks.empty()) delete cost;
      else problem.AddResidualBlock(cost, nullptr, blocks);
    }
    for (int i = 0; i < n; ++i) {
      for (double* blk : {fcc_block(i), k_block(i)}) {
        if (!problem.HasParameterBlock(blk)) continue;
        if (!intrinsics_free) {
          problem.SetParameterBlockConstant(blk);
          continue;
        }
        const bool is_k = blk == k_block(i);
        const auto& cst = is_k ? k_const : fcc_const;
        if (cst.size() == (is_k ? 5u : 4u)) problem.SetParameterBlockConstant(blk);
        else if (!cst.empty()) problem.SetManifold(blk, is_k ? k_manifold.get() : fcc_manifold.get());
      }
    }
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
    spdlog::info("calibrate: bundle adjustment pass {}: {} residual blocks, {} iterations, cost {:.4g} -> {:.4g}",
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
      std::vector<double> e2;
      evaluate(&e2, true);
      const double thr2 = opt.outlier_px * opt.outlier_px;
      size_t idx = 0;
      for (size_t ti = 0; ti < tracks.size(); ++ti)
        for (size_t oi = 0; oi < tracks[ti].size(); ++oi, ++idx)
          if (keep[ti][oi] && e2[idx] > thr2) keep[ti][oi] = 0, ++res.rejected;
    }
  }

  // 6. Statistics over the kept observations of tracks with >= 2 kept observations.
  std::vector<double> e2;
  evaluate(&e2);
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
    const Mat3 r = exp_rotation(delta[i].data(), r_nom[i]);
    c.frame.t = r.row(0).transpose();
    c.frame.u = r.row(1).transpose();
    c.frame.v = r.row(2).transpose();
    const double* f = fcc_block(i);
    c.in.fu = f[0], c.in.fv = f[1], c.in.cu = f[2], c.in.cv = f[3];
    const double* k = k_block(i);
    for (int j = 0; j < 5; ++j) c.in.k[j] = k[j];
  }
  res.rig.validate();
  if (state) {
    state->tracks = tracks;
    state->points = points;
  }
  spdlog::info("calibrate: reprojection RMS {:.3f} px (nominal rig {:.3f} px), {} tracks, {} observations, {} rejected",
               res.rms_px, res.initial_rms_px, res.tracks, res.observations, res.rejected);
  return res;
}

// The homography (continuous pixels of camera a -> camera b) of the scene plane through x (dome
// frame, mm) with normal `normal`, fitted to a 5 x 5 grid of points within +-half pixels of pa;
// false if the plane is seen edge-on or a point leaves a camera.
bool plane_homography(const RigCamera& ca, const RigCamera& cb, const Vec2& pa, const Vec3& x, const Vec3& normal,
                      double half, Eigen::Matrix3d* h) {
  const CameraModel ma = ca.model(), mb = cb.model();
  std::vector<cv::Point2d> src, dst;
  for (int i = -2; i <= 2; ++i)
    for (int j = -2; j <= 2; ++j) {
      const Vec2 q = pa + Vec2(i, j) * (half / 2);
      const Vec3 d = ma.unproject(q);
      const double den = normal.dot(d);
      if (std::abs(den) < 1e-3) return false;
      const double s = normal.dot(x - ca.position_mm) / den;
      if (!(s > 0)) return false;
      const auto p = mb.project(ca.position_mm + s * d - cb.position_mm);
      if (!p) return false;
      src.emplace_back(q.x(), q.y());
      dst.emplace_back(p->x(), p->y());
    }
  const cv::Mat hm = cv::findHomography(src, dst, 0);
  if (hm.empty()) return false;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) (*h)(r, c) = hm.at<double>(r, c);
  return h->allFinite();
}

// Subpixel refinement (subpixel.h) after a solve. Every track: the observation nearest its
// camera's principal point is the reference; every other observation is replaced by the ECC
// alignment of the reference's patch, started from the current model's homography of the local
// scene plane. The plane at a near-field point is normal to the smallest principal axis of its
// nearest neighbouring scene points (the direction to the dome centre when those are degenerate);
// in the far field it is the plane at infinity. Observations whose alignment fails are dropped.
std::vector<std::vector<TrackObservation>> refine_tracks(const Rig& rig, const std::vector<cv::Mat>& gray,
                                                         const SolveState& st, bool near, const SubpixelOptions& so,
                                                         int* attempted, int* refined) {
  const size_t m = st.tracks.size();
  std::vector<Vec3> x(m);
  std::vector<char> finite(m, 0);
  for (size_t ti = 0; ti < m; ++ti) {
    const auto& p = st.points[ti];
    if (near && std::abs(p[3]) > 1e-9) {
      x[ti] = Vec3(p[0], p[1], p[2]) / p[3];
      finite[ti] = 1;
    } else {
      x[ti] = Vec3(p[0], p[1], p[2]).normalized() * 1e6;  // far field: a plane at 1 km
    }
  }
  std::vector<Vec3> normal(m);
  constexpr int kNeighbours = 12;
  for (size_t ti = 0; ti < m; ++ti) {
    normal[ti] = x[ti].normalized();
    if (!finite[ti]) continue;
    std::vector<std::pair<double, size_t>> d;
    for (size_t tj = 0; tj < m; ++tj)
      if (finite[tj] && tj != ti) d.emplace_back((x[tj] - x[ti]).squaredNorm(), tj);
    if (static_cast<int>(d.size()) < kNeighbours) continue;
    std::partial_sort(d.begin(), d.begin() + kNeighbours, d.end());
    Vec3 mean = x[ti];
    for (int k = 0; k < kNeighbours; ++k) mean += x[d[k].second];
    mean /= kNeighbours + 1;
    Mat3 cov = (x[ti] - mean) * (x[ti] - mean).transpose();
    for (int k = 0; k < kNeighbours; ++k) cov += (x[d[k].second] - mean) * (x[d[k].second] - mean).transpose();
    Eigen::SelfAdjointEigenSolver<Mat3> es(cov);
    if (es.eigenvalues()(0) < 0.2 * es.eigenvalues()(1)) normal[ti] = es.eigenvectors().col(0);
  }

  // Alignment jobs: a reference pixel, its scene plane and the cameras to find it in.
  struct Job {
    TrackObservation ref;
    Vec3 x, normal;
    std::vector<TrackObservation> targets;  // the current observations to refine
  };
  std::vector<Job> jobs;
  for (size_t ti = 0; ti < m; ++ti) {
    const auto& t = st.tracks[ti];
    size_t ref = 0;
    double best = 1e300;
    for (size_t oi = 0; oi < t.size(); ++oi) {
      const auto& in = rig.cameras[t[oi].cam].in;
      const double d = (t[oi].px - Vec2(in.cu, in.cv)).squaredNorm();
      if (d < best) best = d, ref = oi;
    }
    Job job{t[ref], x[ti], normal[ti], {}};
    for (size_t oi = 0; oi < t.size(); ++oi)
      if (oi != ref) job.targets.push_back(t[oi]);
    jobs.push_back(std::move(job));
  }
  std::vector<std::vector<TrackObservation>> done(jobs.size());
  cv::parallel_for_(cv::Range(0, static_cast<int>(jobs.size())), [&](const cv::Range& r) {
    for (int k = r.start; k < r.end; ++k) {
      const Job& job = jobs[k];
      std::vector<TrackObservation> nt{job.ref};
      for (const TrackObservation& target : job.targets) {
        const int b = target.cam;
        Eigen::Matrix3d h;
        if (!plane_homography(rig.cameras[job.ref.cam], rig.cameras[b], job.ref.px, job.x, job.normal,
                              so.patch_px / 2, &h))
          continue;
        const auto p = align_patch(gray[job.ref.cam], job.ref.px, gray[b], h, so);
        if (p) nt.push_back({b, *p});
      }
      done[k] = std::move(nt);
    }
  });
  std::vector<std::vector<TrackObservation>> out;
  for (size_t k = 0; k < jobs.size(); ++k) {
    *attempted += static_cast<int>(jobs[k].targets.size());
    *refined += static_cast<int>(done[k].size()) - 1;
    if (done[k].size() >= 2) {
      out.push_back(std::move(done[k]));
    }
  }
  return out;
}


// A whitening matrix W = scale * Sigma^-1/2 (eigenvalues of Sigma floored at floor_px^2).
Eigen::Matrix2d whitening(const Eigen::Matrix2d& cov, double scale, double floor_px) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(cov);
  const Eigen::Vector2d ev = es.eigenvalues().cwiseMax(floor_px * floor_px);
  return scale * (es.eigenvectors() * ev.cwiseSqrt().cwiseInverse().asDiagonal() * es.eigenvectors().transpose());
}

// Dense guided correspondences (near field, after the first solve). Every keypoint of every camera
// is a candidate reference pixel, not only the matched ones: its depth is the median depth of the
// current solution's scene points observed nearest to it in the same camera, its plane normal comes
// from their 3D neighbours, and the current model predicts where it lies in every other camera.
// A candidate is used in the one camera (of those that see it) where it lies nearest the principal
// point, so that one region of the wall is one reference patch; every other camera that sees it
// is a target of the ECC alignment (subpixel.h), started from the plane homography. Each aligned
// observation gets the whitening of its covariance (AlignInfo), scaled so that the median
// observation weighs 1, floored at weight_floor times the median sigma.
std::vector<std::vector<TrackObservation>> dense_tracks(const Rig& rig, const std::vector<cv::Mat>& gray,
                                                        const std::vector<CameraFeatures>& feats, const SolveState& st,
                                                        const CalibrationOptions& opt, int* attempted, int* refined) {
  const int n = static_cast<int>(rig.cameras.size());
  const SubpixelOptions& so = opt.dense_subpixel;
  std::vector<CameraModel> model(n);
  for (int i = 0; i < n; ++i) model[i] = rig.cameras[i].model();
  // Scene points of the solution (finite ones) and, per camera, where it observed them.
  std::vector<Vec3> pts;
  struct Seen {
    Vec2 px;
    int point;
  };
  std::vector<std::vector<Seen>> seen(n);
  for (size_t ti = 0; ti < st.tracks.size(); ++ti) {
    const auto& p = st.points[ti];
    if (std::abs(p[3]) < 1e-9) continue;
    const Vec3 x = Vec3(p[0], p[1], p[2]) / p[3];
    const int id = static_cast<int>(pts.size());
    pts.push_back(x);
    for (const auto& o : st.tracks[ti]) seen[o.cam].push_back({o.px, id});
  }
  const int half = so.patch_px / 2;
  const double margin = half + 2;
  struct Job {
    TrackObservation ref;
    Vec3 x, normal;
    std::vector<int> targets;
  };
  std::vector<Job> jobs;
  for (int a = 0; a < n; ++a) {
    const RigCamera& ca = rig.cameras[a];
    if (seen[a].size() < 3) continue;
    for (const Vec2& q : feats[a].px) {
      if (q.x() < margin || q.y() < margin || q.x() > ca.in.width - margin || q.y() > ca.in.height - margin) continue;
      // The nearest observed scene points in this camera.
      std::vector<std::pair<double, int>> d;
      d.reserve(seen[a].size());
      for (const Seen& sp : seen[a]) d.emplace_back((sp.px - q).squaredNorm(), sp.point);
      const int k = std::min<int>(opt.dense_neighbours, static_cast<int>(d.size()));
      std::partial_sort(d.begin(), d.begin() + k, d.end());
      if (d[0].first > opt.dense_max_gap_px * opt.dense_max_gap_px) continue;
      std::vector<double> depth;
      for (int j = 0; j < k; ++j)
        if (d[j].first <= 4 * d[0].first + 100) depth.push_back((pts[d[j].second] - ca.position_mm).norm());
      std::nth_element(depth.begin(), depth.begin() + depth.size() / 2, depth.end());
      const Vec3 ray = model[a].unproject(q);
      const Vec3 x = ca.position_mm + depth[depth.size() / 2] * ray;
      // Plane normal: smallest principal axis of the neighbours (the ray when degenerate).
      Vec3 normal = -ray;
      if (k >= 4) {
        Vec3 mean = Vec3::Zero();
        for (int j = 0; j < k; ++j) mean += pts[d[j].second];
        mean /= k;
        Mat3 cov = Mat3::Zero();
        for (int j = 0; j < k; ++j) cov += (pts[d[j].second] - mean) * (pts[d[j].second] - mean).transpose();
        Eigen::SelfAdjointEigenSolver<Mat3> es(cov);
        if (es.eigenvalues()(0) < 0.2 * es.eigenvalues()(1)) normal = es.eigenvectors().col(0);
      }
      // Reference camera: where the point lies nearest the principal point.
      const double ra = (q - Vec2(ca.in.cu, ca.in.cv)).norm() / ca.in.fu;
      Job job{{a, q}, x, normal, {}};
      bool is_ref = true;
      for (int b = 0; b < n && is_ref; ++b) {
        if (b == a) continue;
        const RigCamera& cb = rig.cameras[b];
        const Vec3 w = x - cb.position_mm;
        if (!model[b].sees(w)) continue;
        const auto pb = model[b].project(w);
        if (!pb || pb->x() < margin || pb->y() < margin || pb->x() > cb.in.width - margin ||
            pb->y() > cb.in.height - margin)
          continue;
        if ((*pb - Vec2(cb.in.cu, cb.in.cv)).norm() / cb.in.fu < ra) is_ref = false;
        job.targets.push_back(b);
      }
      if (is_ref && !job.targets.empty()) jobs.push_back(std::move(job));
    }
  }
  struct Aligned {
    TrackObservation obs;
    Eigen::Matrix2d cov;
  };
  std::vector<std::vector<Aligned>> done(jobs.size());
  cv::parallel_for_(cv::Range(0, static_cast<int>(jobs.size())), [&](const cv::Range& r) {
    for (int k = r.start; k < r.end; ++k) {
      const Job& job = jobs[k];
      for (int b : job.targets) {
        Eigen::Matrix3d h;
        if (!plane_homography(rig.cameras[job.ref.cam], rig.cameras[b], job.ref.px, job.x, job.normal, half, &h))
          continue;
        AlignInfo info;
        const auto p = align_patch(gray[job.ref.cam], job.ref.px, gray[b], h, so, &info);
        if (p) done[k].push_back({{b, *p}, info.covariance});
      }
    }
  });
  std::vector<double> sig;
  for (size_t k = 0; k < jobs.size(); ++k) {
    *attempted += static_cast<int>(jobs[k].targets.size());
    *refined += static_cast<int>(done[k].size());
    for (const Aligned& al : done[k]) sig.push_back(std::sqrt(0.5 * al.cov.trace()));
  }
  std::vector<std::vector<TrackObservation>> out;
  if (sig.empty()) return out;
  std::nth_element(sig.begin(), sig.begin() + sig.size() / 2, sig.end());
  const double msig = sig[sig.size() / 2];
  for (size_t k = 0; k < jobs.size(); ++k) {
    if (done[k].empty()) continue;
    std::vector<TrackObservation> t;
    TrackObservation ref = jobs[k].ref;
    ref.weight = opt.dense_reference_weight * Eigen::Matrix2d::Identity();
    t.push_back(ref);
    for (Aligned& al : done[k]) {
      al.obs.weight = opt.dense_weighting ? whitening(al.cov, msig, opt.dense_weight_floor * msig)
                                          : Eigen::Matrix2d::Identity();
      t.push_back(al.obs);
    }
    out.push_back(std::move(t));
  }
  spdlog::info("calibrate: dense refinement: {} reference patches, {} of {} alignments, median sigma {:.3f} px",
               out.size(), *refined, *attempted, msig);
  return out;
}

}  // namespace

CalibrationResult calibrate_rig(const Rig& nominal, const std::vector<cv::Mat>& frames,
                                const CalibrationOptions& opt) {
  const int n = static_cast<int>(nominal.cameras.size());
  if (static_cast<int>(frames.size()) != n)
    throw std::invalid_argument(fmt::format("calibrate: {} frames for a rig of {} cameras", frames.size(), n));
  if (n < 2) throw std::invalid_argument("calibrate: the rig needs at least 2 cameras");
  for (int i = 0; i < n; ++i)
    if (frames[i].cols != nominal.cameras[i].in.width || frames[i].rows != nominal.cameras[i].in.height)
      throw std::invalid_argument(fmt::format("calibrate: frame of camera {} is {}x{}, the rig says {}x{}",
                                              nominal.cameras[i].id, frames[i].cols, frames[i].rows,
                                              nominal.cameras[i].in.width, nominal.cameras[i].in.height));
  CalibrationResult res;
  res.rig = nominal;

  // 1. Features.
  std::vector<CameraFeatures> feats(n);
  {
    Progress progress("calibrate: features", n);
    for (int i = 0; i < n; ++i) {
      feats[i] = detect_features(frames[i], opt.features);
      progress.step();
    }
  }
  // 2. Pairwise matching between overlapping cameras.
  const auto pairs = overlapping_pairs(nominal, deg2rad(opt.overlap_margin_deg));
  res.pairs = static_cast<int>(pairs.size());
  std::vector<PairMatches> pms;
  long rot_total = 0, ess_total = 0;
  {
    Progress progress("calibrate: matching", pairs.size());
    for (const auto& [a, b] : pairs) {
      PairMatches pm = match_pair(nominal, a, b, feats[a], feats[b], opt.scene, opt.match);
      res.matches += pm.putative;
      rot_total += pm.rotation_inliers;
      ess_total += pm.essential_inliers;
      pms.push_back(std::move(pm));
      progress.step();
    }
  }
  SceneModel scene = opt.scene;
  if (scene == SceneModel::kAuto) {
    // Parallax shows as matches that no rotation explains but an essential matrix does.
    scene = ess_total > opt.near_ratio * rot_total ? SceneModel::kNear : SceneModel::kFar;
    spdlog::info("calibrate: consensus over all pairs: rotation-only {}, essential matrix {} -> {} scene", rot_total,
                 ess_total, to_string(scene));
    // All pairs use the one chosen model.
    for (auto& pm : pms) pm.choose(scene, opt.match.min_inliers);
  } else {
    for (auto& pm : pms) pm.choose(scene, opt.match.min_inliers);
  }
  res.scene = scene;
  if (scene == SceneModel::kNear) {
    res.warnings.push_back(
        "near-field scene (parallax): scene points with camera positions fixed at nominal; the mean focal length "
        "is held at the nominal one (prior, the focal/depth ambiguity) and principal point trades against "
        "rotation (on the simulated colon: ~0.5 deg, ~0.7-1.1 % focal, ~2 px centre errors, panorama as good as "
        "with the true rig); prefer a far-field calibration scene for accurate intrinsics");
    spdlog::warn("calibrate: {}", res.warnings.back());
  }
  for (const auto& pm : pms) res.inliers += static_cast<int>(pm.inliers.size());
  spdlog::info("calibrate: {} cameras, {} overlapping pairs, {} matches, {} RANSAC inliers, {} scene", n,
               res.pairs, res.matches, res.inliers, to_string(scene));

  // 3. Tracks (union-find over keypoints), tracks seen twice by one camera are dropped.
  std::vector<int> offset(n + 1, 0);
  for (int i = 0; i < n; ++i) offset[i + 1] = offset[i] + static_cast<int>(feats[i].px.size());
  UnionFind uf(offset[n]);
  std::vector<char> used(offset[n], 0);
  for (const auto& pm : pms)
    for (const auto& m : pm.inliers) {
      const int ga = offset[pm.cam_a] + m.a, gb = offset[pm.cam_b] + m.b;
      uf.unite(ga, gb);
      used[ga] = used[gb] = 1;
    }
  std::map<int, std::vector<int>> groups;
  for (int g = 0; g < offset[n]; ++g)
    if (used[g]) groups[uf.find(g)].push_back(g);
  auto cam_of = [&](int g) { return static_cast<int>(std::upper_bound(offset.begin(), offset.end(), g) - offset.begin()) - 1; };
  std::vector<std::vector<Observation>> tracks;
  for (const auto& [root, members] : groups) {
    std::vector<Observation> t;
    std::vector<char> seen(n, 0);
    bool conflict = false;
    for (int g : members) {
      const int c = cam_of(g);
      if (seen[c]) conflict = true;
      seen[c] = 1;
      t.push_back({c, feats[c].px[g - offset[c]]});
    }
    if (!conflict && t.size() >= 2) tracks.push_back(std::move(t));
  }

  {
    std::vector<int> hist(6, 0);
    for (const auto& t : tracks) ++hist[std::min<size_t>(t.size(), 5)];
    spdlog::info("calibrate: {} tracks, by length 2: {}, 3: {}, 4: {}, 5+: {}", tracks.size(), hist[2], hist[3],
                 hist[4], hist[5]);
  }
  SolveState st;
  res = solve_tracks(nominal, nominal, std::move(tracks), scene, opt, std::move(res), &st);
  if (opt.refine_rounds > 0) {
    std::vector<cv::Mat> gray(n);
    const bool dense = scene == SceneModel::kNear && opt.dense_refine;
    const SubpixelOptions& so = dense ? opt.dense_subpixel : opt.subpixel;
    for (int i = 0; i < n; ++i) gray[i] = to_alignment_image(frames[i], so.flatfield_sigma_px);
    CalibrationOptions ropt = opt;
    ropt.outlier_px = opt.refine_outlier_px;
    const double initial_rms = res.initial_rms_px;
    const int rounds = dense ? opt.dense_rounds : opt.refine_rounds;
    for (int round = 0; round < rounds; ++round) {
      int attempted = 0, refined = 0;
      auto rtracks = dense ? dense_tracks(res.rig, gray, feats, st, opt, &attempted, &refined)
                           : refine_tracks(res.rig, gray, st, scene == SceneModel::kNear, opt.subpixel, &attempted, &refined);
      spdlog::info("calibrate: subpixel refinement round {}: {} of {} observations aligned, {} tracks", round + 1,
                   refined, attempted, rtracks.size());
      if (refined < opt.refine_min_fraction * attempted) {
        // Texture the alignment cannot lock onto (flat cells, repetitive patterns): keep the
        // unrefined solution rather than solve again from a few observations.
        res.warnings.push_back(fmt::format(
            "subpixel refinement skipped: only {} of {} observations aligned; the unrefined solution is kept",
            refined, attempted));
        spdlog::warn("calibrate: {}", res.warnings.back());
        break;
      }
      const Rig start = res.rig;
      res = solve_tracks(nominal, start, std::move(rtracks), scene, ropt, std::move(res), &st);
    }
    res.initial_rms_px = initial_rms;
  }
  return res;
}

std::vector<cv::Mat> average_frame_sets(const std::vector<std::vector<cv::Mat>>& sets) {
  if (sets.empty()) throw std::invalid_argument("average_frame_sets: no frame sets");
  const size_t n = sets[0].size();
  for (size_t s = 0; s < sets.size(); ++s) {
    if (sets[s].size() != n)
      throw std::invalid_argument(fmt::format("shots differ: shot {} has {} frames, shot 0 has {}", s, sets[s].size(), n));
    for (size_t i = 0; i < n; ++i) {
      const cv::Mat& f = sets[s][i];
      if (f.type() != CV_8UC3 && f.type() != CV_16UC3)
        throw std::invalid_argument(fmt::format("shot {}, camera index {}: not an 8- or 16-bit colour frame", s, i));
      if (f.size() != sets[0][i].size())
        throw std::invalid_argument(fmt::format("shots differ: camera index {} is {}x{} in shot {} but {}x{} in shot 0",
                                                i, f.cols, f.rows, s, sets[0][i].cols, sets[0][i].rows));
    }
  }
  if (sets.size() == 1) return sets[0];
  std::vector<cv::Mat> out(n);
  cv::parallel_for_(cv::Range(0, static_cast<int>(n)), [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i) {
      cv::Mat sum = decode_linear(sets[0][size_t(i)]);
      for (size_t s = 1; s < sets.size(); ++s) sum += decode_linear(sets[s][size_t(i)]);
      sum /= double(sets.size());
      cv::Mat enc(sum.size(), CV_16UC3);
      const float* src = sum.ptr<float>();
      uint16_t* dst = enc.ptr<uint16_t>();
      for (size_t k = 0; k < sum.total() * 3; ++k) dst[k] = uint16_t(std::lround(65535.0f * linear_to_srgb(src[k])));
      out[size_t(i)] = enc;
    }
  });
  return out;
}

CalibrationResult calibrate_from_tracks(const Rig& nominal, std::vector<std::vector<TrackObservation>> tracks,
                                        SceneModel scene, const CalibrationOptions& opt) {
  if (scene == SceneModel::kAuto) throw std::invalid_argument("calibrate_from_tracks: scene must be far or near");
  const int n = static_cast<int>(nominal.cameras.size());
  for (const auto& t : tracks)
    for (const auto& o : t)
      if (o.cam < 0 || o.cam >= n) throw std::invalid_argument(fmt::format("calibrate_from_tracks: camera index {} out of range", o.cam));
  CalibrationResult res;
  res.rig = nominal;
  res.scene = scene;
  return solve_tracks(nominal, nominal, std::move(tracks), scene, opt, std::move(res));
}

}  // namespace omma::calib
