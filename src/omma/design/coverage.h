// Coverage analysis of a dome (thesis §2.4.2, §3.3-3.4, Fig. 7.5).
//
// Model: each camera i has its pinhole at p_i (on the dome surface, mm), optical axis t_i and
// angle of view aov_i. A point X (mm, dome frame) is seen by camera i when the angle between
// X - p_i and t_i is at most aov_i / 2; for a camera with a rectangular field
// (Intrinsics::Field::kImage) when X - p_i projects inside its image (the fast path uses the four
// planes through p_i and the image edges: exact without distortion, the undistorted edges with it).
// At distance +infinity only directions count (X - p_i -> X). The field of view of the dome is the hemisphere
// theta in [0, 90 deg] around +z, or the full sphere when rig.dome.sphere is true. A distance R is covered
// when every direction w of the field of view has its point R w seen by at least one camera.
// R_vir (the virtual radius, "overlap distance") is the smallest R from which on there is no gap.
//
// Sampling: directions theta = j * step (j = 0..N, the pole and the rim included), phi = k * step;
// statistics are weighted by solid angle. Units: mm and radians in the API (the CLI uses degrees).
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "omma/core/grid.h"
#include "omma/core/rig.h"

namespace omma::design {

// The sampled field of view of a dome.
struct Sampling {
  double step_rad = deg2rad(0.1);
  bool sphere = false;
  double theta_limit = 0;                // if > 0: the field of view ends at this polar angle (radians)
  int rows = 0, cols = 0;                // theta samples (pole and rim included), phi samples
  std::vector<double> cos_phi, sin_phi;  // per column (filled by make_sampling)
  double theta_max() const { return theta_limit > 0 ? theta_limit : sphere ? kPi : kPi / 2; }
  double theta(int row) const;  // row * step, the last row clamped to theta_max
  double phi(int col) const { return col * step_rad; }
  Vec3 direction(int row, int col) const;
  double weight(int row) const;  // solid angle of one sample of this row (sums to the FOV's)
};
Sampling make_sampling(double step_rad, bool sphere, double theta_limit = 0);

// Reference test: is the point X (mm) inside camera cam's field of view (cone, or image bounds)?
bool camera_sees_point(const RigCamera& cam, const Vec3& X);
// Reference: number of cameras that see the point distance_mm * w (w unit; distance may be +inf).
int cameras_seeing(const Rig& rig, const Vec3& w, double distance_mm);

// Closed form (fast path): the smallest R >= 0 from which on every point R' w (R' >= R) is seen
// by at least one camera; +infinity if the far field of w is not covered. For a radial camera
// (p = rho t) this is eq. 3.1 solved for the distance: rho sin(h) / sin(h - angle(w, t)).
double covered_from(const Rig& rig, const Vec3& w);

// A band of polar angles [from, to] (radians, sample rows) and the counts seen inside it.
struct PolarBand {
  double from_rad = 0, to_rad = -1;
  int min_cameras = 0, max_cameras = 0;
  bool empty() const { return to_rad < from_rad; }
};

struct CoverageSummary {
  double distance_mm = 0;  // may be +infinity
  double step_deg = 0;
  double theta_max_deg = 0;     // the sampled field of view: polar 0..theta_max
  double covered_fraction = 0;  // solid-angle fraction of the FOV seen by >= 1 camera
  int min_cameras = 0, max_cameras = 0;
  double mean_cameras = 0;                   // solid-angle weighted mean count
  double r_virtual_mm = 0;                   // R_vir (max over the samples of covered_from); inf if never
  std::vector<double> solid_angle_by_count;  // [n]: steradians seen by exactly n cameras
  std::vector<double> row_theta_rad;         // per sample row: polar angle,
  std::vector<int> row_min, row_max;         // and the fewest / most cameras along it
  double solid_angle_at_least(int n) const;  // steradians seen by >= n cameras
  // The widest band of whole sample rows in which every sample is seen by >= n cameras (the
  // counts inside it: min..max); empty if there is none.
  PolarBand polar_band(int n) const;
};
// Counts at distance_mm (> 0, may be +infinity) and R_vir, on the sampling of the given step;
// theta_max_rad > 0 limits the field of view to polar 0..theta_max (default: the dome's hemisphere
// or sphere). Parallel (oneTBB).
CoverageSummary analyze_coverage(const Rig& rig, double distance_mm, double step_rad,
                                 double theta_max_rad = 0);
// R_vir only (fast closed form, parallel).
double virtual_radius(const Rig& rig, double step_rad);
// Reference R_vir: bisection on "every sample is covered at R" between lo and hi (mm), to tol_mm.
// Plain and slow; agrees with virtual_radius for rigs whose coverage grows with distance.
double virtual_radius_bisection(const Rig& rig, double step_rad, double tol_mm = 1e-3, double hi_mm = 1e4);

// Per-pixel number of cameras that see distance_mm * grid.pixel_direction(col, row): CV_32SC1,
// grid.height x grid.width. Parallel.
cv::Mat coverage_count_map(const Rig& rig, const PanoGrid& grid, double distance_mm);
// Colour-coded picture of a count map (0 = black, then one colour per count) with a legend strip
// below it (a swatch and the number for each count, and `title`). BGR CV_8UC3.
cv::Mat render_coverage_map(const cv::Mat& counts, const std::string& title);
// BGR colour used for a count (the legend's colours).
cv::Vec3b coverage_color(int count, int max_count);

// Cap model for radial rigs (what the designers use): the covering radius of a set of unit axes,
// i.e. the largest angle from any sampled direction of the FOV to its nearest axis, in radians.
// A radial rig with equal cameras covers distance R exactly when this is <= reach_angle(R).
double covering_radius(const std::vector<Vec3>& axes, const Sampling& s);
// Does every sample lie within `reach` (radians) of some axis? Stops at the first gap.
bool covers(const std::vector<Vec3>& axes, const Sampling& s, double reach);
// Polar angle (radians) of the first sample row, from the pole, holding a direction farther than
// `reach` from every axis; +infinity when all are within reach ("theta_uc" of eq. 3.6). Rows
// above from_theta are assumed covered (not scanned).
double first_uncovered_theta(const std::vector<Vec3>& axes, const Sampling& s, double reach,
                             double from_theta = 0);
// Largest distance from any direction of the field of view to the nearest sample (radians):
// a conservative check adds it to the sampled covering radius.
double sampling_radius(const Sampling& s);

}  // namespace omma::design
