// omma calibrate: calibrate a rig from one set of camera frames (thesis §3.6): SIFT features,
// matching between cameras whose nominal views overlap, RANSAC, Ceres bundle adjustment.
#include "omma/calib/calibrate.h"

#include <chrono>
#include <filesystem>
#include <iostream>

#include <fmt/format.h>

#include "apps/command.h"
#include "omma/calib/initial_pose.h"
#include "omma/calib/photometric.h"
#include "omma/core/frames.h"
#include "omma/core/log.h"
#include "omma/core/rig.h"
#include "omma/design/prototype.h"

namespace omma::app {

namespace {
double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct CalibrateArgs {
  std::vector<std::string> frames;
  std::string shots = "auto", position = "fixed";
  std::string rig, out, flat, scene = "auto", focal = "per-camera", center = "per-camera",
                              distortion = "per-camera", loss = "auto";
  int radial_terms = 1, max_iterations = 50, min_matches = 30, upsample = 2, threads = 2,
      dense_rounds = calib::CalibrationOptions{}.dense_rounds;
  double self_ratio = 0;
  double loss_scale = 1.0, ransac_px = 5, prior_deg = 5, prior_mean_focal = 0.002, tube = 0;
  bool tube_tilt = false;
  bool json = false, photometric = false, no_geometric = false, initial_pose = false;
};

// "per-camera" | "shared" | "fixed" -> (estimate, share)
void parse_mode(const std::string& what, const std::string& mode, bool* estimate, bool* share) {
  if (mode == "per-camera")
    *estimate = true, *share = false;
  else if (mode == "shared")
    *estimate = true, *share = true;
  else if (mode == "fixed")
    *estimate = false, *share = false;
  else
    throw std::invalid_argument(
        fmt::format("--{} must be per-camera, shared or fixed (got '{}')", what, mode));
}
// --initial-pose: the rig's cameras oriented from the images of one shot (calib/initial_pose.h), with
// their intrinsics, ids and photometric models kept; positions on the rig's dome along each axis.
Rig with_initial_pose(const Rig& rig, const std::vector<cv::Mat>& frames, nlohmann::json* report) {
  std::vector<Intrinsics> intrinsics;
  for (const auto& c : rig.cameras) intrinsics.push_back(c.in);
  calib::InitialPoseOptions po;
  po.dome_radius_mm = rig.dome.radius_mm;
  const auto t0 = std::chrono::steady_clock::now();
  const calib::InitialPoseSummary s = calib::initial_pose(frames, intrinsics, po);
  Rig out = rig;
  for (size_t i = 0; i < out.cameras.size(); ++i) {
    out.cameras[i].frame = s.rig.cameras[i].frame;
    out.cameras[i].position_mm = s.rig.cameras[i].position_mm;
  }
  out.validate();
  nlohmann::json pairs = nlohmann::json::array();
  for (const auto& p : s.pairs) {
    if (!p.in_tree) continue;
    pairs.push_back({{"cameras", {rig.cameras[p.cam_a].id, rig.cameras[p.cam_b].id}},
                     {"matches", p.matches},
                     {"inliers", p.inliers},
                     {"rms_px", p.rms_px}});
    spdlog::info("calibrate: initial pose: cameras {} and {}: {} matches, {} inliers, RMS {:.2f} px",
                 rig.cameras[p.cam_a].id, rig.cameras[p.cam_b].id, p.matches, p.inliers, p.rms_px);
  }
  for (const auto& w : s.warnings) spdlog::warn("calibrate: initial pose: {}", w);
  *report = {{"pairs", pairs}, {"seconds", seconds_since(t0)}};
  return out;
}
}  // namespace

void add_calibrate_command(CLI::App& root) {
  static CalibrateArgs a;
  auto* cmd = root.add_subcommand(
      "calibrate",
      "Calibrate a rig from camera frames (thesis §3.6): SIFT features in every camera, matching between\n"
      "cameras whose nominal cones of view intersect, RANSAC (rotation-only model for a far scene, "
      "essential\n"
      "matrix with parallax), then a Ceres bundle adjustment of each camera's rotation, fu, fv, cu, cv and\n"
      "radial distortion with a robust loss. Cameras with too few matches keep their nominal values "
      "(warning).\n"
      "Several shots (--frames repeated, or a shots folder): of a static scene they are averaged; of a\n"
      "scene that changes between shots (a static rig, a moving chessboard) their matches are pooled into\n"
      "one adjustment (--shots). --photometric adds\n"
      "each camera's vignetting and colour gains (from the overlaps, or --flat DIR), applied from then on "
      "by\n"
      "stitch, run and the engine.");
  cmd->add_option("--rig", a.rig, "Nominal rig (JSON)")->required();
  cmd->add_option(
         "--frames", a.frames,
         "Frames folder (DIR/cam_XX.png per camera, omma/core/frames.h) or shots folder (DIR/shot_XX/, "
         "`omma simulate --shots`); repeat for several shots of a static scene: the geometric calibration "
         "averages them in linear light (noise / sqrt(shots)), the photometric one pools their overlaps")
      ->required();
  cmd->add_option("--out", a.out, "Calibrated rig to write (JSON, atomic)")->required();
  cmd->add_option(
      "--shots", a.shots,
      "Several shots: pool (features, matches and tracks per shot, one bundle adjustment: the "
      "scene may change between shots, the rig may not), average (a static scene: frames averaged "
      "in linear light) or auto (default: pool when the shots' frames of one camera differ, PSNR "
      "below 28 dB, else average)");
  cmd->add_option(
      "--position", a.position,
      "Camera positions (near field): fixed (default: at the nominal ones) or estimate (every "
      "camera's direction from the first camera; the first camera's pose and every distance from it "
      "are held: the gauge; a real baseline, e.g. a stereo pair; implies --prior-mean-focal 0 unless "
      "given)");
  cmd->add_option("--scene", a.scene,
                  "Scene model: far (rotation only), near (parallax: scene points, camera "
                  "positions fixed at nominal) or auto (default: from the RANSAC consensus)");
  cmd->add_option("--focal", a.focal, "fu, fv: per-camera (default), shared or fixed");
  cmd->add_option("--center", a.center, "cu, cv: per-camera (default), shared or fixed");
  cmd->add_option("--distortion", a.distortion, "radial k: per-camera (default), shared or fixed");
  cmd->add_option("--radial-terms", a.radial_terms,
                  "How many radial coefficients to estimate: 1 = k1 (default), "
                  "2 = k1, k2, 3 = k1, k2, k5");
  cmd->add_option(
      "--loss", a.loss,
      "Robust loss: auto (default: huber in the far field, cauchy in the near field), huber, cauchy or none");
  cmd->add_option("--loss-scale", a.loss_scale, "Robust loss scale, pixels (default 1)");
  cmd->add_option("--ransac-px", a.ransac_px, "RANSAC inlier threshold, pixels (default 5)");
  cmd->add_option(
         "--self-ratio", a.self_ratio,
         "Repetitive texture (a chessboard): drop a match when either keypoint has a look-alike in its "
         "own image closer than the match distance / this (0 = off, the default; 0.7 halves the "
         "wrong matches on OpenCV's stereo chessboard shots)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--prior-deg", a.prior_deg, "Gauge prior on the rotation corrections, degrees (default 5)");
  auto* prior_mean_focal = cmd->add_option(
      "--prior-mean-focal", a.prior_mean_focal,
      "Near field only: sigma (relative) of the prior holding the cameras' MEAN focal length at the "
      "nominal one, against the focal/depth ambiguity of small-baseline parallax (default 0.002; 0 = off)");
  cmd->add_option(
      "--tube", a.tube,
      "The frames show the calibration tube of this diameter (mm; the thesis's is 35) around the dome: "
      "near field, and scene points on its wall are constrained to it (its axis offset is estimated; "
      "its axis defines the rig's z axis, as the thesis's fixture does); default 0 = a scene of unknown "
      "shape");
  cmd->add_flag(
      "--tube-tilt", a.tube_tilt,
      "Estimate the tube's tilt too (a mount that is not trusted): the rig's tilt is then held only by the "
      "5 mm parallax of the camera positions; compare with rig-diff --align");
  cmd->add_option("--max-iterations", a.max_iterations, "Ceres iterations per solve (default 50)");
  cmd->add_option("--dense-rounds", a.dense_rounds,
                  "Near field: rounds of dense patch alignment and re-solve after the first solve")
      ->capture_default_str()
      ->check(CLI::Range(0, 10));
  cmd->add_option("--threads", a.threads,
                  "Ceres threads (default 2); 1 = reproducible to the last digit (near-field results move by "
                  "~0.2 deg with the summation order of a multi-threaded solve)")
      ->check(CLI::Range(1, 256));
  cmd->add_option("--min-matches", a.min_matches,
                  "Matched observations a camera needs to be calibrated "
                  "(default 30)");
  cmd->add_option("--upsample", a.upsample, "Run SIFT on frames upsampled this much (default 2; 1 = off)");
  cmd->add_flag(
      "--photometric", a.photometric,
      "Also calibrate each camera's vignetting and colour gains (calib/photometric.h) from the overlaps "
      "of the frames (after the geometric calibration, on its rig), and store them in the rig file");
  cmd->add_option(
      "--flat", a.flat,
      "Calibrate vignetting and gains from this flat-field frames (or shots) folder instead: a uniformly "
      "lit white target (implies --photometric)");
  cmd->add_flag(
      "--no-geometric", a.no_geometric,
      "Keep the rig's geometry as given (already calibrated); only the photometric calibration runs");
  cmd->add_flag(
      "--initial-pose", a.initial_pose,
      "Estimate every camera's orientation from the images first (calib/initial_pose.h: SIFT between\n"
      "every pair without a prior, RANSAC on the rotation, chained from camera 0 looking along +z), keeping\n"
      "the rig's intrinsics: for cameras whose poses nobody measured, e.g. a rig from `omma rig new` with\n"
      "sizes and focal lengths only");
  cmd->add_flag("--json", a.json, "Print one JSON object on stdout");
  cmd->callback([prior_mean_focal] {
    set_json_mode(a.json);
    Rig nominal = design::load_rig_or_builtin(a.rig);
    const bool photometric = a.photometric || !a.flat.empty();
    if (a.no_geometric && !photometric)
      throw std::invalid_argument("--no-geometric leaves nothing to do: add --photometric or --flat DIR");
    std::vector<std::filesystem::path> paths(a.frames.begin(), a.frames.end());
    const auto sets = load_frame_sets(paths, nominal);
    nlohmann::json initial = nullptr;
    if (a.initial_pose) {
      if (a.no_geometric) throw std::invalid_argument("--initial-pose and --no-geometric exclude each other");
      nominal = with_initial_pose(nominal, sets.front(), &initial);
    }
    std::vector<std::vector<cv::Mat>> flats;
    if (!a.flat.empty()) flats = load_frame_sets({a.flat}, nominal);
    calib::CalibrationOptions opt;
    opt.scene = calib::parse_scene_model(a.scene);
    bool share = false;
    parse_mode("focal", a.focal, &opt.estimate_focal, &opt.share_focal);
    parse_mode("center", a.center, &opt.estimate_center, &opt.share_center);
    bool est_k = true;
    parse_mode("distortion", a.distortion, &est_k, &share);
    opt.share_distortion = share;
    if (a.radial_terms < 0 || a.radial_terms > 3) throw std::invalid_argument("--radial-terms must be 0..3");
    opt.radial_terms = est_k ? a.radial_terms : 0;
    if (a.loss != "auto" && a.loss != "huber" && a.loss != "cauchy" && a.loss != "none")
      throw std::invalid_argument("--loss must be auto, huber, cauchy or none");
    opt.loss = a.loss;
    opt.loss_scale_px = a.loss_scale;
    opt.match.ransac_threshold_px = a.ransac_px;
    opt.match.self_ratio = a.self_ratio;
    opt.prior_rotation_deg = a.prior_deg;
    if (a.prior_mean_focal < 0) throw std::invalid_argument("--prior-mean-focal must be >= 0");
    opt.prior_mean_focal = a.prior_mean_focal;
    if (a.position != "fixed" && a.position != "estimate")
      throw std::invalid_argument("--position must be fixed or estimate (got '" + a.position + "')");
    opt.estimate_position = a.position == "estimate";
    if (opt.estimate_position && prior_mean_focal->count() == 0) opt.prior_mean_focal = 0;
    const calib::ShotMode shot_mode = calib::parse_shot_mode(a.shots);
    opt.max_iterations = a.max_iterations;
    opt.dense_rounds = a.dense_rounds;
    if (a.tube < 0) throw std::invalid_argument("--tube must be a diameter in mm (> 0), or 0 for none");
    opt.tube_diameter_mm = a.tube;
    opt.tube_tilt = a.tube_tilt;
    if (a.tube > 0) opt.scene = calib::SceneModel::kNear;
    opt.threads = a.threads;
    opt.min_observations = a.min_matches;
    opt.features.upsample = a.upsample;
    const auto t0 = std::chrono::steady_clock::now();
    calib::CalibrationSummary r;
    r.rig = nominal;
    if (!a.no_geometric) {
      // With a flat field the frames are flat-fielded first: the patch alignment is then free of
      // the vignetting ramp (calib/photometric.h flat_field_frames).
      bool pool = sets.size() > 1 && shot_mode == calib::ShotMode::kPool;
      if (sets.size() > 1 && shot_mode == calib::ShotMode::kAuto) {
        const double psnr = calib::min_shot_psnr_db(sets);
        pool = psnr < calib::kShotsDifferPsnrDb;
        spdlog::info("calibrate: {} shots, lowest PSNR between shots {:.1f} dB -> {}", sets.size(), psnr,
                     pool ? "pool (the scene changes)" : "average (a static scene)");
      }
      if (pool) {
        if (!flats.empty())
          throw std::invalid_argument("--flat with pooled shots is not supported: use --shots average");
        r = calib::calibrate_shots(nominal, sets, calib::ShotMode::kPool, opt);
      } else {
        std::vector<cv::Mat> frames = calib::average_frame_sets(sets);
        if (!flats.empty()) frames = calib::flat_field_frames(frames, flats);
        r = calib::calibrate_rig(nominal, frames, opt);
      }
    }
    const double geometric_s = seconds_since(t0);
    Rig out = r.rig;
    nlohmann::json pj = nullptr;
    std::vector<std::string> warnings = r.warnings;
    if (photometric) {
      calib::PhotometricOptions po;
      po.threads = a.threads;
      const auto t1 = std::chrono::steady_clock::now();
      const calib::PhotometricSummary ps = a.flat.empty() ? calib::calibrate_photometric(out, sets, po)
                                                          : calib::calibrate_flat_field(out, flats, po);
      out = ps.rig;
      warnings.insert(warnings.end(), ps.warnings.begin(), ps.warnings.end());
      pj = {{"source", a.flat.empty() ? "overlaps" : "flat-field"},
            {"pairs", ps.pairs},
            {"samples", ps.samples},
            {"rms_log", ps.rms_log},
            {"initial_rms_log", ps.initial_rms_log},
            {"lens", ps.lens},
            {"max_fit_error", ps.max_fit_error},
            {"uncalibrated", ps.uncalibrated_ids},
            {"seconds", seconds_since(t1)}};
    }
    save_rig(out, a.out);
    if (a.json) {
      nlohmann::json per = nlohmann::json::array();
      for (const auto& c : r.per_camera)
        per.push_back(
            {{"id", c.id}, {"rms_px", c.rms_px}, {"matches", c.matches}, {"calibrated", c.calibrated}});
      print_json({{"cameras", out.cameras.size()},
                  {"shots", sets.size()},
                  {"shot_mode", r.shots > 1       ? "pool"
                                : sets.size() > 1 ? "average"
                                                  : "single"},
                  {"geometric", !a.no_geometric},
                  {"matches", r.matches},
                  {"inliers", r.inliers},
                  {"rms_px", r.rms_px},
                  {"initial_rms_px", r.initial_rms_px},
                  {"scene", calib::to_string(r.scene)},
                  {"pairs", r.pairs},
                  {"tracks", r.tracks},
                  {"observations", r.observations},
                  {"rejected", r.rejected},
                  {"uncalibrated", r.uncalibrated_ids},
                  {"warnings", warnings},
                  {"per_camera", per},
                  {"geometric_seconds", geometric_s},
                  {"photometric", pj},
                  {"initial_pose", initial},
                  {"out", a.out}});
    } else {
      if (!a.no_geometric)
        std::cout << fmt::format(
            "{}: {} cameras ({} uncalibrated) from {} shot(s), {} matches, {} inliers, {} scene, "
            "reprojection RMS {:.3f} px (nominal rig {:.3f} px)\n",
            a.out, out.cameras.size(), r.uncalibrated_ids.size(), sets.size(), r.matches, r.inliers,
            calib::to_string(r.scene), r.rms_px, r.initial_rms_px);
      if (!pj.is_null())
        std::cout << fmt::format("{}: photometric model from {} ({} samples), RMS {:.4f} -> {:.4f} (log)\n",
                                 a.out, pj["source"].get<std::string>(), pj["samples"].get<int>(),
                                 pj["initial_rms_log"].get<double>(), pj["rms_log"].get<double>());
    }
  });
}

}  // namespace omma::app
