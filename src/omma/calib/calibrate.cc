// Geometric calibration (calibrate.h): the stages in order. 1 features and matching (features.h,
// with the tracks), 2 bundle adjustment (bundle.h), 3 subpixel refinement (refine.h); photometric
// calibration follows separately (photometric.h).
#include "omma/calib/calibrate.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "omma/calib/bundle.h"
#include "omma/calib/photometric.h"
#include "omma/calib/refine.h"
#include "omma/calib/subpixel.h"
#include "omma/core/log.h"
#include "omma/core/progress.h"
#include "omma/core/srgb.h"
#include "omma/core/valid.h"

namespace omma::calib {

bool CalibrationOptions::IsValid(std::string* why) const {
  std::string sub;
  if (!features.IsValid(&sub)) return invalid(why, "features: " + sub);
  if (!match.IsValid(&sub)) return invalid(why, "match: " + sub);
  if (!subpixel.IsValid(&sub)) return invalid(why, "subpixel: " + sub);
  if (!dense_subpixel.IsValid(&sub)) return invalid(why, "dense_subpixel: " + sub);
  if (!(near_ratio > 0)) return invalid(why, "near_ratio must be > 0");
  if (!(overlap_margin_deg >= 0 && overlap_margin_deg < 180))
    return invalid(why, "overlap_margin_deg must be in [0, 180)");
  if (radial_terms < 0 || radial_terms > 3)
    return invalid(why, fmt::format("radial_terms must be 0..3, got {}", radial_terms));
  if (loss != "auto" && loss != "huber" && loss != "cauchy" && loss != "none")
    return invalid(why, "loss must be auto, huber, cauchy or none, got '" + loss + "'");
  if (!(loss_scale_px > 0) || !(outlier_px > 0) || !(refine_outlier_px > 0))
    return invalid(why, "loss_scale_px, outlier_px and refine_outlier_px must be > 0");
  if (!(prior_rotation_deg >= 0) || !(prior_mean_focal >= 0))
    return invalid(why, "prior_rotation_deg and prior_mean_focal must be >= 0");
  if (refine_rounds < 0 || dense_rounds < 0)
    return invalid(why, "refine_rounds and dense_rounds must be >= 0");
  if (!(refine_min_fraction >= 0 && refine_min_fraction <= 1))
    return invalid(why, "refine_min_fraction must be in [0, 1]");
  if (dense_neighbours < 1) return invalid(why, "dense_neighbours must be >= 1");
  if (!(dense_max_gap_px > 0) || !(dense_weight_floor > 0) || !(dense_reference_weight > 0))
    return invalid(why, "dense_max_gap_px, dense_weight_floor and dense_reference_weight must be > 0");
  if (!(tube_diameter_mm >= 0) || !std::isfinite(tube_diameter_mm))
    return invalid(why, "tube_diameter_mm must be a diameter in mm (> 0), or 0 for none");
  if (!(tube_tolerance > 0 && tube_tolerance < 1) ||
      !(tube_tolerance_refined > 0 && tube_tolerance_refined < 1))
    return invalid(why, "tube_tolerance and tube_tolerance_refined must be in (0, 1)");
  if (estimate_position && tube_diameter_mm > 0)
    return invalid(why, "estimate_position cannot be combined with the calibration tube (tube_diameter_mm)");
  if (max_iterations < 1) return invalid(why, "max_iterations must be >= 1");
  if (min_observations < 0) return invalid(why, "min_observations must be >= 0");
  if (threads < 1) return invalid(why, "threads must be >= 1");
  return true;
}

namespace {

// Step 2 of calibrate_rig: matches between the overlapping cameras in every shot (pms[shot]), the
// scene model (auto: the consensus over all pairs of all shots) under which every pair keeps its
// inliers, and the counts in res.
SceneModel match_pairs(const Rig& nominal, const std::vector<std::vector<CameraFeatures>>& feats,
                       const CalibrationOptions& opt, std::vector<std::vector<PairMatches>>& pms,
                       CalibrationSummary& res) {
  const auto pairs = overlapping_pairs(nominal, deg2rad(opt.overlap_margin_deg));
  res.pairs = static_cast<int>(pairs.size());
  long rot_total = 0, ess_total = 0;
  pms.assign(feats.size(), {});
  {
    Progress progress("calibrate: matching", pairs.size() * feats.size());
    for (size_t s = 0; s < feats.size(); ++s)
      for (const auto& [a, b] : pairs) {
        PairMatches pm = match_pair(nominal, a, b, feats[s][a], feats[s][b], opt.scene, opt.match);
        res.matches += pm.putative;
        rot_total += pm.rotation_inliers;
        ess_total += pm.essential_inliers;
        pms[s].push_back(std::move(pm));
        progress.step();
      }
  }
  SceneModel scene = opt.scene;
  if (scene == SceneModel::kAuto) {
    // Parallax shows as matches that no rotation explains but an essential matrix does.
    scene = ess_total > opt.near_ratio * rot_total ? SceneModel::kNear : SceneModel::kFar;
    // Cameras that share one centre (a rig made from sizes and focal lengths, rig new without pos=)
    // cannot explain parallax with fixed positions: the near model would be degenerate there.
    double spread_mm = 0;
    for (const auto& c : nominal.cameras)
      spread_mm = std::max(spread_mm, (c.position_mm - nominal.cameras.front().position_mm).norm());
    if (scene == SceneModel::kNear && spread_mm < 1e-6 && !opt.estimate_position) {
      scene = SceneModel::kFar;
      res.warnings.push_back(
          "the images show parallax, but the rig's cameras share one centre: far-field model (rotation "
          "only), which folds the parallax into the cameras' intrinsics; give the cameras' positions and "
          "--position estimate to model it");
      spdlog::warn("calibrate: {}", res.warnings.back());
    }
    spdlog::info("calibrate: consensus over all pairs: rotation-only {}, essential matrix {} -> {} scene",
                 rot_total, ess_total, to_string(scene));
  }
  // All pairs use the one chosen model.
  for (auto& shot : pms)
    for (auto& pm : shot) pm.choose(scene, opt.match.min_inliers);
  res.scene = scene;
  if (scene == SceneModel::kNear && opt.tube_diameter_mm <= 0 && !opt.estimate_position) {
    res.warnings.push_back(
        "near-field scene (parallax): scene points with camera positions fixed at nominal; the mean focal "
        "length "
        "is held at the nominal one (prior, the focal/depth ambiguity) and principal point trades against "
        "rotation (on the simulated colon: ~0.5 deg, ~0.7-1.1 % focal, ~2 px centre errors, panorama as good "
        "as "
        "with the true rig); calibrate from several shots of the calibration tube (--tube) or a far-field "
        "scene "
        "for accurate intrinsics");
    spdlog::warn("calibrate: {}", res.warnings.back());
  }
  for (size_t p = 0; p < pairs.size(); ++p) {
    PairReport rep;
    rep.cam_a = nominal.cameras[pairs[p].first].id;
    rep.cam_b = nominal.cameras[pairs[p].second].id;
    for (const auto& shot : pms) {
      rep.matches += shot[p].putative;
      rep.inliers += static_cast<int>(shot[p].inliers.size());
    }
    res.inliers += rep.inliers;
    res.per_pair.push_back(rep);
  }
  spdlog::info(
      "calibrate: {} cameras, {} overlapping pairs, {} shot(s), {} matches, {} RANSAC inliers, {} scene",
      nominal.cameras.size(), res.pairs, feats.size(), res.matches, res.inliers, to_string(scene));
  return scene;
}

void check_frames(const Rig& nominal, const std::vector<cv::Mat>& frames, const std::string& where) {
  const int n = static_cast<int>(nominal.cameras.size());
  if (static_cast<int>(frames.size()) != n)
    throw std::invalid_argument(
        fmt::format("calibrate: {}{} frames for a rig of {} cameras", where, frames.size(), n));
  for (int i = 0; i < n; ++i)
    if (frames[i].cols != nominal.cameras[i].in.width || frames[i].rows != nominal.cameras[i].in.height)
      throw std::invalid_argument(fmt::format("calibrate: {}frame of camera {} is {}x{}, the rig says {}x{}",
                                              where, nominal.cameras[i].id, frames[i].cols, frames[i].rows,
                                              nominal.cameras[i].in.width, nominal.cameras[i].in.height));
}

std::vector<CameraFeatures> detect_all(const std::vector<cv::Mat>& frames, const CalibrationOptions& opt) {
  std::vector<CameraFeatures> feats(frames.size());
  Progress progress("calibrate: features", frames.size());
  for (size_t i = 0; i < frames.size(); ++i) {
    feats[i] = detect_features(frames[i], opt.features);
    progress.step();
  }
  return feats;
}

void log_tracks(const std::vector<std::vector<TrackObservation>>& tracks) {
  std::vector<int> hist(6, 0);
  for (const auto& t : tracks) ++hist[std::min<size_t>(t.size(), 5)];
  spdlog::info("calibrate: {} tracks, by length 2: {}, 3: {}, 4: {}, 5+: {}", tracks.size(), hist[2], hist[3],
               hist[4], hist[5]);
}

// The subpixel refinement rounds of calibrate_rig: align every observation (dense: new ones from
// every keypoint), then solve again from the previous solution; stops with a warning when too few align.
void refine_rounds(const Rig& nominal, const std::vector<cv::Mat>& frames,
                   const std::vector<CameraFeatures>& feats, SceneModel scene, const CalibrationOptions& opt,
                   SolveState& st, CalibrationSummary& res) {
  const int n = static_cast<int>(nominal.cameras.size());
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
                         : refine_tracks(res.rig, gray, st, scene == SceneModel::kNear, opt.subpixel,
                                         &attempted, &refined);
    spdlog::info("calibrate: subpixel refinement round {}: {} of {} observations aligned, {} tracks",
                 round + 1, refined, attempted, rtracks.size());
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

}  // namespace

CalibrationSummary calibrate_rig(const Rig& nominal, const std::vector<cv::Mat>& frames,
                                 const CalibrationOptions& opt) {
  std::string why;
  if (!opt.IsValid(&why)) throw std::invalid_argument("calibrate: " + why);
  const int n = static_cast<int>(nominal.cameras.size());
  if (n < 2) throw std::invalid_argument("calibrate: the rig needs at least 2 cameras");
  check_frames(nominal, frames, "");
  CalibrationSummary res;
  res.rig = nominal;

  // 1. Features.
  std::vector<std::vector<CameraFeatures>> feats{detect_all(frames, opt)};
  // 2. Pairwise matching between overlapping cameras, and the scene model.
  std::vector<std::vector<PairMatches>> pms;
  const SceneModel scene = match_pairs(nominal, feats, opt, pms, res);
  // 3. Tracks (union-find over keypoints), tracks seen twice by one camera are dropped.
  std::vector<std::vector<TrackObservation>> tracks = build_tracks(feats[0], pms[0]);
  log_tracks(tracks);
  SolveState st;
  res = solve_tracks(nominal, nominal, std::move(tracks), scene, opt, std::move(res), &st);
  if (opt.refine_rounds > 0) refine_rounds(nominal, frames, feats[0], scene, opt, st, res);
  return res;
}

ShotMode parse_shot_mode(const std::string& name) {
  if (name == "average") return ShotMode::kAverage;
  if (name == "pool") return ShotMode::kPool;
  if (name == "auto") return ShotMode::kAuto;
  throw std::invalid_argument("unknown shot mode '" + name + "' (expected pool, average or auto)");
}

std::string to_string(ShotMode m) {
  return m == ShotMode::kAverage ? "average" : m == ShotMode::kPool ? "pool" : "auto";
}

double min_shot_psnr_db(const std::vector<std::vector<cv::Mat>>& sets) {
  double lowest = std::numeric_limits<double>::infinity();
  auto gray8 = [](const cv::Mat& m) {
    cv::Mat g = m;
    if (g.channels() == 3) cv::cvtColor(g, g, cv::COLOR_BGR2GRAY);
    if (g.channels() == 4) cv::cvtColor(g, g, cv::COLOR_BGRA2GRAY);
    if (g.depth() == CV_16U) g.convertTo(g, CV_8U, 1.0 / 257);
    return g;
  };
  for (size_t s = 1; s < sets.size(); ++s) {
    if (sets[s].size() != sets[0].size())
      throw std::invalid_argument(fmt::format("shots differ: shot {} has {} frames, shot 0 has {}", s,
                                              sets[s].size(), sets[0].size()));
    for (size_t i = 0; i < sets[s].size(); ++i) {
      if (sets[s][i].size() != sets[0][i].size())
        throw std::invalid_argument(
            fmt::format("shots differ: camera index {} is {}x{} in shot {} but {}x{} in "
                        "shot 0",
                        i, sets[s][i].cols, sets[s][i].rows, s, sets[0][i].cols, sets[0][i].rows));
      lowest = std::min(lowest, cv::PSNR(gray8(sets[0][i]), gray8(sets[s][i])));
    }
  }
  return lowest;
}

bool shots_differ(const std::vector<std::vector<cv::Mat>>& sets) {
  return min_shot_psnr_db(sets) < kShotsDifferPsnrDb;
}

CalibrationSummary calibrate_shots(const Rig& nominal, const std::vector<std::vector<cv::Mat>>& sets,
                                   ShotMode mode, const CalibrationOptions& opt) {
  if (sets.empty()) throw std::invalid_argument("calibrate: no shots");
  if (mode == ShotMode::kAuto) {
    const double psnr = min_shot_psnr_db(sets);
    mode = psnr < kShotsDifferPsnrDb ? ShotMode::kPool : ShotMode::kAverage;
    spdlog::info("calibrate: {} shot(s), lowest PSNR between shots {:.1f} dB -> {}", sets.size(), psnr,
                 to_string(mode));
  }
  if (mode == ShotMode::kAverage || sets.size() == 1) {
    CalibrationSummary r = calibrate_rig(nominal, average_frame_sets(sets), opt);
    r.shots = 1;
    return r;
  }
  std::string why;
  if (!opt.IsValid(&why)) throw std::invalid_argument("calibrate: " + why);
  if (nominal.cameras.size() < 2) throw std::invalid_argument("calibrate: the rig needs at least 2 cameras");
  for (size_t s = 0; s < sets.size(); ++s) check_frames(nominal, sets[s], fmt::format("shot {}: ", s));
  CalibrationSummary res;
  res.rig = nominal;
  res.shots = static_cast<int>(sets.size());
  // 1.-3. per shot: features, matches, tracks; a scene point belongs to one shot.
  std::vector<std::vector<CameraFeatures>> feats;
  for (const auto& frames : sets) feats.push_back(detect_all(frames, opt));
  std::vector<std::vector<PairMatches>> pms;
  const SceneModel scene = match_pairs(nominal, feats, opt, pms, res);
  std::vector<std::vector<TrackObservation>> tracks;
  for (size_t s = 0; s < sets.size(); ++s) {
    auto t = build_tracks(feats[s], pms[s]);
    tracks.insert(tracks.end(), std::make_move_iterator(t.begin()), std::make_move_iterator(t.end()));
  }
  log_tracks(tracks);
  if (opt.refine_rounds > 0 || (scene == SceneModel::kNear && opt.dense_refine)) {
    res.warnings.push_back(
        "pooled shots: the subpixel refinement is not run (keypoint positions as detected)");
    spdlog::warn("calibrate: {}", res.warnings.back());
  }
  return solve_tracks(nominal, nominal, std::move(tracks), scene, opt, std::move(res));
}

std::vector<cv::Mat> average_frame_sets(const std::vector<std::vector<cv::Mat>>& sets) {
  if (sets.empty()) throw std::invalid_argument("average_frame_sets: no frame sets");
  const size_t n = sets[0].size();
  for (size_t s = 0; s < sets.size(); ++s) {
    if (sets[s].size() != n)
      throw std::invalid_argument(
          fmt::format("shots differ: shot {} has {} frames, shot 0 has {}", s, sets[s].size(), n));
    for (size_t i = 0; i < n; ++i) {
      const cv::Mat& f = sets[s][i];
      if (f.type() != CV_8UC3 && f.type() != CV_16UC3)
        throw std::invalid_argument(
            fmt::format("shot {}, camera index {}: not an 8- or 16-bit colour frame", s, i));
      if (f.size() != sets[0][i].size())
        throw std::invalid_argument(
            fmt::format("shots differ: camera index {} is {}x{} in shot {} but {}x{} in shot 0", i, f.cols,
                        f.rows, s, sets[0][i].cols, sets[0][i].rows));
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
      for (size_t k = 0; k < sum.total() * 3; ++k)
        dst[k] = uint16_t(std::lround(65535.0f * linear_to_srgb(src[k])));
      out[size_t(i)] = enc;
    }
  });
  return out;
}

}  // namespace omma::calib
