// Free-running simulated cameras for the live engine (thesis §5.1, Table 5.1).
//
// The dome's sensors free-run at 44-56 fps, each on its own oscillator, so the frames of one
// panorama differ in age by at most about one frame period. The simulator cannot render 24 cameras
// at 50 fps in real time (a colon frame of the 250x250 prototype camera costs milliseconds of ray
// marching), so SimLoop renders a loop of the motion once, at start-up (progress line on stderr),
// and then plays it back on each camera's own clock:
//
//   camera c runs at f_c (drawn uniformly in [fps_min, fps_max], rounded so that a whole number
//   N_c = round(T f_c) of frames fills the loop of T seconds), with phase phi_c (uniform in one
//   period) and per-frame jitter j_ck (Gaussian, sd jitter_ms, clipped to a quarter period);
//   frame k of the loop is captured at tau_ck = phi_c + k / f_c + j_ck and shows the scene at
//   scene time tau_ck (mod T). Played back from the instant S the first camera starts, frame k of
//   repetition m is delivered at S + m T + tau_ck, and that is its capture instant.
//
// The motion is periodic with period T and smooth (continuous position and velocity), so the
// loop has no seam: colon, the dome moves along the tube axis z(t) = A (1 - cos(2 pi t / T)) / 2;
// a scene that says how it is travelled (Scene::travel, e.g. the room: along its corridor, +x), the
// dome moves the same way along that direction; other scenes, it turns about the dome axis by the
// angle a(t) = A (1 - cos(2 pi t / T)) / 2; the peak speed is pi A / T = `speed` (mm/s or deg/s),
// so A = speed T / pi.
//
// A camera read late (busy machine) delivers the newest frame already captured, as a sensor
// writing into a latest-frame buffer would.
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/core/rig.h"
#include "omma/live/sources.h"
#include "omma/sim/render.h"
#include "omma/sim/scene.h"

namespace omma::live {

// The dome's periodic motion (see the file comment).
struct SimMotion {
  bool translate = false;           // along `axis` (colon, room) or turning about the dome axis
  Vec3 axis = Vec3::UnitZ();        // unit direction of the translation, scene frame
  double speed = 10;                // peak speed, mm/s (translate) or deg/s, at most kMaxSimSpeed
  double period_s = 2;              // T
  double amplitude() const;         // A: mm or deg
  double offset(double t_s) const;  // z (mm) or angle (deg) at scene time t (any t: periodic)
  sim::DomePose pose(double t_s) const;
};

// Create with std::make_shared (its sources share it).
class SimLoop : public std::enable_shared_from_this<SimLoop> {
 public:
  // `scene` as sim::make_scene takes it (colon, room, photo:PATH, usaf[:MM], checker[:MM]); `speed`
  // the peak speed (default: 5 mm/s for the colon, the scene's own (Scene::travel) for the room,
  // 300 mm/s, 10 deg/s for the others). Draws the cameras' clocks
  // and renders the loop (in parallel, progress on stderr). Throws SourceError for a bad scene or
  // options.
  SimLoop(const Rig& rig, const std::string& scene, std::optional<double> speed, const SimCameraOptions& opt);
  // Any scene; `translate`: the dome moves along the scene's z axis (mm/s) instead of turning (deg/s).
  // A scene with Scene::travel() moves along its direction (default speed its speed) either way.
  SimLoop(const Rig& rig, std::shared_ptr<const sim::Scene> scene, bool translate,
          std::optional<double> speed, const SimCameraOptions& opt);

  // One source per rig camera, in rig order, playing the loop back on its own clock. The clocks
  // start (S) when the first of them is asked for its first capture instant.
  std::vector<std::unique_ptr<CameraSource>> sources();

  // Scene time (s, in [0, T)) of a steady-clock instant after the start (for tests: the scene as it
  // was at that instant is scene().radiance at motion().pose(scene_time(t))).
  double scene_time(Clock::time_point t) const;
  Clock::time_point start() const;  // S; time_point{} before the first camera asked
  const SimMotion& motion() const { return motion_; }
  const sim::Scene& scene() const { return *scene_; }
  double camera_fps(int c) const { return double(frames_[c].size()) / motion_.period_s; }
  // Camera c's capture instants tau_ck in the loop (s) and its frames (rig order).
  const std::vector<double>& capture_times(int c) const { return capture_s_[c]; }
  const std::vector<cv::Mat>& loop_frames(int c) const { return frames_[c]; }
  size_t frames() const;  // pre-rendered frames in all
  double render_seconds() const { return render_s_; }
  size_t bytes() const;  // memory of the pre-rendered frames

 private:
  friend class SimLoopCamera;
  Clock::time_point start_now();  // sets S on the first call
  std::shared_ptr<const sim::Scene> scene_;
  SimMotion motion_;
  std::string spec_;
  std::vector<std::vector<cv::Mat>> frames_;    // [camera][k]
  std::vector<std::vector<double>> capture_s_;  // [camera][k]: tau_ck, s from the loop start
  mutable std::mutex mutex_;
  Clock::time_point start_{};
  double render_s_ = 0;
};

}  // namespace omma::live
