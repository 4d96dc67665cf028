#include "omma/testing/real_stereo.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace omma::testing {
namespace fs = std::filesystem;

StereoPairs load_stereo_pairs(const fs::path& dir) {
  StereoPairs p;
  p.dir = dir;
  if (dir.empty()) return p;
  for (int s = 1; s <= 14; ++s) {
    const fs::path lp = dir / fmt::format("left{:02d}.jpg", s), rp = dir / fmt::format("right{:02d}.jpg", s);
    if (!fs::exists(lp) || !fs::exists(rp)) continue;  // left10 / right10 are missing
    cv::Mat l = cv::imread(lp.string(), cv::IMREAD_GRAYSCALE),
            r = cv::imread(rp.string(), cv::IMREAD_GRAYSCALE);
    if (l.empty()) throw std::runtime_error("real stereo pairs: cannot read " + lp.string());
    if (r.empty()) throw std::runtime_error("real stereo pairs: cannot read " + rp.string());
    p.ids.push_back(s), p.left.push_back(l), p.right.push_back(r);
  }
  return p;
}

StereoTruth stereo_chessboard_truth(const StereoPairs& pairs) {
  const cv::Size board(9, 6);
  const double square_mm = 25;
  std::vector<cv::Point3f> grid;
  for (int y = 0; y < board.height; ++y)
    for (int x = 0; x < board.width; ++x) grid.emplace_back(float(x * square_mm), float(y * square_mm), 0.f);
  std::vector<std::vector<cv::Point3f>> obj;
  std::vector<std::vector<cv::Point2f>> pts[2];
  StereoTruth t;
  for (size_t s = 0; s < pairs.left.size(); ++s) {
    std::vector<cv::Point2f> c[2];
    bool ok = true;
    for (int cam = 0; cam < 2 && ok; ++cam) {
      const cv::Mat& g = cam ? pairs.right[s] : pairs.left[s];
      ok = cv::findChessboardCorners(g, board, c[cam],
                                     cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
      if (ok)
        cv::cornerSubPix(g, c[cam], cv::Size(11, 11), cv::Size(-1, -1),
                         cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 0.01));
    }
    for (int cam = 0; cam < 2; ++cam) t.corners[cam].push_back(ok ? c[cam] : std::vector<cv::Point2f>{});
    if (!ok) continue;
    obj.push_back(grid);
    pts[0].push_back(c[0]);
    pts[1].push_back(c[1]);
  }
  if (obj.size() < 3)
    throw std::runtime_error(
        fmt::format("real stereo pairs: the chessboard was found in both images of {} shots "
                    "(fewer than 3) in '{}'",
                    obj.size(), pairs.dir.string()));
  t.views = static_cast<int>(obj.size());
  const cv::Size size = pairs.left[0].size();
  for (int cam = 0; cam < 2; ++cam) {
    std::vector<cv::Mat> rv, tv;
    t.rms_mono[cam] = cv::calibrateCamera(obj, pts[cam], size, t.k[cam], t.d[cam], rv, tv);
  }
  cv::Mat r, tt, e, f;
  t.rms_stereo = cv::stereoCalibrate(obj, pts[0], pts[1], t.k[0], t.d[0], t.k[1], t.d[1], size, r, tt, e, f,
                                     cv::CALIB_FIX_INTRINSIC);
  cv::cv2eigen(r, t.r);
  cv::cv2eigen(tt, t.t);
  return t;
}

