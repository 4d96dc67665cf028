#include "omma/calib/refine.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include <Eigen/Eigenvalues>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/utility.hpp>

#include "omma/core/log.h"

namespace omma::calib {
namespace {

// The homography (continuous pixels of camera a -> camera b) of the scene plane through x (dome
// frame, mm) with normal `normal`, fitted to a 5 x 5 grid of points within +-half pixels of pa;
// false if the plane is seen edge-on or a point leaves a camera.
bool plane_homography(const RigCamera& ca, const RigCamera& cb, const Vec2& pa, const Vec3& x,
                      const Vec3& normal, double half, Eigen::Matrix3d* h) {
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

// A whitening matrix W = scale * Sigma^-1/2 (eigenvalues of Sigma floored at floor_px^2).
Eigen::Matrix2d whitening(const Eigen::Matrix2d& cov, double scale, double floor_px) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(cov);
  const Eigen::Vector2d ev = es.eigenvalues().cwiseMax(floor_px * floor_px);
  return scale *
         (es.eigenvectors() * ev.cwiseSqrt().cwiseInverse().asDiagonal() * es.eigenvectors().transpose());
}

// A scene point as one camera observed it: its pixel and its index into the scene points.
struct Seen {
  Vec2 px;
  int point;
};

// A dense alignment job: a reference pixel, its scene plane and the cameras to find it in.
struct DenseJob {
  TrackObservation ref;
  Vec3 x, normal;
  std::vector<int> targets;
};

// One alignment of a dense job: the observation found and its covariance (px^2).
struct Aligned {
  TrackObservation obs;
  Eigen::Matrix2d cov;
};

// The finite scene points of the solution (dome frame, mm), appended to pts, and per camera
// where it observed them.
std::vector<std::vector<Seen>> observed_points(const SolveState& st, int n, std::vector<Vec3>& pts) {
  std::vector<std::vector<Seen>> seen(n);
  for (size_t ti = 0; ti < st.tracks.size(); ++ti) {
    const auto& p = st.points[ti];
    if (std::abs(p[3]) < 1e-9) continue;
    const Vec3 x = Vec3(p[0], p[1], p[2]) / p[3];
    const int id = static_cast<int>(pts.size());
    pts.push_back(x);
    for (const auto& o : st.tracks[ti]) seen[o.cam].push_back({o.px, id});
  }
  return seen;
}

// The normal of the scene plane through the k nearest points d (squared distance, index into
// pts): their smallest principal axis, or -ray when degenerate.
Vec3 plane_normal(const std::vector<Vec3>& pts, const std::vector<std::pair<double, int>>& d, int k,
                  const Vec3& ray) {
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
  return normal;
}

// The dense job of feature q of camera a (continuous px), its depth and plane from the nearest
// observed scene points; nullopt if q is too near the border or too far from them, if another
// camera sees it nearer its principal point, or if no other camera sees it.
std::optional<DenseJob> dense_job(const Rig& rig, const std::vector<CameraModel>& model,
                                  const std::vector<Vec3>& pts, const std::vector<Seen>& seen_a, int a,
                                  const Vec2& q, const CalibrationOptions& opt, double margin) {
  const int n = static_cast<int>(rig.cameras.size());
  const RigCamera& ca = rig.cameras[a];
  if (q.x() < margin || q.y() < margin || q.x() > ca.in.width - margin || q.y() > ca.in.height - margin)
    return std::nullopt;
  // The nearest observed scene points in this camera.
  std::vector<std::pair<double, int>> d;
  d.reserve(seen_a.size());
  for (const Seen& sp : seen_a) d.emplace_back((sp.px - q).squaredNorm(), sp.point);
  const int k = std::min<int>(opt.dense_neighbours, static_cast<int>(d.size()));
  std::partial_sort(d.begin(), d.begin() + k, d.end());
  if (d[0].first > opt.dense_max_gap_px * opt.dense_max_gap_px) return std::nullopt;
  std::vector<double> depth;
  for (int j = 0; j < k; ++j)
    if (d[j].first <= 4 * d[0].first + 100) depth.push_back((pts[d[j].second] - ca.position_mm).norm());
  std::nth_element(depth.begin(), depth.begin() + depth.size() / 2, depth.end());
  const Vec3 ray = model[a].unproject(q);
  const Vec3 x = ca.position_mm + depth[depth.size() / 2] * ray;
  // Plane normal: smallest principal axis of the neighbours (the ray when degenerate).
  const Vec3 normal = plane_normal(pts, d, k, ray);
  // Reference camera: where the point lies nearest the principal point.
  const double ra = (q - Vec2(ca.in.cu, ca.in.cv)).norm() / ca.in.fu;
  DenseJob job{{a, q}, x, normal, {}};
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
  if (is_ref && !job.targets.empty()) return job;
  return std::nullopt;
}

// The dense jobs of every feature of every camera that observed at least 3 scene points.
std::vector<DenseJob> dense_jobs(const Rig& rig, const std::vector<CameraModel>& model,
                                 const std::vector<CameraFeatures>& feats, const std::vector<Vec3>& pts,
                                 const std::vector<std::vector<Seen>>& seen, const CalibrationOptions& opt,
                                 double margin) {
  const int n = static_cast<int>(rig.cameras.size());
  std::vector<DenseJob> jobs;
  for (int a = 0; a < n; ++a) {
    if (seen[a].size() < 3) continue;
    for (const Vec2& q : feats[a].px) {
      auto job = dense_job(rig, model, pts, seen[a], a, q, opt, margin);
      if (job) jobs.push_back(std::move(*job));
    }
  }
  return jobs;
}

// Per job, the alignments of its reference patch (half-size half px) in its target cameras that
// succeeded.
std::vector<std::vector<Aligned>> align_dense_jobs(const Rig& rig, const std::vector<cv::Mat>& gray,
                                                   const std::vector<DenseJob>& jobs,
                                                   const SubpixelOptions& so, int half) {
  std::vector<std::vector<Aligned>> done(jobs.size());
  cv::parallel_for_(cv::Range(0, static_cast<int>(jobs.size())), [&](const cv::Range& r) {
    for (int k = r.start; k < r.end; ++k) {
      const DenseJob& job = jobs[k];
      for (int b : job.targets) {
        Eigen::Matrix3d h;
        if (!plane_homography(rig.cameras[job.ref.cam], rig.cameras[b], job.ref.px, job.x, job.normal, half,
                              &h))
          continue;
        AlignInfo info;
        const auto p = align_patch(gray[job.ref.cam], job.ref.px, gray[b], h, so, &info);
        if (p) done[k].push_back({{b, *p}, info.covariance});
      }
    }
  });
  return done;
}

}  // namespace

std::vector<std::vector<TrackObservation>> refine_tracks(const Rig& rig, const std::vector<cv::Mat>& gray,
                                                         const SolveState& st, bool near,
                                                         const SubpixelOptions& so, int* attempted,
                                                         int* refined) {
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
    for (int k = 0; k < kNeighbours; ++k)
      cov += (x[d[k].second] - mean) * (x[d[k].second] - mean).transpose();
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

std::vector<std::vector<TrackObservation>> dense_tracks(const Rig& rig, const std::vector<cv::Mat>& gray,
                                                        const std::vector<CameraFeatures>& feats,
                                                        const SolveState& st, const CalibrationOptions& opt,
                                                        int* attempted, int* refined) {
  const int n = static_cast<int>(rig.cameras.size());
  const SubpixelOptions& so = opt.dense_subpixel;
  std::vector<CameraModel> model(n);
  for (int i = 0; i < n; ++i) model[i] = rig.cameras[i].model();
  // Scene points of the solution (finite ones) and, per camera, where it observed them.
  std::vector<Vec3> pts;
  const std::vector<std::vector<Seen>> seen = observed_points(st, n, pts);
  const int half = so.patch_px / 2;
  const double margin = half + 2;
  const std::vector<DenseJob> jobs = dense_jobs(rig, model, feats, pts, seen, opt, margin);
  std::vector<std::vector<Aligned>> done = align_dense_jobs(rig, gray, jobs, so, half);
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
  spdlog::info(
      "calibrate: dense refinement: {} reference patches, {} of {} alignments, median sigma {:.3f} px",
      out.size(), *refined, *attempted, msig);
  return out;
}

}  // namespace omma::calib
