#include "omma/calib/initial_pose.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include <fmt/format.h>
#include <opencv2/features2d.hpp>
#include <spdlog/spdlog.h>

namespace omma::calib {

namespace {
bool invalid(std::string* why, const std::string& what) {
  if (why) *why = what;
  return false;
}

// The camera looking along its own frame's axes: rays in its (t, u, v) coordinates.
CameraModel local_camera(const Intrinsics& in) {
  Frame f;
  f.t = Vec3::UnitX();
  f.u = Vec3::UnitY();
  f.v = Vec3::UnitZ();
  return CameraModel{f, in};
}

// Camera 0's frame: looking along +z, image right -x, image down -y (grid.h (G2): vr180's centre
// shows it upright).
Mat3 reference_rows() {
  Mat3 r;
  r << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  return r;
}
}  // namespace

bool InitialPoseOptions::IsValid(std::string* why) const {
  if (!features.IsValid(why)) return false;
  if (!(ratio > 0 && ratio <= 1)) return invalid(why, "ratio must be in (0, 1]");
  if (!(ransac_threshold_px > 0)) return invalid(why, "ransac_threshold_px must be > 0");
  if (ransac_iterations < 1) return invalid(why, "ransac_iterations must be >= 1");
  if (min_inliers < 2) return invalid(why, "min_inliers must be >= 2");
  if (!(dome_radius_mm >= 0 && dome_radius_mm < 1e6))
    return invalid(why, "dome_radius_mm must be in [0, 1e6)");
  return true;
}

PixelMatches match_features(const CameraFeatures& fa, const CameraFeatures& fb, double ratio) {
  PixelMatches out;
  if (fa.descriptors.rows < 2 || fb.descriptors.rows < 2) return out;
  cv::BFMatcher matcher(cv::NORM_L2);
  std::vector<std::vector<cv::DMatch>> ab, ba;
  matcher.knnMatch(fa.descriptors, fb.descriptors, ab, 2);
  matcher.knnMatch(fb.descriptors, fa.descriptors, ba, 1);
  for (const auto& m : ab) {
    if (m.size() < 2 || m[0].distance > ratio * m[1].distance) continue;
    const int ia = m[0].queryIdx, ib = m[0].trainIdx;
    if (ba[ib].empty() || ba[ib][0].trainIdx != ia) continue;  // mutual best
    out.a.push_back(fa.px[ia]);
    out.b.push_back(fb.px[ib]);
  }
  return out;
}

PairPose estimate_pair_rotation(const Intrinsics& in_a, const Intrinsics& in_b, const PixelMatches& m,
                                const InitialPoseOptions& opt, std::vector<bool>* inlier_mask) {
  if (m.a.size() != m.b.size())
    throw std::invalid_argument("estimate_pair_rotation: a and b differ in length");
  PairPose p;
  const int n = static_cast<int>(m.a.size());
  p.matches = n;
  if (inlier_mask) inlier_mask->assign(n, false);
  if (n < 2) return p;
  const CameraModel ca = local_camera(in_a), cb = local_camera(in_b);
  std::vector<Vec3> da(n), db(n);
  for (int i = 0; i < n; ++i) {
    da[i] = ca.unproject(m.a[i]);
    db[i] = cb.unproject(m.b[i]);
  }
  const double f = std::max({in_a.fu, in_a.fv, in_b.fu, in_b.fv});
  const double thr = opt.ransac_threshold_px / f;  // radians
  const double cos_thr = std::cos(thr);
  std::mt19937 rng(opt.seed);
  std::uniform_int_distribution<int> pick(0, n - 1);
  auto consensus = [&](const Mat3& q, std::vector<int>* in) {
    int c = 0;
    for (int i = 0; i < n; ++i)
      if ((q * da[i]).dot(db[i]) > cos_thr) {
        ++c;
        if (in) in->push_back(i);
      }
    return c;
  };
  Mat3 best = Mat3::Identity();
  int best_count = -1;
  for (int it = 0; it < opt.ransac_iterations; ++it) {
    const int i = pick(rng), j = pick(rng);
    if (i == j) continue;
    // A degenerate sample: the two rays (nearly) parallel in either camera.
    if (da[i].cross(da[j]).norm() < 4 * thr || db[i].cross(db[j]).norm() < 4 * thr) continue;
    // The two rays' angle must agree in both cameras (a rotation keeps it).
    if (std::abs(std::acos(std::clamp(da[i].dot(da[j]), -1.0, 1.0)) -
                 std::acos(std::clamp(db[i].dot(db[j]), -1.0, 1.0))) > 2 * thr)
      continue;
    const Mat3 q = fit_rotation({da[i], da[j]}, {db[i], db[j]});
    const int c = consensus(q, nullptr);
    if (c > best_count) {
      best_count = c;
      best = q;
    }
  }
  if (best_count < 2) return p;
  // Refit on the consensus set, twice (the set may grow with the better rotation).
  std::vector<int> in;
  for (int round = 0; round < 2; ++round) {
    in.clear();
    consensus(best, &in);
    if (in.size() < 2) break;
    std::vector<Vec3> a, b;
    for (int i : in) {
      a.push_back(da[i]);
      b.push_back(db[i]);
    }
    best = fit_rotation(a, b);
  }
  in.clear();
  p.inliers = consensus(best, &in);
  p.rotation = best;
  double ss = 0;
  for (int i : in) {
    const auto px = cb.project(best * da[i]);
    if (px) ss += (*px - m.b[i]).squaredNorm();
    if (inlier_mask) (*inlier_mask)[i] = true;
  }
  p.rms_px = in.empty() ? 0 : std::sqrt(ss / in.size());
  return p;
}

InitialPoseSummary initial_pose(const std::vector<cv::Mat>& images, const std::vector<Intrinsics>& intrinsics,
                                const InitialPoseOptions& opt) {
  std::string why;
  if (!opt.IsValid(&why)) throw std::invalid_argument("initial_pose: " + why);
  const int n = static_cast<int>(images.size());
  if (n < 1) throw std::invalid_argument("initial_pose: no images");
  if (static_cast<int>(intrinsics.size()) != n)
    throw std::invalid_argument(
        fmt::format("initial_pose: {} images but {} cameras' intrinsics", n, intrinsics.size()));
  for (int i = 0; i < n; ++i) {
    if (images[i].empty())
      throw std::invalid_argument(fmt::format("initial_pose: camera {}: empty image", i));
    if (images[i].cols != intrinsics[i].width || images[i].rows != intrinsics[i].height)
      throw std::invalid_argument(
          fmt::format("initial_pose: camera {}: image is {}x{} but its intrinsics say {}x{}", i,
                      images[i].cols, images[i].rows, intrinsics[i].width, intrinsics[i].height));
  }
  std::vector<CameraFeatures> feats(n);
  for (int i = 0; i < n; ++i) feats[i] = detect_features(images[i], opt.features);

  std::vector<PairPose> pairs;
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) {
      PairPose p = estimate_pair_rotation(intrinsics[a], intrinsics[b],
                                          match_features(feats[a], feats[b], opt.ratio), opt);
      p.cam_a = a;
      p.cam_b = b;
      spdlog::debug("initial_pose: cameras {}-{}: {} matches, {} inliers, rms {:.2f} px", a, b, p.matches,
                    p.inliers, p.rms_px);
      pairs.push_back(p);
    }
  return initial_pose_from_pairs(intrinsics, std::move(pairs), opt);
}