Rig stereo_start_rig(const StereoTruth& truth, const StereoStartOptions& opt) {
  Rig rig;
  rig.name = opt.name;
  rig.dome.radius_mm = opt.dome_radius_mm;
  const double angle = deg2rad(opt.pose_deg);
  for (int cam = 0; cam < 2; ++cam) {
    RigCamera c;
    c.id = cam;
    c.in.width = 640;
    c.in.height = 480;
    c.in.fu = opt.focal_rel * truth.k[cam].at<double>(0, 0);
    c.in.fv = opt.focal_rel * truth.k[cam].at<double>(1, 1);
    c.in.cu = 320;
    c.in.cv = 240;
    c.in.k = {0, 0, 0, 0, 0};
    c.in.aov = deg2rad(80);
    Mat3 r = Mat3::Identity();
    if (cam == 1) {
      r = Eigen::AngleAxisd(angle, opt.axis.normalized()).matrix() * truth.r;
      const Vec3 b = truth.right_centre_mm();
      const Vec3 a = opt.baseline_axis.isZero(0) ? opt.axis : opt.baseline_axis;
      const Vec3 normal = b.cross(a).norm() > 1e-6 ? b.cross(a) : b.unitOrthogonal();
      c.position_mm = Eigen::AngleAxisd(angle, normal.normalized()).matrix() * b;
    }
    c.frame.u = r.row(0).transpose();
    c.frame.v = r.row(1).transpose();
    c.frame.t = r.row(2).transpose();
    rig.cameras.push_back(c);
  }
  rig.validate();
  return rig;
}

Rig with_truth_intrinsics(Rig rig, const StereoTruth& truth) {
  for (int cam = 0; cam < 2; ++cam) {
    auto& in = rig.cameras.at(cam).in;
    const double* d = truth.d[cam].ptr<double>();
    in.fu = truth.k[cam].at<double>(0, 0), in.fv = truth.k[cam].at<double>(1, 1);
    in.cu = truth.k[cam].at<double>(0, 2) + 0.5, in.cv = truth.k[cam].at<double>(1, 2) + 0.5;
    in.k = {d[0], d[1], d[3], d[2], d[4]};  // OpenCV (k1 k2 p1 p2 k3) -> omma k3 = p2, k4 = p1
  }
  return rig;
}

namespace {
Mat3 rows_uvt(const RigCamera& c) {
  Mat3 m;
  m.row(0) = c.frame.u.transpose();
  m.row(1) = c.frame.v.transpose();
  m.row(2) = c.frame.t.transpose();
  return m;
}
}  // namespace

Mat3 stereo_relative_rotation(const Rig& rig) {
  return rows_uvt(rig.cameras.at(1)) * rows_uvt(rig.cameras.at(0)).transpose();
}

StereoErrors stereo_errors(const Rig& rig, const StereoTruth& truth) {
  StereoErrors e;
  e.relative_rotation_deg =
      rad2deg(Eigen::AngleAxisd(stereo_relative_rotation(rig) * truth.r.transpose()).angle());
  const Vec3 b =
      rows_uvt(rig.cameras.at(0)) * (rig.cameras.at(1).position_mm - rig.cameras.at(0).position_mm);
  e.baseline_direction_deg = rad2deg(angle_between(b, truth.right_centre_mm()));
  for (int cam = 0; cam < 2; ++cam) {
    const auto& in = rig.cameras.at(cam).in;
    const double fx = truth.k[cam].at<double>(0, 0), fy = truth.k[cam].at<double>(1, 1);
    const double cx = truth.k[cam].at<double>(0, 2) + 0.5, cy = truth.k[cam].at<double>(1, 2) + 0.5;
    e.focal_pct[cam] = 100 * 0.5 * (std::abs(in.fu / fx - 1) + std::abs(in.fv / fy - 1));
    e.principal_point_px[cam] = std::hypot(in.cu - cx, in.cv - cy);
  }
  return e;
}

std::vector<std::vector<cv::Mat>> stereo_shot_sets(const StereoPairs& pairs, const std::vector<int>& ids) {
  std::vector<std::vector<cv::Mat>> sets;
  for (size_t s = 0; s < pairs.ids.size(); ++s) {
    if (!ids.empty() && std::find(ids.begin(), ids.end(), pairs.ids[s]) == ids.end()) continue;
    cv::Mat l, r;
    cv::cvtColor(pairs.left[s], l, cv::COLOR_GRAY2BGR);
    cv::cvtColor(pairs.right[s], r, cv::COLOR_GRAY2BGR);
    sets.push_back({l, r});
  }
  return sets;
}

}  // namespace omma::testing
