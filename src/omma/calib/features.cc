#include "omma/calib/features.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <random>
#include <stdexcept>

#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "omma/core/valid.h"

namespace omma::calib {

bool FeatureOptions::IsValid(std::string* why) const {
  if (max_features < 0) return invalid(why, "max_features must be >= 0 (0: every keypoint SIFT finds)");
  if (!(contrast_threshold > 0)) return invalid(why, "contrast_threshold must be > 0");
  if (border_px < 0) return invalid(why, "border_px must be >= 0");
  if (upsample < 1 || upsample > 8) return invalid(why, "upsample must be 1..8");
  if (!(blur_sigma >= 0) || !(clahe_clip >= 0) || clahe_below < 0)
    return invalid(why, "blur_sigma, clahe_clip and clahe_below must be >= 0");
  return true;
}

bool MatchOptions::IsValid(std::string* why) const {
  if (!(ratio > 0 && ratio <= 1)) return invalid(why, "ratio must be in (0, 1]");
  if (!(self_ratio >= 0 && self_ratio <= 1)) return invalid(why, "self_ratio must be in [0, 1]");
  if (!(overlap_margin_deg >= 0 && overlap_margin_deg < 180))
    return invalid(why, "overlap_margin_deg must be in [0, 180)");
  if (!(ransac_threshold_px > 0)) return invalid(why, "ransac_threshold_px must be > 0");
  if (ransac_iterations < 1) return invalid(why, "ransac_iterations must be >= 1");
  if (min_inliers < 1) return invalid(why, "min_inliers must be >= 1");
  return true;
}

constexpr double kSiftToContinuous = 0.25;

namespace {
CameraFeatures detect(const cv::Mat& gray_in, const FeatureOptions& opt, bool clahe) {
  cv::Mat gray = gray_in;
  if (clahe) {
    auto eq = cv::createCLAHE(opt.clahe_clip, cv::Size(4, 4));
    cv::Mat out;
    eq->apply(gray, out);
    gray = out;
  }
  const int up = std::max(1, opt.upsample);
  if (up > 1) cv::resize(gray, gray, cv::Size(), up, up, cv::INTER_CUBIC);
  auto sift = cv::SIFT::create(opt.max_features, 3, opt.contrast_threshold);
  std::vector<cv::KeyPoint> kps;
  cv::Mat desc;
  sift->detectAndCompute(gray, cv::noArray(), kps, desc);
  CameraFeatures f;
  std::vector<int> keep;
  const double border = opt.border_px * up;
  for (size_t i = 0; i < kps.size(); ++i) {
    const auto& p = kps[i].pt;
    if (p.x < border || p.y < border || p.x > gray.cols - 1 - border || p.y > gray.rows - 1 - border)
      continue;
    keep.push_back(static_cast<int>(i));
    // OpenCV's SIFT works on the image upsampled 2x (resize INTER_LINEAR: upsampled pixel i looks
    // at source i/2 - 0.25 in integer-centre coordinates) and reports pt = i/2, so the source
    // position is pt - 0.25 with centres at integers, i.e. pt + 0.25 in our convention (+0.5).
    // Our own upsampling by `up` keeps pixel-centre alignment: continuous source = continuous / up.
    f.px.emplace_back((p.x + kSiftToContinuous) / up, (p.y + kSiftToContinuous) / up);
  }
  f.descriptors = cv::Mat(static_cast<int>(keep.size()), desc.cols > 0 ? desc.cols : 128, CV_32F);
  for (size_t r = 0; r < keep.size(); ++r) desc.row(keep[r]).copyTo(f.descriptors.row(static_cast<int>(r)));
  return f;
}
}  // namespace

CameraFeatures detect_features(const cv::Mat& image, const FeatureOptions& opt) {
  std::string why;
  if (!opt.IsValid(&why)) throw std::invalid_argument("detect_features: " + why);
  cv::Mat gray = image;
  if (gray.channels() == 3) cv::cvtColor(gray, gray, cv::COLOR_BGR2GRAY);
  if (gray.channels() == 4) cv::cvtColor(gray, gray, cv::COLOR_BGRA2GRAY);
  if (gray.depth() == CV_16U) gray.convertTo(gray, CV_8U, 1.0 / 257);
  if (gray.depth() == CV_32F) gray.convertTo(gray, CV_8U, 255.0);
  if (opt.blur_sigma > 0) cv::GaussianBlur(gray, gray, cv::Size(), opt.blur_sigma);
  CameraFeatures f = detect(gray, opt, false);
  if (opt.clahe_clip > 0 && static_cast<int>(f.px.size()) < opt.clahe_below) {
    CameraFeatures g = detect(gray, opt, true);
    if (g.px.size() > f.px.size()) f = std::move(g);
  }
  return f;
}

std::vector<std::pair<int, int>> overlapping_pairs(const Rig& rig, double margin_rad) {
  std::vector<std::pair<int, int>> pairs;
  const int n = static_cast<int>(rig.cameras.size());
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) {
      const auto& ca = rig.cameras[a];
      const auto& cb = rig.cameras[b];
      if (angle_between(ca.frame.t, cb.frame.t) < 0.5 * (ca.in.aov + cb.in.aov) - margin_rad)
        pairs.emplace_back(a, b);
    }
  return pairs;
}

