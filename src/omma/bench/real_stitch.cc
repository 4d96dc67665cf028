// omma real stitch PAIR: a real pair calibrated and stitched by omma from the images alone (plus
// what a photographer knows: a camera matrix or a field-of-view guess), beside OpenCV's Stitcher and
// Hugin (pto_gen, cpfind, cpclean, autooptimiser, nona), all run here on the same images.
//
// Alignment error. The SIFT matches of the pair (ratio test, then a loose homography RANSAC that
// only removes gross outliers) are split by a checkerboard of cells in image a: matches in even
// cells feed omma's calibration (calibrate_from_tracks, nothing else), matches in odd cells are
// held out. Every method's cameras map a held-out match's pixel in a to camera b through the
// rotation-only (far-field) model: unproject in a, project in b (OpenCV: x_b ~ K_b R_b^-1 R_a
// K_a^-1 x_a; Hugin: its optimised project read as a rig, calib/pto.h). The error is the distance to
// the match's pixel in b. The Graffiti pair also has its true homography H1to3p (a planar wall):
// the same mapping against H over a grid of graf1 pixels that land in graf3.
//
// Seam visibility: inter-camera PSNR (eq. 4.19-4.21, pano/maps.h) of each method's rig on the same
// frames, on a vr180 grid about camera 0 (every rig turned so that its camera 0 looks along +z); also
// over the overlap only (MSE_pan scaled by all pixels / overlap pixels), which does not depend on
// how much of the grid is empty.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/stitching.hpp>
#include <spdlog/spdlog.h>

#include "omma/bench/real.h"
#include "omma/calib/calibrate.h"
#include "omma/calib/initial_pose.h"
#include "omma/calib/photometric.h"
#include "omma/calib/pto.h"
#include "omma/core/frames.h"
#include "omma/core/io.h"
#include "omma/core/srgb.h"
#include "omma/isp/photometric.h"
#include "omma/pano/maps.h"
#include "omma/pano/stitch.h"
#include "omma/testing/real_data.h"