InitialPoseSummary initial_pose_from_pairs(const std::vector<Intrinsics>& intrinsics,
                                           std::vector<PairPose> pairs, const InitialPoseOptions& opt) {
  std::string why;
  if (!opt.IsValid(&why)) throw std::invalid_argument("initial_pose: " + why);
  const int n = static_cast<int>(intrinsics.size());
  if (n < 1) throw std::invalid_argument("initial_pose: no cameras");
  for (const auto& p : pairs)
    if (p.cam_a < 0 || p.cam_b < 0 || p.cam_a >= n || p.cam_b >= n || p.cam_a == p.cam_b)
      throw std::invalid_argument(
          fmt::format("initial_pose: bad pair {}-{} of {} cameras", p.cam_a, p.cam_b, n));
  InitialPoseSummary res;
  res.pairs = std::move(pairs);
  // Prim's maximum spanning tree from camera 0 over pairs with min_inliers.
  std::vector<Mat3> rows(n, Mat3::Identity());
  std::vector<bool> placed(n, false);
  placed[0] = true;
  rows[0] = reference_rows();
  for (int added = 1; added < n; ++added) {
    int best = -1;
    for (int k = 0; k < static_cast<int>(res.pairs.size()); ++k) {
      const PairPose& p = res.pairs[k];
      if (p.inliers < opt.min_inliers || placed[p.cam_a] == placed[p.cam_b]) continue;
      if (best < 0 || p.inliers > res.pairs[best].inliers) best = k;
    }
    if (best < 0) break;
    PairPose& p = res.pairs[best];
    p.in_tree = true;
    // d = R w in each camera; d_b = Q d_a  =>  R_b = Q R_a, R_a = Q^T R_b.
    if (placed[p.cam_a]) {
      rows[p.cam_b] = p.rotation * rows[p.cam_a];
      placed[p.cam_b] = true;
    } else {
      rows[p.cam_a] = p.rotation.transpose() * rows[p.cam_b];
      placed[p.cam_a] = true;
    }
  }
  std::string missing;
  for (int i = 0; i < n; ++i)
    if (!placed[i]) missing += (missing.empty() ? "" : ", ") + std::to_string(i);
  if (!missing.empty())
    throw std::runtime_error(fmt::format(
        "initial_pose: camera(s) {} share no overlap of at least {} rotation-consistent matches with the "
        "others (check that neighbouring pictures overlap, and the focal length)",
        missing, opt.min_inliers));

  res.rig.name = opt.name;
  res.rig.dome.radius_mm = opt.dome_radius_mm;
  res.rig.dome.sphere = true;
  res.rig.dome.method = "initial-pose";
  for (int i = 0; i < n; ++i) {
    RigCamera c;
    c.id = i;
    c.frame.t = rows[i].row(0).transpose();
    c.frame.u = rows[i].row(1).transpose();
    c.frame.v = rows[i].row(2).transpose();
    c.position_mm = opt.dome_radius_mm * c.frame.t;
    c.in = intrinsics[i];
    res.rig.cameras.push_back(c);
  }
  res.rig.validate();
  return res;
}

Intrinsics intrinsics_from_focal(int width, int height, double focal_px) {
  if (width < 1 || height < 1 || !(focal_px > 0))
    throw std::invalid_argument(
        fmt::format("intrinsics: bad size {}x{} or focal {} px", width, height, focal_px));
  Intrinsics in;
  in.width = width;
  in.height = height;
  in.fu = in.fv = focal_px;
  in.cu = width / 2.0;
  in.cv = height / 2.0;
  in.k = {};
  in.field = Intrinsics::Field::kImage;
  in.aov = in.bounding_aov();
  return in;
}

Intrinsics intrinsics_from_diagonal_fov(int width, int height, double diagonal_fov_deg) {
  if (!(diagonal_fov_deg > 0 && diagonal_fov_deg < 180))
    throw std::invalid_argument(
        fmt::format("intrinsics: diagonal field of view {} deg not in (0, 180)", diagonal_fov_deg));
  const double half_diag = 0.5 * std::hypot(width, height);
  return intrinsics_from_focal(width, height, half_diag / std::tan(deg2rad(diagonal_fov_deg) / 2));
}

}  // namespace omma::calib