SceneModel parse_scene_model(const std::string& name) {
  if (name == "far") return SceneModel::kFar;
  if (name == "near") return SceneModel::kNear;
  if (name == "auto") return SceneModel::kAuto;
  throw std::invalid_argument("unknown scene model '" + name + "' (expected far, near or auto)");
}

std::string to_string(SceneModel m) {
  switch (m) {
    case SceneModel::kFar:
      return "far";
    case SceneModel::kNear:
      return "near";
    default:
      return "auto";
  }
}

Mat3 fit_rotation(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  Mat3 h = Mat3::Zero();
  for (size_t i = 0; i < a.size(); ++i) h += b[i] * a[i].transpose();
  Eigen::JacobiSVD<Mat3> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 d = Mat3::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0) d(2, 2) = -1;
  return svd.matrixU() * d * svd.matrixV().transpose();
}

namespace {

// Ratio test + mutual nearest neighbours between the keypoint subsets ia (of a) and ib (of b).
// Per row of d: the distance to its nearest OTHER row (its twin in the same image; +inf if none).
std::vector<float> twin_distance(const cv::Mat& d) {
  std::vector<float> out(static_cast<size_t>(d.rows), std::numeric_limits<float>::infinity());
  if (d.rows < 2) return out;
  cv::BFMatcher matcher(cv::NORM_L2);
  std::vector<std::vector<cv::DMatch>> m;
  matcher.knnMatch(d, d, m, 2);
  for (const auto& v : m)
    for (const auto& x : v)
      if (x.trainIdx != x.queryIdx) {
        out[size_t(x.queryIdx)] = x.distance;
        break;
      }
  return out;
}

std::vector<Match> ratio_matches(const CameraFeatures& fa, const CameraFeatures& fb,
                                 const std::vector<int>& ia, const std::vector<int>& ib, double ratio,
                                 double self_ratio) {
  std::vector<Match> out;
  if (ia.size() < 2 || ib.size() < 2) return out;
  cv::Mat da(static_cast<int>(ia.size()), fa.descriptors.cols, CV_32F);
  cv::Mat db(static_cast<int>(ib.size()), fb.descriptors.cols, CV_32F);
  for (size_t i = 0; i < ia.size(); ++i) fa.descriptors.row(ia[i]).copyTo(da.row(static_cast<int>(i)));
  for (size_t i = 0; i < ib.size(); ++i) fb.descriptors.row(ib[i]).copyTo(db.row(static_cast<int>(i)));
  cv::BFMatcher matcher(cv::NORM_L2);
  std::vector<std::vector<cv::DMatch>> ab, ba;
  matcher.knnMatch(da, db, ab, 2);
  matcher.knnMatch(db, da, ba, 1);
  std::vector<float> twin_a, twin_b;
  if (self_ratio > 0) twin_a = twin_distance(da), twin_b = twin_distance(db);
  for (const auto& m : ab) {
    if (m.size() < 2 || m[0].distance > ratio * m[1].distance) continue;
    const int qa = m[0].queryIdx, qb = m[0].trainIdx;
    if (ba[qb].empty() || ba[qb][0].trainIdx != qa) continue;  // mutual nearest neighbours
    if (self_ratio > 0 &&
        (m[0].distance > self_ratio * twin_a[size_t(qa)] || m[0].distance > self_ratio * twin_b[size_t(qb)]))
      continue;  // a keypoint with a look-alike in its own image (repetitive texture)
    out.push_back({ia[qa], ib[qb]});
  }
  return out;
}

// Keypoints of camera `from` whose nominal direction falls inside the cone of camera `to`,
// widened by `margin` radians (the overlap region; everything else cannot match).
std::vector<int> in_overlap(const CameraModel& from, const CameraFeatures& f, const CameraModel& to,
                            double margin) {
  std::vector<int> idx;
  const double cos_lim = std::cos(std::min(kPi / 2, to.in.aov / 2 + margin));
  for (size_t i = 0; i < f.px.size(); ++i)
    if (from.unproject(f.px[i]).dot(to.frame.t) >= cos_lim) idx.push_back(static_cast<int>(i));
  return idx;
}

}  // namespace