namespace omma::bench {
namespace fs = std::filesystem;

std::vector<std::string> real_stitch_pairs() { return {"leuven", "aero", "graf"}; }

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// What a user knows about the pair, and the truth where there is one.
struct PairData {
  std::string name;
  cv::Mat a, b;       // BGR 8-bit, as used (downscaled in quick mode)
  Intrinsics ia, ib;  // the user's intrinsics (continuous pixel convention)
  std::string intrinsics_source;
  bool focal_known = false;  // true: the calibration keeps the focal length
  bool has_truth = false;
  Mat3 h_truth = Mat3::Identity();  // graf: x_b ~ H x_a, continuous pixels (centres at +0.5)
  double scale = 1;                 // image scale used (quick: 0.5)
};

// The field of view a photographer would guess for an unknown ordinary lens: 55 deg diagonal (a
// "normal" lens of 35-50 mm equivalent spans 47-63 deg). The calibration estimates the focal length.
constexpr double kGuessDiagonalFovDeg = 55;

cv::Mat read_color(const fs::path& p) { return read_image(p, cv::IMREAD_COLOR); }

PairData load_pair(const std::string& name, const RealOptions& opt, const fs::path& dir) {
  PairData d;
  d.name = name;
  d.scale = opt.quick ? 0.5 : 1.0;
  cv::Mat a, b;
  if (name == "leuven") {
    a = read_color(dir / "leuvenA.jpg");
    b = read_color(dir / "leuvenB.jpg");
  } else if (name == "aero") {
    a = read_color(dir / "aero1.jpg");
    b = read_color(dir / "aero3.jpg");
  } else if (name == "graf") {
    a = read_color(dir / "graf1.png");
    b = read_color(dir / "graf3.png");
  } else {
    throw std::invalid_argument("real stitch: unknown pair '" + name + "' (leuven, aero or graf)");
  }
  if (d.scale != 1) {
    cv::resize(a, a, cv::Size(), d.scale, d.scale, cv::INTER_AREA);
    cv::resize(b, b, cv::Size(), d.scale, d.scale, cv::INTER_AREA);
  }
  d.a = a;
  d.b = b;
  if (name == "leuven") {
    // essential_mat_data.txt: the camera matrix (OpenCV's integer pixel centres).
    std::ifstream f(dir / "essential_mat_data.txt");
    std::string l1, l2;
    double k[9];
    std::getline(f, l1);
    std::getline(f, l2);
    for (double& v : k)
      if (!(f >> v))
        throw std::runtime_error("cannot read the camera matrix of " +
                                 (dir / "essential_mat_data.txt").string());
    auto make = [&](const cv::Mat& img) {
      Intrinsics in = calib::intrinsics_from_focal(img.cols, img.rows, k[0] * d.scale);
      in.fv = k[4] * d.scale;
      in.cu = (k[2] + 0.5) * d.scale;
      in.cv = (k[5] + 0.5) * d.scale;
      in.aov = in.bounding_aov();
      return in;
    };
    d.ia = make(a);
    d.ib = make(b);
    d.intrinsics_source = "camera matrix of essential_mat_data.txt (focal kept)";
    d.focal_known = true;
  } else {
    d.ia = calib::intrinsics_from_diagonal_fov(a.cols, a.rows, kGuessDiagonalFovDeg);
    d.ib = calib::intrinsics_from_diagonal_fov(b.cols, b.rows, kGuessDiagonalFovDeg);
    d.intrinsics_source =
        fmt::format("{} deg diagonal field of view guessed (focal estimated)", kGuessDiagonalFovDeg);
  }
  if (name == "graf") {
    cv::FileStorage fsx((dir / "H1to3p.xml").string(), cv::FileStorage::READ);
    cv::Mat h;
    fsx["H13"] >> h;
    if (h.empty()) throw std::runtime_error("cannot read H13 from " + (dir / "H1to3p.xml").string());
    Mat3 hm;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) hm(r, c) = h.at<double>(r, c);
    // OpenCV's integer centres -> continuous (T = +0.5 shift), then the image scale S.
    Mat3 t, s;
    t << 1, 0, 0.5, 0, 1, 0.5, 0, 0, 1;
    s << d.scale, 0, 0, 0, d.scale, 0, 0, 0, 1;
    d.h_truth = s * t * hm * t.inverse() * s.inverse();
    d.has_truth = true;
  }
  return d;
}

// The split matches of the pair.
struct SplitMatches {
  calib::PixelMatches fit, test;
  int ratio_matches = 0, homography_inliers = 0;
  double cell_px = 0;
};

SplitMatches split_matches(const cv::Mat& a, const cv::Mat& b, double scale) {
  const auto fo = calib::InitialPoseOptions::default_features();
  const calib::CameraFeatures fa = calib::detect_features(a, fo), fb = calib::detect_features(b, fo);
  const calib::PixelMatches m = calib::match_features(fa, fb, 0.75);
  SplitMatches s;
  s.ratio_matches = static_cast<int>(m.a.size());
  s.cell_px = 48 * scale;
  if (m.a.size() < 8) return s;
  std::vector<cv::Point2d> pa, pb;
  for (size_t i = 0; i < m.a.size(); ++i) {
    pa.emplace_back(m.a[i].x(), m.a[i].y());
    pb.emplace_back(m.b[i].x(), m.b[i].y());
  }
  // Loose: only gross outliers go (parallax and the rotation model's misfit stay in).
  cv::Mat mask;
  cv::findHomography(pa, pb, cv::RANSAC, 12 * scale, mask, 5000, 0.999);
  for (size_t i = 0; i < m.a.size(); ++i) {
    if (!mask.at<uchar>(static_cast<int>(i))) continue;
    ++s.homography_inliers;
    const int cx = static_cast<int>(std::floor(m.a[i].x() / s.cell_px));
    const int cy = static_cast<int>(std::floor(m.a[i].y() / s.cell_px));
    auto& dst = (cx + cy) % 2 == 0 ? s.fit : s.test;
    dst.a.push_back(m.a[i]);
    dst.b.push_back(m.b[i]);
  }
  return s;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const double pos = q * (v.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(pos)), hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - lo) * (v[hi] - v[lo]);
}

