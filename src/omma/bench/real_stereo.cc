// omma real stereo-calib (real.h): the real stereo rig of OpenCV's samples (left01..14 /
// right01..14, 640x480 gray, left10/right10 missing) calibrated by omma from its natural features
// (pooled shots: the rig is static, the chessboard moves between shots), against the chessboard
// calibration of the same images (cv::calibrateCamera per camera, then cv::stereoCalibrate with the
// intrinsics fixed), with COLMAP's mapper beside it.
//
// The pairs, the chessboard truth, the perturbed start and the errors against the truth are the
// test fixture testing/real_stereo.h, which states the conventions (x_r = R x_l + T; the dome frame
// is the left camera's OpenCV frame; omma's cu = OpenCV's cx + 0.5).
#include "omma/testing/real_stereo.h"

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "omma/bench/real.h"
#include "omma/calib/calibrate.h"
#include "omma/core/log.h"
#include "omma/testing/real_data.h"

namespace omma::bench {
namespace {
namespace fs = std::filesystem;
using testing::StereoTruth;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double rotation_angle_deg(const Mat3& r) { return rad2deg(Eigen::AngleAxisd(r).angle()); }

// Errors of a rig against the truth (testing::stereo_errors), and the distortion found.
nlohmann::json rig_errors(const Rig& rig, const StereoTruth& t) {
  const testing::StereoErrors e = testing::stereo_errors(rig, t);
  nlohmann::json j;
  j["relative_rotation_error_deg"] = e.relative_rotation_deg;
  j["baseline_direction_error_deg"] = e.baseline_direction_deg;
  for (int cam = 0; cam < 2; ++cam) {
    const std::string name = cam ? "right" : "left";
    j["focal_error_" + name + "_pct"] = e.focal_pct[cam];
    j["principal_point_error_" + name + "_px"] = e.principal_point_px[cam];
    j["k1_" + name] = rig.cameras[cam].in.k[0];
  }
  return j;
}

// The chessboard's repetitive texture in matching: in every shot whose board was found, the SIFT
// matches (start rig, the calibration's options) whose left keypoint lies on the board, checked
// against the board's plane: the truth's homography between the undistorted views of its corners
// predicts the right keypoint; more than 3 px away = a wrong match (a square matched to another).
nlohmann::json board_match_check(const std::vector<std::vector<cv::Mat>>& sets, const StereoTruth& t,
                                 const Rig& start, const calib::CalibrationOptions& co) {
  struct Shot {
    calib::CameraFeatures fl, fr;
    cv::Mat h;
    std::vector<cv::Point2f> hull;
  };
  std::vector<Shot> shots;
  for (size_t s = 0; s < sets.size(); ++s) {
    if (t.corners[0][s].empty()) continue;
    Shot sh;
    std::vector<cv::Point2f> n[2];
    for (int cam = 0; cam < 2; ++cam) cv::undistortPoints(t.corners[cam][s], n[cam], t.k[cam], t.d[cam]);
    sh.h = cv::findHomography(n[0], n[1], 0);
    cv::convexHull(t.corners[0][s], sh.hull);
    sh.fl = calib::detect_features(sets[s][0], co.features);
    sh.fr = calib::detect_features(sets[s][1], co.features);
    shots.push_back(std::move(sh));
  }
  auto wrong = [&](const Shot& sh, const calib::Match& m, bool* on_board) {
    const cv::Point2f pl(float(sh.fl.px[m.a].x() - 0.5), float(sh.fl.px[m.a].y() - 0.5));
    *on_board = cv::pointPolygonTest(sh.hull, pl, false) >= 0;
    if (!*on_board) return false;
    std::vector<cv::Point2f> in{pl}, nl;
    cv::undistortPoints(in, nl, t.k[0], t.d[0]);
    const cv::Mat p = sh.h * (cv::Mat_<double>(3, 1) << nl[0].x, nl[0].y, 1.0);
    std::vector<cv::Point3d> obj{{p.at<double>(0), p.at<double>(1), p.at<double>(2)}};
    std::vector<cv::Point2d> pr;
    cv::projectPoints(obj, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), t.k[1], t.d[1], pr);
    return std::hypot(pr[0].x + 0.5 - sh.fr.px[m.b].x(), pr[0].y + 0.5 - sh.fr.px[m.b].y()) > 3.0;
  };
  nlohmann::json out = nlohmann::json::object();
  for (const auto& [ratio, self_ratio] : std::vector<std::pair<double, double>>{
           {0.8, 0.0}, {0.6, 0.0}, {0.8, 0.9}, {co.match.ratio, co.match.self_ratio}}) {
    calib::MatchOptions mo = co.match;
    mo.ratio = ratio, mo.self_ratio = self_ratio;
    int putative = 0, wrong_putative = 0, inliers = 0, wrong_inliers = 0, all_putative = 0, all_inliers = 0;
    for (const auto& sh : shots) {
      const calib::PairMatches pm =
          calib::match_pair(start, 0, 1, sh.fl, sh.fr, calib::SceneModel::kNear, mo);
      all_putative += pm.putative;
      all_inliers += static_cast<int>(pm.essential_set.size());
      for (const auto& m : pm.putative_set) {
        bool on = false;
        const bool w = wrong(sh, m, &on);
        putative += on, wrong_putative += w;
      }
      for (const auto& m : pm.essential_set) {
        bool on = false;
        const bool w = wrong(sh, m, &on);
        inliers += on, wrong_inliers += w;
      }
    }
    const std::string key = fmt::format("ratio{:02.0f}_self{:02.0f}", 10 * ratio, 10 * self_ratio);
    out[key] = nlohmann::json({{"ratio", ratio},
                               {"self_ratio", self_ratio},
                               {"matches", all_putative},
                               {"ransac_inliers", all_inliers},
                               {"board_matches", putative},
                               {"board_wrong_matches", wrong_putative},
                               {"board_inliers", inliers},
                               {"board_wrong_inliers", wrong_inliers}});
  }
  return out;
}

// COLMAP's mapper on the 26 images (lefts and rights in two folders, one OPENCV camera each).
nlohmann::json run_colmap(const std::vector<cv::Mat>& left, const std::vector<cv::Mat>& right,
                          const std::vector<int>& ids, const StereoTruth& truth, const fs::path& work) {
  nlohmann::json j;
  const auto t0 = std::chrono::steady_clock::now();
  fs::remove_all(work);
  fs::create_directories(work / "imgs/left");
  fs::create_directories(work / "imgs/right");
  fs::create_directories(work / "sparse");
  for (size_t s = 0; s < ids.size(); ++s) {
    cv::imwrite((work / fmt::format("imgs/left/{:02d}.png", ids[s])).string(), left[s]);
    cv::imwrite((work / fmt::format("imgs/right/{:02d}.png", ids[s])).string(), right[s]);
  }
  const std::string w = work.string();
  const std::string env = "QT_QPA_PLATFORM=offscreen ";
  const std::string log = " >> " + w + "/colmap.log 2>&1";
  const std::vector<std::string> cmds = {
      env + "colmap feature_extractor --database_path " + w + "/db.db --image_path " + w +
          "/imgs --ImageReader.camera_model OPENCV --ImageReader.single_camera_per_folder 1 "
          "--SiftExtraction.use_gpu 0 --SiftExtraction.num_threads 2" +
          log,
      env + "colmap exhaustive_matcher --database_path " + w +
          "/db.db --SiftMatching.use_gpu 0 "
          "--SiftMatching.num_threads 2" +
          log,
      env + "colmap mapper --database_path " + w + "/db.db --image_path " + w + "/imgs --output_path " + w +
          "/sparse --Mapper.num_threads 2" + log};
  for (const auto& c : cmds)
    if (std::system(c.c_str()) != 0) {
      j["error"] = "colmap failed: " + c.substr(0, c.find(' ', env.size() + 7)) + " (see colmap.log)";
      j["time_s"] = seconds_since(t0);
      return j;
    }
  if (!fs::exists(work / "sparse/0")) {
    j["error"] = "colmap's mapper reconstructed no model";
    j["time_s"] = seconds_since(t0);
    return j;
  }
  const std::string conv = env + "colmap model_converter --input_path " + w + "/sparse/0 --output_path " + w +
                           "/sparse/0 --output_type TXT" + log;
  if (std::system(conv.c_str()) != 0) {
    j["error"] = "colmap model_converter failed";
    return j;
  }
  j["time_s"] = seconds_since(t0);
  // cameras.txt: CAMERA_ID MODEL W H fx fy cx cy k1 k2 p1 p2 (OPENCV; pixel centres at +0.5).
  std::map<int, std::vector<double>> cams;
  {
    std::ifstream f(work / "sparse/0/cameras.txt");
    std::string line;
    while (std::getline(f, line)) {
      if (line.empty() || line[0] == '#') continue;
      std::istringstream ss(line);
      int id, wd, ht;
      std::string model;
      ss >> id >> model >> wd >> ht;
      std::vector<double> p;
      double v;
      while (ss >> v) p.push_back(v);
      cams[id] = p;
    }
  }
  // images.txt: IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME, then a line of points.
  std::map<int, Mat3> rl, rr;  // shot id -> world-to-camera rotation
  std::map<int, Vec3> cl, cr;  // shot id -> camera centre
  int cam_left = -1, cam_right = -1, registered = 0;
  {
    std::ifstream f(work / "sparse/0/images.txt");
    std::string line;
    bool pose_line = true;
    while (std::getline(f, line)) {
      if (line.empty() || line[0] == '#') continue;
      if (!pose_line) {
        pose_line = true;
        continue;
      }
      pose_line = false;
      std::istringstream ss(line);
      int id, cam;
      double qw, qx, qy, qz, tx, ty, tz;
      std::string name;
      ss >> id >> qw >> qx >> qy >> qz >> tx >> ty >> tz >> cam >> name;
      const Mat3 r = Eigen::Quaterniond(qw, qx, qy, qz).normalized().matrix();
      const Vec3 c = -r.transpose() * Vec3(tx, ty, tz);
      const int shot = std::atoi(name.substr(name.find('/') + 1).c_str());
      ++registered;
      if (name.rfind("left", 0) == 0) {
        rl[shot] = r, cl[shot] = c, cam_left = cam;
      } else {
        rr[shot] = r, cr[shot] = c, cam_right = cam;
      }
    }
  }
  {
    // points3D.txt: POINT3D_ID X Y Z R G B ERROR TRACK[]: ERROR = the point's mean reprojection error.
    std::ifstream f(work / "sparse/0/points3D.txt");
    std::string line;
    double sum2 = 0;
    int count = 0;
    while (std::getline(f, line)) {
      if (line.empty() || line[0] == '#') continue;
      std::istringstream ss(line);
      double v[8];
      for (double& x : v) ss >> x;
      if (ss) sum2 += v[7] * v[7], ++count;
    }
    if (count) j["reprojection_rms_px"] = std::sqrt(sum2 / count);  // over points' mean errors
    j["points"] = count;
  }
  j["note"] =
      "the rig never moves, only the chessboard: the mapper sees 13 copies of one stereo pair; it keeps the "
      "principal points at the image centres (ba_refine_principal_point off); registration varies run to run";
  j["registered_images"] = registered;
  j["images"] = 2 * ids.size();
  const Mat3& r_true = truth.r;
  const Vec3 b_true = truth.right_centre_mm();
  // Relative rotation per shot with both images registered, averaged (chordal mean).
  Mat3 sum = Mat3::Zero();
  Vec3 bsum = Vec3::Zero();
  int both = 0;
  for (const auto& [shot, r] : rl) {
    if (!rr.count(shot)) continue;
    sum += rr[shot] * r.transpose();
    bsum += r * (cr[shot] - cl[shot]).normalized();
    ++both;
  }
  j["shots_with_both"] = both;
  if (both > 0) {
    Eigen::JacobiSVD<Mat3> svd(sum, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Mat3 r = svd.matrixU() * svd.matrixV().transpose();
    if (r.determinant() < 0) r = -r;
    j["relative_rotation_error_deg"] = rotation_angle_deg(r * r_true.transpose());
    j["baseline_direction_error_deg"] = rad2deg(angle_between(bsum, b_true));
  }
  for (int cam = 0; cam < 2; ++cam) {
    const int id = cam ? cam_right : cam_left;
    if (!cams.count(id) || cams[id].size() < 4) continue;
    const auto& p = cams[id];
    const double fx = truth.k[cam].at<double>(0, 0), fy = truth.k[cam].at<double>(1, 1);
    const std::string name = cam ? "right" : "left";
    j["focal_error_" + name + "_pct"] = 100 * 0.5 * (std::abs(p[0] / fx - 1) + std::abs(p[1] / fy - 1));
    j["principal_point_error_" + name + "_px"] = std::hypot(p[2] - (truth.k[cam].at<double>(0, 2) + 0.5),
                                                            p[3] - (truth.k[cam].at<double>(1, 2) + 0.5));
  }
  return j;
}

// The rectified pair (cv::stereoRectify + remap from omma's calibration), side by side, with
// horizontal lines every 32 rows: rows line up where the calibration is right.
void write_rectified(const Rig& rig, const cv::Mat& left, const cv::Mat& right, const fs::path& path) {
  cv::Mat k[2], d[2];
  for (int cam = 0; cam < 2; ++cam) {
    const auto& in = rig.cameras[cam].in;
    k[cam] = (cv::Mat_<double>(3, 3) << in.fu, 0, in.cu - 0.5, 0, in.fv, in.cv - 0.5, 0, 0, 1);
    d[cam] =
        (cv::Mat_<double>(1, 5) << in.k[0], in.k[1], in.k[3], in.k[2], in.k[4]);  // omma k3 = p2, k4 = p1
  }
  const Mat3 r = testing::stereo_relative_rotation(rig);
  const Vec3 t = -r * (rig.cameras[1].position_mm - rig.cameras[0].position_mm);
  cv::Mat rc, tc;
  cv::eigen2cv(r, rc);
  cv::eigen2cv(t, tc);
  cv::Mat r1, r2, p1, p2, q;
  cv::stereoRectify(k[0], d[0], k[1], d[1], left.size(), rc, tc, r1, r2, p1, p2, q, cv::CALIB_ZERO_DISPARITY,
                    0);
  cv::Mat out[2];
  for (int cam = 0; cam < 2; ++cam) {
    cv::Mat mx, my;
    cv::initUndistortRectifyMap(k[cam], d[cam], cam ? r2 : r1, cam ? p2 : p1, left.size(), CV_32FC1, mx, my);
    cv::remap(cam ? right : left, out[cam], mx, my, cv::INTER_LINEAR);
  }
  cv::Mat pair;
  cv::hconcat(out[0], out[1], pair);
  if (pair.channels() == 1) cv::cvtColor(pair, pair, cv::COLOR_GRAY2BGR);
  for (int y = 16; y < pair.rows; y += 32) cv::line(pair, {0, y}, {pair.cols - 1, y}, {0, 255, 0}, 1);
  cv::imwrite(path.string(), pair);
}

}  // namespace

nlohmann::json real_stereo_calibration(const RealOptions& opt) {
  const fs::path data = opt.data_dir.empty() ? testing::opencv_samples_dir() : opt.data_dir;
  const fs::path out = opt.out_dir.empty() ? fs::temp_directory_path() / "omma_real_stereo" : opt.out_dir;
  fs::create_directories(out);
  const testing::StereoPairs pairs = testing::load_stereo_pairs(data);
  const std::vector<cv::Mat>&left = pairs.left, &right = pairs.right;
  const std::vector<int>& ids = pairs.ids;
  if (left.size() < 3)
    throw std::runtime_error("real stereo-calib: fewer than 3 stereo pairs in " + data.string());
  // The truth.
  auto t0 = std::chrono::steady_clock::now();
  const StereoTruth truth = testing::stereo_chessboard_truth(pairs);
  const double truth_s = seconds_since(t0);
  nlohmann::json j;
  j["case"] = "stereo-calib";
  j["shots"] = ids.size();
  j["truth"] = {{"method",
                 "cv::calibrateCamera per camera, then cv::stereoCalibrate (CALIB_FIX_INTRINSIC), 9x6 "
                 "inner corners, 25 mm squares"},
                {"views", truth.views},
                {"fx_left", truth.k[0].at<double>(0, 0)},
                {"fx_right", truth.k[1].at<double>(0, 0)},
                {"k1_left", truth.d[0].at<double>(0)},
                {"k1_right", truth.d[1].at<double>(0)},
                {"relative_rotation_deg", rotation_angle_deg(truth.r)},
                {"baseline_mm", truth.t.norm()},
                {"rms_left_px", truth.rms_mono[0]},
                {"rms_right_px", truth.rms_mono[1]},
                {"rms_stereo_px", truth.rms_stereo},
                {"time_s", truth_s}};
  // omma: pooled shots from the perturbed start.
  testing::StereoStartOptions so;
  so.axis = Vec3(1, 1, 0);
  so.name = "opencv-stereo-start";
  so.dome_radius_mm = 100;
  const Rig start = testing::stereo_start_rig(truth, so);
  const std::vector<std::vector<cv::Mat>> sets = testing::stereo_shot_sets(pairs);
  j["start"] = rig_errors(start, truth);
  calib::CalibrationOptions co = calib::stereo_calibration_options();
  co.threads = opt.threads;
  t0 = std::chrono::steady_clock::now();
  const calib::CalibrationSummary res = calib::calibrate_shots(start, sets, calib::ShotMode::kPool, co);
  nlohmann::json oj = rig_errors(res.rig, truth);
  oj["time_s"] = seconds_since(t0);
  oj["reprojection_rms_px"] = res.rms_px;
  oj["initial_rms_px"] = res.initial_rms_px;
  oj["matches"] = res.matches;
  oj["inliers"] = res.inliers;
  oj["tracks"] = res.tracks;
  oj["rejected"] = res.rejected;
  oj["scene"] = calib::to_string(res.scene);
  j["omma"] = oj;
  if (!opt.quick) {
    // Every intrinsic free (focal lengths and principal points too): the degeneracy of a static
    // two-camera rig (calibrate.h stereo_calibration_options).
    calib::CalibrationOptions free = co;
    free.estimate_focal = free.estimate_center = true;
    t0 = std::chrono::steady_clock::now();
    const auto rf = calib::calibrate_shots(start, sets, calib::ShotMode::kPool, free);
    j["omma_free_intrinsics"] = rig_errors(rf.rig, truth);
    j["omma_free_intrinsics"]["reprojection_rms_px"] = rf.rms_px;
    j["omma_free_intrinsics"]["time_s"] = seconds_since(t0);
    j["repetitive_texture"] = board_match_check(sets, truth, start, co);
    // The same pooled adjustment from the chessboard's intrinsics (focal, principal point,
    // distortion as a start; k1, k2 still estimated), the pose 5 deg off: what the pose estimation
    // reaches when the intrinsics are known (e.g. each camera calibrated once beforehand).
    const Rig known = testing::with_truth_intrinsics(start, truth);
    t0 = std::chrono::steady_clock::now();
    const auto rk = calib::calibrate_shots(known, sets, calib::ShotMode::kPool, co);
    j["omma_known_intrinsics"] = rig_errors(rk.rig, truth);
    j["omma_known_intrinsics"]["reprojection_rms_px"] = rk.rms_px;
    j["omma_known_intrinsics"]["time_s"] = seconds_since(t0);
  }
  if (!opt.quick) {
    // The former multi-shot mode (frames averaged as if the scene were static), for comparison.
    t0 = std::chrono::steady_clock::now();
    try {
      const auto avg = calib::calibrate_shots(start, sets, calib::ShotMode::kAverage, co);
      j["omma_average"] = rig_errors(avg.rig, truth);
      j["omma_average"]["reprojection_rms_px"] = avg.rms_px;
    } catch (const std::exception& e) {
      j["omma_average"] = {{"error", e.what()}};
    }
    j["omma_average"]["time_s"] = seconds_since(t0);
  }
  write_rectified(res.rig, left[0], right[0], out / "stereo_rectified_omma.png");
  write_rectified(start, left[0], right[0], out / "stereo_rectified_start.png");
  j["pictures"] = {"stereo_rectified_omma.png", "stereo_rectified_start.png"};
  if (opt.peers) j["colmap"] = run_colmap(left, right, ids, truth, out / "colmap");
  return j;
}

}  // namespace omma::bench