PairMatches match_pair(const Rig& nominal, int cam_a, int cam_b, const CameraFeatures& fa,
                       const CameraFeatures& fb, SceneModel model, const MatchOptions& opt) {
  std::string why;
  if (!opt.IsValid(&why)) throw std::invalid_argument("match_pair: " + why);
  PairMatches pm;
  pm.cam_a = cam_a;
  pm.cam_b = cam_b;
  const CameraModel ma = nominal.cameras[cam_a].model();
  const CameraModel mb = nominal.cameras[cam_b].model();
  const double margin = deg2rad(opt.overlap_margin_deg);
  const std::vector<Match> cand = ratio_matches(fa, fb, in_overlap(ma, fa, mb, margin),
                                                in_overlap(mb, fb, ma, margin), opt.ratio, opt.self_ratio);
  pm.putative = static_cast<int>(cand.size());
  pm.putative_set = cand;
  if (pm.putative < std::max(opt.min_inliers, 3)) return pm;

  const double f = 0.25 * (ma.in.fu + ma.in.fv + mb.in.fu + mb.in.fv);
  const double thr = opt.ransac_threshold_px / f;  // radians (small angles)
  const int n = static_cast<int>(cand.size());
  std::vector<Vec3> da(n), db(n);
  for (int i = 0; i < n; ++i) {
    da[i] = ma.unproject(fa.px[cand[i].a]);
    db[i] = mb.unproject(fb.px[cand[i].b]);
  }

  // Rotation-only RANSAC (far field): d_b = R d_a.
  std::mt19937 rng(opt.seed + 7919u * cam_a + cam_b);
  std::uniform_int_distribution<int> pick(0, n - 1);
  auto consensus = [&](const Mat3& r, std::vector<int>* idx) {
    int count = 0;
    for (int i = 0; i < n; ++i)
      if (angle_between(r * da[i], db[i]) < thr) {
        ++count;
        if (idx) idx->push_back(i);
      }
    return count;
  };
  Mat3 best = Mat3::Identity();
  int best_count = consensus(best, nullptr);
  for (int it = 0; it < opt.ransac_iterations; ++it) {
    const int i = pick(rng), j = pick(rng);
    if (i == j || angle_between(da[i], da[j]) < 0.02) continue;
    const Mat3 r = fit_rotation({da[i], da[j]}, {db[i], db[j]});
    const int c = consensus(r, nullptr);
    if (c > best_count) best_count = c, best = r;
  }
  std::vector<int> rot_idx;
  for (int round = 0; round < 2; ++round) {  // refit on the consensus set
    rot_idx.clear();
    consensus(best, &rot_idx);
    if (rot_idx.size() < 3) break;
    std::vector<Vec3> sa, sb;
    for (int i : rot_idx) sa.push_back(da[i]), sb.push_back(db[i]);
    best = fit_rotation(sa, sb);
  }
  rot_idx.clear();
  pm.rotation_inliers = consensus(best, &rot_idx);
  pm.rotation = best;

  if (model != SceneModel::kFar && n >= 5) {
    // Essential-matrix RANSAC (near field, parallax) on nominal normalised coordinates.
    std::vector<cv::Point2d> pa(n), pb(n);
    for (int i = 0; i < n; ++i) {
      const Vec3 ca = ma.frame.dome_to_camera() * da[i];
      const Vec3 cb = mb.frame.dome_to_camera() * db[i];
      pa[i] = {ca.y() / ca.x(), ca.z() / ca.x()};
      pb[i] = {cb.y() / cb.x(), cb.z() / cb.x()};
    }
    cv::Mat mask;
    cv::Mat e = cv::findEssentialMat(pa, pb, 1.0, cv::Point2d(0, 0), cv::RANSAC, 0.999, thr, mask);
    std::vector<int> ess_idx;
    if (!e.empty() && !mask.empty())
      for (int i = 0; i < n; ++i)
        if (mask.at<uchar>(i)) ess_idx.push_back(i);
    pm.essential_inliers = static_cast<int>(ess_idx.size());
    for (int i : ess_idx) pm.essential_set.push_back(cand[i]);
  }
  for (int i : rot_idx) pm.rotation_set.push_back(cand[i]);
  pm.choose(model, opt.min_inliers);
  return pm;
}

void PairMatches::choose(SceneModel model, int min_inliers) {
  const bool near = model == SceneModel::kNear || (model == SceneModel::kAuto && prefers_near());
  inliers = near ? essential_set : rotation_set;
  if (static_cast<int>(inliers.size()) < min_inliers) inliers.clear();
}

namespace {
struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(int n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(int a, int b) { parent[find(a)] = find(b); }
};
}  // namespace

std::vector<std::vector<TrackObservation>> build_tracks(const std::vector<CameraFeatures>& feats,
                                                        const std::vector<PairMatches>& pairs) {
  const int n = static_cast<int>(feats.size());
  std::vector<int> offset(n + 1, 0);
  for (int i = 0; i < n; ++i) offset[i + 1] = offset[i] + static_cast<int>(feats[i].px.size());
  UnionFind uf(offset[n]);
  std::vector<char> used(offset[n], 0);
  for (const auto& pm : pairs)
    for (const auto& m : pm.inliers) {
      const int ga = offset[pm.cam_a] + m.a, gb = offset[pm.cam_b] + m.b;
      uf.unite(ga, gb);
      used[ga] = used[gb] = 1;
    }
  std::map<int, std::vector<int>> groups;
  for (int g = 0; g < offset[n]; ++g)
    if (used[g]) groups[uf.find(g)].push_back(g);
  auto cam_of = [&](int g) {
    return static_cast<int>(std::upper_bound(offset.begin(), offset.end(), g) - offset.begin()) - 1;
  };
  std::vector<std::vector<TrackObservation>> tracks;
  for (const auto& [root, members] : groups) {
    std::vector<TrackObservation> t;
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
  return tracks;
}

}  // namespace omma::calib