// a -> b through a two-camera far-field rig.
std::optional<Vec2> map_ab(const Rig& rig, const Vec2& pa) {
  const CameraModel ca = rig.cameras[0].model(), cb = rig.cameras[1].model();
  return cb.project(ca.unproject(pa));
}

nlohmann::json error_stats(const std::vector<double>& e, int total) {
  nlohmann::json j;
  j["median_px"] = percentile(e, 0.5);
  j["p90_px"] = percentile(e, 0.9);
  j["count"] = static_cast<int>(e.size());
  j["unmapped"] = total - static_cast<int>(e.size());
  return j;
}

nlohmann::json alignment_error(const std::function<std::optional<Vec2>(const Vec2&)>& f,
                               const calib::PixelMatches& test) {
  std::vector<double> e;
  for (size_t i = 0; i < test.a.size(); ++i) {
    const auto p = f(test.a[i]);
    if (p && std::isfinite(p->x())) e.push_back((*p - test.b[i]).norm());
  }
  return error_stats(e, static_cast<int>(test.a.size()));
}

// graf: against the true homography over a grid of a's pixels that land inside b.
nlohmann::json truth_error(const std::function<std::optional<Vec2>(const Vec2&)>& f, const PairData& d) {
  std::vector<double> e;
  int total = 0;
  const double step = 8 * d.scale;
  for (double y = step / 2; y < d.a.rows; y += step)
    for (double x = step / 2; x < d.a.cols; x += step) {
      const Eigen::Vector3d h = d.h_truth * Eigen::Vector3d(x, y, 1);
      const Vec2 pt = h.head<2>() / h.z();
      if (!(pt.x() >= 0 && pt.y() >= 0 && pt.x() < d.b.cols && pt.y() < d.b.rows)) continue;
      ++total;
      const auto p = f(Vec2(x, y));
      if (p && std::isfinite(p->x())) e.push_back((*p - pt).norm());
    }
  return error_stats(e, total);
}

// The rig turned (one global rotation) so that camera 0 looks along +z, image right -x, down -y.
Rig canonical(Rig rig) {
  Mat3 c;
  c << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  const Mat3 g = rig.cameras[0].frame.dome_to_camera().transpose() * c;  // R_0 g = c
  for (auto& cam : rig.cameras) {
    const Mat3 r = cam.frame.dome_to_camera() * g;
    cam.frame.t = r.row(0).transpose();
    cam.frame.u = r.row(1).transpose();
    cam.frame.v = r.row(2).transpose();
    cam.position_mm = cam.position_mm.norm() * cam.frame.t;
  }
  return rig;
}

nlohmann::json seam_psnr(const Rig& rig, const std::vector<cv::Mat>& frames, const PanoGrid& grid) {
  nlohmann::json j;
  const double p = pano::inter_camera_psnr(rig, frames, grid);
  const cv::Mat cov = pano::coverage_map(rig, grid);
  const int overlap = cv::countNonZero(cov >= 2);
  j["inter_camera_psnr_db"] = p;
  if (overlap > 0) {
    const double mse = std::pow(10.0, -p / 10) * double(grid.width) * grid.height / overlap;
    j["overlap_psnr_db"] = -10 * std::log10(mse);
  }
  j["overlap_pixels"] = overlap;
  return j;
}

cv::Mat crop_to_coverage(const cv::Mat& pano, const cv::Mat& coverage) {
  const cv::Rect box = cv::boundingRect(coverage > 0);
  return box.area() > 0 ? pano(box).clone() : pano;
}

// A two-camera Rig from OpenCV's rotation-model cameras (ray_world = R K^-1 x, integer centres).
// OpenCV's world (x right, y down, z forward) turned by 180 deg about z: y up as omma's vr180.
Rig rig_from_opencv(const std::vector<cv::detail::CameraParams>& cams, const std::vector<cv::Size>& sizes) {
  Rig rig;
  rig.name = "opencv-stitcher";
  for (size_t i = 0; i < cams.size(); ++i) {
    cv::Mat r64;
    cams[i].R.convertTo(r64, CV_64F);
    Mat3 r;
    for (int y = 0; y < 3; ++y)
      for (int x = 0; x < 3; ++x) r(y, x) = r64.at<double>(y, x);
    Eigen::JacobiSVD<Mat3> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
    r = svd.matrixU() * svd.matrixV().transpose();
    const Mat3 m = Eigen::Vector3d(-1, -1, 1).asDiagonal();
    RigCamera c;
    c.id = static_cast<int>(i);
    c.frame.t = m * r.col(2);
    c.frame.u = m * r.col(0);
    c.frame.v = m * r.col(1);
    c.position_mm = 5 * c.frame.t;
    c.in = calib::intrinsics_from_focal(sizes[i].width, sizes[i].height, cams[i].focal);
    c.in.fv = cams[i].focal * cams[i].aspect;
    c.in.cu = cams[i].ppx + 0.5;
    c.in.cv = cams[i].ppy + 0.5;
    c.in.aov = c.in.bounding_aov();
    rig.cameras.push_back(c);
  }
  rig.validate();
  return rig;
}

int run_logged(const std::string& cmd, const fs::path& log) {
  return std::system((cmd + " > '" + log.string() + "' 2>&1").c_str());
}

cv::Mat labelled(const cv::Mat& img, const std::string& label, int height) {
  cv::Mat out;
  if (img.empty()) {
    out = cv::Mat(height, height, CV_8UC3, cv::Scalar(40, 40, 40));
  } else {
    const double s = double(height) / img.rows;
    cv::resize(img, out, cv::Size(std::max(1, int(std::lround(img.cols * s))), height), 0, 0, cv::INTER_AREA);
  }
  cv::putText(out, label, cv::Point(10, 30), cv::FONT_HERSHEY_SIMPLEX, 0.9, cv::Scalar(0, 0, 0), 4);
  cv::putText(out, label, cv::Point(10, 30), cv::FONT_HERSHEY_SIMPLEX, 0.9, cv::Scalar(255, 255, 255), 2);
  return out;
}

cv::Mat to_bgr8(cv::Mat m) {
  if (m.empty()) return m;
  if (m.depth() == CV_16U) m.convertTo(m, CV_8U, 1.0 / 257);
  if (m.channels() == 4) {
    std::vector<cv::Mat> ch;
    cv::split(m, ch);
    cv::Mat rgb;
    cv::merge(std::vector<cv::Mat>{ch[0], ch[1], ch[2]}, rgb);
    rgb.setTo(cv::Scalar(0, 0, 0), ch[3] == 0);
    return rgb;
  }
  if (m.channels() == 1) cv::cvtColor(m, m, cv::COLOR_GRAY2BGR);
  return m;
}

// omma's calibration of the pair from the fit matches alone.
struct OmmaCalib {
  Rig rig;
  calib::InitialPoseSummary init;
  calib::CalibrationSummary cal;
  double init_s = 0, calib_s = 0;
};

OmmaCalib omma_calibrate(const PairData& d, const calib::PixelMatches& fit, int threads, bool estimate_focal,
                         bool share_focal = true) {
  OmmaCalib r;
  auto t0 = Clock::now();
  calib::InitialPoseOptions io;
  io.name = "real-" + d.name;
  io.min_inliers = 10;
  io.ransac_threshold_px = 12 * d.scale;  // the focal is a guess, the scene not at infinity
  // The initial pose from the fit matches only (the held-out ones never reach omma).
  calib::PairPose pp = calib::estimate_pair_rotation(d.ia, d.ib, fit, io);
  pp.cam_a = 0;
  pp.cam_b = 1;
  r.init = calib::initial_pose_from_pairs({d.ia, d.ib}, {pp}, io);
  r.init_s = since(t0);
  t0 = Clock::now();
  std::vector<std::vector<calib::TrackObservation>> tracks;
  for (size_t i = 0; i < fit.a.size(); ++i) {
    calib::TrackObservation oa, ob;
    oa.cam = 0;
    oa.px = fit.a[i];
    ob.cam = 1;
    ob.px = fit.b[i];
    tracks.push_back({oa, ob});
  }
  calib::CalibrationOptions co;
  co.estimate_focal = estimate_focal;
  co.share_focal = share_focal;
  co.estimate_center = false;
  co.radial_terms = 0;
  co.loss = "huber";
  co.loss_scale_px = 2.0 * d.scale;
  co.outlier_px = 8.0 * d.scale;
  co.min_observations = 20;
  co.threads = threads;
  r.cal = calib::calibrate_from_tracks(r.init.rig, std::move(tracks), calib::SceneModel::kFar, co);
  r.calib_s = since(t0);
  r.rig = canonical(r.cal.rig);
  return r;
}

cv::Mat scale_linear(const cv::Mat& srgb8, double gain) {
  cv::Mat out(srgb8.size(), CV_8UC3);
  uchar lut[256];
  for (int v = 0; v < 256; ++v)
    lut[v] = cv::saturate_cast<uchar>(255.0f * linear_to_srgb(float(gain) * srgb_to_linear(v / 255.0f)));
  cv::LUT(srgb8, cv::Mat(1, 256, CV_8U, lut), out);
  return out;
}

// Camera b made darker by a known gain in linear light; omma's photometric calibration from the
// overlap; the gain ratio b/a measured on the original and the darkened pair (their quotient must
// be the gain: the two pictures' own exposures may differ), and the seam PSNR with and without it.
nlohmann::json exposure_test(const Rig& rig, const cv::Mat& a, const cv::Mat& b, const PanoGrid& grid,
                             int threads) {
  constexpr double kGain = 0.6;
  nlohmann::json j;
  j["applied_gain"] = kGain;
  calib::PhotometricOptions po;
  po.estimate_vignetting = false;  // two pictures of one camera: the gain is what differs
  po.threads = threads;
  po.registration_px = 1.0;  // a real far-field calibration of a pair with parallax
  const cv::Mat dark = scale_linear(b, kGain);
  auto ratio = [&](const cv::Mat& bb, calib::PhotometricSummary* out) {
    const auto s = calib::calibrate_photometric(rig, {{a, bb}}, po);
    if (out) *out = s;
    const auto& ga = s.rig.cameras[0].photometric->gains;
    const auto& gb = s.rig.cameras[1].photometric->gains;
    return std::array<double, 3>{gb[0] / ga[0], gb[1] / ga[1], gb[2] / ga[2]};
  };
  const auto r0 = ratio(b, nullptr);
  calib::PhotometricSummary sd;
  const auto r1 = ratio(dark, &sd);
  nlohmann::json m = nlohmann::json::array();
  double worst = 0;
  for (int c = 0; c < 3; ++c) {
    m.push_back(r1[c] / r0[c]);
    worst = std::max(worst, std::abs(r1[c] / r0[c] / kGain - 1) * 100);
  }
  j["measured_gain_bgr"] = m;
  j["original_ratio_bgr"] = nlohmann::json::array({r0[0], r0[1], r0[2]});
  j["gain_error_pct"] = worst;
  j["samples"] = sd.samples;
  const std::vector<cv::Mat> raw = {a, dark};
  j["seam_uncorrected"] = seam_psnr(rig, raw, grid);
  j["seam_corrected"] = seam_psnr(sd.rig, isp::correct_frames(sd.rig, raw), grid);
  return j;
}

}  // namespace

nlohmann::json real_stitch(const std::string& pair, const RealOptions& opt) {
  const fs::path dir = opt.data_dir.empty() ? testing::opencv_samples_dir() : opt.data_dir;
  if (dir.empty()) throw std::runtime_error("OpenCV's sample images are not installed (opencv-doc)");
  const PairData d = load_pair(pair, opt, dir);
  const fs::path out = opt.out_dir.empty() ? fs::temp_directory_path() /
                                                 fmt::format("omma_real_stitch_{}_{}", pair, ::getpid())
                                           : opt.out_dir;
  fs::create_directories(out);

  nlohmann::json j;
  j["pair"] = pair;
  j["quick"] = opt.quick;
  j["image_scale"] = d.scale;
  j["sizes"] = {{d.a.cols, d.a.rows}, {d.b.cols, d.b.rows}};
  j["intrinsics_given"] = d.intrinsics_source;
  j["model"] = "far field (rotation only): unproject in a, project in b";

  auto t0 = Clock::now();
  const SplitMatches sm = split_matches(d.a, d.b, d.scale);
  j["matches"] = {{"ratio_test", sm.ratio_matches},
                  {"homography_inliers", sm.homography_inliers},
                  {"fit", static_cast<int>(sm.fit.a.size())},
                  {"test", static_cast<int>(sm.test.a.size())},
                  {"checker_cell_px", sm.cell_px},
                  {"time_s", since(t0)}};
  const bool enough = sm.fit.a.size() >= 20 && sm.test.a.size() >= 20;
  const std::vector<cv::Mat> frames = {d.a, d.b};
  // The vr180 grid whose pixels are about as large as camera a's (as given).
  PanoGrid grid;
  grid.projection = Projection::kVr180;
  grid.width = grid.height = std::min(opt.quick ? 900 : 2400, static_cast<int>(std::lround(kPi * d.ia.fu)));
  cv::Mat pano_omma;

  // ---- omma
  nlohmann::json jo;
  if (!enough) {
    jo["failed"] = fmt::format(
        "too few matches for a calibration with held-out matches ({} after the ratio test, {} homography "
        "inliers: {} fit, {} test; omma needs 20 of each)",
        sm.ratio_matches, sm.homography_inliers, sm.fit.a.size(), sm.test.a.size());
  } else {
    // Each picture its own focal length, estimated from the start the user gave: measured best on every
    // pair (the alternatives below): a rotation with a zoom absorbs part of the camera's move (leuven's
    // step forward, graf's turn about the wall) that a rotation alone cannot.
    const OmmaCalib oc = omma_calibrate(d, sm.fit, opt.threads, true, false);
    const Rig& rig = oc.rig;
    jo["initial_pose_s"] = oc.init_s;
    jo["initial_pose_inliers"] = oc.init.pairs[0].inliers;
    jo["calibrate_s"] = oc.calib_s;
    jo["calibration_rms_px"] = oc.cal.rms_px;
    jo["focal_px"] = {rig.cameras[0].in.fu, rig.cameras[1].in.fu};
    jo["rotation_deg"] = rad2deg(angle_between(rig.cameras[0].frame.t, rig.cameras[1].frame.t));
    auto omma_map = [&](const Vec2& p) { return map_ab(rig, p); };
    jo["initial_error"] = alignment_error([&](const Vec2& p) { return map_ab(oc.init.rig, p); }, sm.test);
    jo["alignment_error"] = alignment_error(omma_map, sm.test);
    jo["fit_error"] = alignment_error(omma_map, sm.fit);
    if (d.has_truth) jo["truth_error"] = truth_error(omma_map, d);
    // The alternatives: one focal length for both (estimated, or kept where the user knows it), and
    // the user's focal length kept.
    for (const bool estimate : {true, false}) {
      const OmmaCalib alt = omma_calibrate(d, sm.fit, opt.threads, estimate, true);
      auto fm = [&](const Vec2& p) { return map_ab(alt.rig, p); };
      const std::string key = estimate ? "focal_shared" : "focal_fixed";
      jo[key] = {{"alignment_error", alignment_error(fm, sm.test)}, {"focal_px", alt.rig.cameras[0].in.fu}};
      if (d.has_truth) jo[key]["truth_error"] = truth_error(fm, d);
    }
    jo["grid"] = fmt::format("vr180 {}x{}", grid.width, grid.height);
    t0 = Clock::now();
    pano::StitchOptions so;
    so.method = pano::Method::kMrf;
    so.grid = grid;
    so.progress = false;
    const cv::Mat cov = pano::coverage_map(rig, grid);
    pano_omma = crop_to_coverage(to_u8(pano::stitch(rig, frames, so)), cov);
    jo["stitch_s"] = since(t0);
    jo["method"] = "mrf";
    jo["seam"] = seam_psnr(rig, frames, grid);
    write_image(out / "omma_pano.jpg", pano_omma);
    jo["picture"] = "omma_pano.jpg";
    save_rig(rig, out / "omma_rig.json");

    // JPEG blocking: the pair re-encoded at quality 30, calibrated again; errors on the ORIGINAL
    // held-out matches (what the calibration is worth), and the matches themselves.
    {
      std::vector<uchar> buf;
      cv::Mat a30, b30;
      cv::imencode(".jpg", d.a, buf, {cv::IMWRITE_JPEG_QUALITY, 30});
      a30 = cv::imdecode(buf, cv::IMREAD_COLOR);
      cv::imencode(".jpg", d.b, buf, {cv::IMWRITE_JPEG_QUALITY, 30});
      b30 = cv::imdecode(buf, cv::IMREAD_COLOR);
      const SplitMatches s30 = split_matches(a30, b30, d.scale);
      nlohmann::json jq;
      jq["fit_matches"] = static_cast<int>(s30.fit.a.size());
      try {
        const OmmaCalib c30 = omma_calibrate(d, s30.fit, opt.threads, true, false);
        jq["alignment_error"] = alignment_error([&](const Vec2& p) { return map_ab(c30.rig, p); }, sm.test);
        if (d.has_truth)
          jq["truth_error"] = truth_error([&](const Vec2& p) { return map_ab(c30.rig, p); }, d);
      } catch (const std::exception& e) {
        jq["failed"] = e.what();
      }
      jo["jpeg_q30"] = jq;
    }
    try {
      jo["exposure"] = exposure_test(rig, d.a, d.b, grid, opt.threads);
    } catch (const std::exception& e) {
      jo["exposure"] = {{"failed", e.what()}};
    }
  }
  j["omma"] = jo;

  cv::Mat pano_cv, pano_hugin;
  std::string cv_label = "OpenCV Stitcher (failed)";
  if (opt.peers) {
    // ---- OpenCV's Stitcher, as a user calls it.
    nlohmann::json jc;
    // Defaults first; then what a user tries when they fail (ERR_NEED_MORE_IMGS: the pair's match
    // confidence is below panoConfidenceThresh 1.0): the threshold lowered to 0.3.
    const std::vector<std::tuple<cv::Stitcher::Mode, double, std::string>> runs = {
        {cv::Stitcher::PANORAMA, 1.0, "panorama"},
        {cv::Stitcher::PANORAMA, 0.3, "panorama_conf0.3"},
        {cv::Stitcher::SCANS, 1.0, "scans"},
        {cv::Stitcher::SCANS, 0.3, "scans_conf0.3"}};
    for (const auto& [mode, conf, mname] : runs) {
      t0 = Clock::now();
      auto st = cv::Stitcher::create(mode);
      st->setPanoConfidenceThresh(conf);
      cv::Mat p;
      const auto status = st->stitch(std::vector<cv::Mat>{d.a, d.b}, p);
      nlohmann::json jm;
      jm["time_s"] = since(t0);
      jm["status"] = static_cast<int>(status);
      if (status == cv::Stitcher::OK && st->component().size() == 2) {
        const auto cams = st->cameras();
        const std::vector<cv::Size> sizes = {d.a.size(), d.b.size()};
        // cameras() are at the composition scale (the original images here): ppx = W / 2 there.
        auto to_k = [](const cv::detail::CameraParams& c) {
          cv::Mat k;
          c.K().convertTo(k, CV_64F);
          return k;
        };
        cv::Mat ka = to_k(cams[0]), kb = to_k(cams[1]), ra, rb;
        cams[0].R.convertTo(ra, CV_64F);
        cams[1].R.convertTo(rb, CV_64F);
        const cv::Mat h = kb * rb.inv() * ra * ka.inv();
        auto cv_map = [&](const Vec2& pa) -> std::optional<Vec2> {
          cv::Mat x = (cv::Mat_<double>(3, 1) << pa.x() - 0.5, pa.y() - 0.5, 1);
          cv::Mat y = h * x;
          const double z = y.at<double>(2);
          if (!(z > 0)) return std::nullopt;
          return Vec2(y.at<double>(0) / z + 0.5, y.at<double>(1) / z + 0.5);
        };
        // SCANS cameras are affine transforms, not rotations: their mapping is not comparable, so only
        // the picture and the time are reported for them.
        if (mode == cv::Stitcher::PANORAMA) {
          jm["focal_px"] = {cams[0].focal, cams[1].focal};
          jm["alignment_error"] = alignment_error(cv_map, sm.test);
          if (d.has_truth) jm["truth_error"] = truth_error(cv_map, d);
          try {
            jm["seam"] = seam_psnr(canonical(rig_from_opencv(cams, sizes)), frames, grid);
          } catch (const std::exception& e) {
            jm["seam"] = {{"failed", e.what()}};
          }
        }
        if (pano_cv.empty()) {
          pano_cv = p;
          cv_label = "OpenCV Stitcher " + mname;
          write_image(out / "opencv_pano.jpg", p);
          jm["picture"] = "opencv_pano.jpg";
        }
      } else {
        jm["failed"] =
            status == cv::Stitcher::OK ? "kept one image only" : "status " + std::to_string(int(status));
      }
      jc[mname] = jm;
    }
    j["opencv"] = jc;

    // ---- Hugin: pto_gen (the same field of view omma started from), cpfind, cpclean,
    // autooptimiser, nona.
    nlohmann::json jh;
    const fs::path hd = out / "hugin";
    fs::create_directories(hd);
    write_image(hd / "a.png", d.a);
    write_image(hd / "b.png", d.b);
    const double hfov = rad2deg(2 * std::atan(d.a.cols / 2.0 / d.ia.fu));
    jh["hfov_given_deg"] = hfov;
    const std::string q = "cd '" + hd.string() + "' && ";
    t0 = Clock::now();
    bool ok = run_logged(q + fmt::format("pto_gen -f {:.4f} -o project.pto a.png b.png", hfov),
                         hd / "pto_gen.log") == 0;
    ok = ok && run_logged(q + "cpfind --multirow -o cp.pto project.pto", hd / "cpfind.log") == 0;
    ok = ok && run_logged(q + "cpclean -o clean.pto cp.pto", hd / "cpclean.log") == 0;
    ok =
        ok && run_logged(q + "autooptimiser -a -m -l -s -o opt.pto clean.pto", hd / "autooptimiser.log") == 0;
    jh["align_s"] = since(t0);
    if (ok) {
      try {
        const auto imp = calib::import_pto(read_text_file(hd / "opt.pto"), hd);
        const Rig hr = canonical(imp.rig);
        auto h_map = [&](const Vec2& p) { return map_ab(hr, p); };
        jh["hfov_deg"] = rad2deg(2 * std::atan(d.a.cols / 2.0 / hr.cameras[0].in.fu));
        jh["alignment_error"] = alignment_error(h_map, sm.test);
        if (d.has_truth) jh["truth_error"] = truth_error(h_map, d);
        jh["seam"] = seam_psnr(hr, frames, grid);
      } catch (const std::exception& e) {
        jh["failed"] = std::string("import: ") + e.what();
      }
      t0 = Clock::now();
      if (run_logged(q + "nona -m TIFF -o pano opt.pto", hd / "nona.log") == 0 &&
          fs::exists(hd / "pano.tif")) {
        jh["nona_s"] = since(t0);
        pano_hugin = to_bgr8(read_image(hd / "pano.tif"));
        cv::Mat gray;
        cv::cvtColor(pano_hugin, gray, cv::COLOR_BGR2GRAY);
        pano_hugin = crop_to_coverage(pano_hugin, gray);
        write_image(out / "hugin_pano.jpg", pano_hugin);
        jh["picture"] = "hugin_pano.jpg";
      } else {
        jh["nona_failed"] = "see hugin/nona.log";
      }
    } else {
      jh["failed"] = "a Hugin tool failed: see the logs in hugin/";
    }
    j["hugin"] = jh;
  }

  const int h = 360;
  std::vector<cv::Mat> row = {labelled(pano_omma, "omma", h)};
  if (opt.peers) {
    row.push_back(cv::Mat(h, 8, CV_8UC3, cv::Scalar(255, 255, 255)));
    row.push_back(labelled(pano_cv, cv_label, h));
    row.push_back(cv::Mat(h, 8, CV_8UC3, cv::Scalar(255, 255, 255)));
    row.push_back(labelled(pano_hugin, "Hugin", h));
  }
  cv::Mat side;
  cv::hconcat(row, side);
  write_image(out / "side_by_side.jpg", side);
  j["side_by_side"] = "side_by_side.jpg";
  j["out_dir"] = out.string();
  return j;
}

}  // namespace omma::bench
