// Synthetic-aperture refocusing (refocus.h) on the thesis's dome: cards with a step edge at two
// distances (sharp on the focal surface, blurred off it), and a card behind a grid occluder
// (recovered by the median combination).
#include "omma/pano/refocus.h"

#include <cmath>
#include <random>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "omma/design/prototype.h"
#include "omma/pano/quality.h"
#include "omma/pano/stitch.h"
#include "omma/sim/scene.h"
#include "omma/sim/simulate.h"

namespace omma::pano {
namespace {

// A square card of half-size `half_mm` facing the origin, its centre `distance_mm` along `dir`:
// a step edge through its centre (dark left, bright right, slanted `slant_deg` from the card's
// vertical), or a value-noise print; optionally a grid of bars in front of it.
struct Card {
  Vec3 dir;
  double distance_mm, half_mm;
  bool edge = true;
  double slant_deg = 5;
};

// Ray-plane hit of the card: distance along dir, and the card's local coordinates (mm).
bool hit_card(const Card& k, const Vec3& o, const Vec3& d, double* s, double* x, double* y) {
  const Vec3 n = k.dir;  // normal (towards +dir)
  const double den = d.dot(n);
  if (den <= 1e-9) return false;
  const Vec3 p0 = k.distance_mm * k.dir;
  const double t = (p0 - o).dot(n) / den;
  if (t <= 0) return false;
  const Vec3 p = o + t * d - p0;
  const Vec3 e1 = Vec3(0, 0, 1).cross(n).normalized(), e2 = n.cross(e1);
  *x = p.dot(e1);
  *y = p.dot(e2);
  *s = t;
  return std::abs(*x) <= k.half_mm && std::abs(*y) <= k.half_mm;
}

class CardScene : public sim::Scene {
 public:
  std::vector<Card> cards;
  // A grid occluder on the plane of `grid_card` (facing the origin like a card), `bar_mm` bars every
  // `pitch_mm` in both directions, dark grey.
  bool has_grid = false;
  Card grid_card{};
  double bar_mm = 0.4, pitch_mm = 1.6;

  double value_noise(double x, double y) const {
    // Sum of three sine gratings per axis at incommensurate frequencies: texture at several scales.
    return 0.5 + 0.18 * std::sin(2.1 * x + 0.7 * y) + 0.12 * std::sin(5.3 * y - 1.9 * x) +
           0.1 * std::sin(9.7 * x + 7.1 * y);
  }
  bool grid_hit(const Vec3& o, const Vec3& d, double* s) const {
    double x, y;
    if (!has_grid || !hit_card(grid_card, o, d, s, &x, &y)) return false;
    auto on_bar = [&](double u) {
      const double m = std::fmod(std::abs(u), pitch_mm);
      return m < bar_mm;
    };
    return on_bar(x) || on_bar(y);
  }
  cv::Vec3f radiance(const Vec3& o, const Vec3& d, const Vec3&) const override {
    double s_grid;
    const bool g = grid_hit(o, d, &s_grid);
    double best = 1e30;
    cv::Vec3f v(0.3f, 0.3f, 0.3f);  // background far away
    for (const Card& k : cards) {
      double s, x, y;
      if (!hit_card(k, o, d, &s, &x, &y) || s >= best) continue;
      best = s;
      if (k.edge) {
        const double a = deg2rad(k.slant_deg);
        const float l = (x * std::cos(a) - y * std::sin(a)) > 0 ? 0.8f : 0.1f;
        v = cv::Vec3f(l, l, l);
      } else {
        const float l = static_cast<float>(value_noise(x, y));
        v = cv::Vec3f(l * 0.9f, l, l * 1.1f);
      }
    }
    if (g && s_grid < best) return cv::Vec3f(0.05f, 0.05f, 0.05f);
    return v;
  }
  double distance(const Vec3& o, const Vec3& d) const override {
    double best = std::numeric_limits<double>::infinity(), s, x, y;
    for (const Card& k : cards)
      if (hit_card(k, o, d, &s, &x, &y)) best = std::min(best, s);
    if (grid_hit(o, d, &s)) best = std::min(best, s);
    return best;
  }
  std::string spec() const override { return "test-cards"; }
};

std::vector<cv::Mat> render_frames(const Rig& rig, const sim::Scene& scene) {
  sim::SimulateOptions so;
  so.effects = sim::CameraEffects::ideal(2);
  so.truth = false;
  so.progress = false;
  const auto r = sim::simulate(rig, scene, so);
  std::vector<cv::Mat> frames;
  for (const auto& f : r.frames) frames.push_back(f.image);
  return frames;
}

cv::Rect roi_at(const PanoGrid& grid, const Vec3& dir, int half) {
  const auto p = grid.pixel(dir.normalized());
  EXPECT_TRUE(p.has_value());
  return cv::Rect(int(p->x()) - half, int(p->y()) - half, 2 * half, 2 * half);
}

TEST(Refocus, OptionsAndBadInput) {
  RefocusOptions o;
  EXPECT_TRUE(o.IsValid());
  o.focus_mm = 0;
  EXPECT_FALSE(o.IsValid());
  o.focus_mm = 100;
  o.aperture_mm = -1;
  EXPECT_FALSE(o.IsValid());
  EXPECT_THROW(parse_aperture_shape("disc"), std::invalid_argument);
  EXPECT_THROW(parse_refocus_combine("max"), std::invalid_argument);
  const Rig rig = design::thesis_prototype_rig();
  RefocusOptions ok;
  ok.progress = false;
  EXPECT_THROW(refocus(rig, {}, ok), std::invalid_argument);  // no frames
}

TEST(Refocus, EdgeWidthOfKnownEdges) {
  // A step blurred by a Gaussian of sigma s has a 10-90 % width of 2.563 s.
  for (double sigma : {1.0, 2.0, 4.0}) {
    cv::Mat img(64, 64, CV_32FC1);
    for (int r = 0; r < 64; ++r)
      for (int c = 0; c < 64; ++c) img.at<float>(r, c) = (c + 0.5 - 32 - 0.1 * (r - 32)) > 0 ? 0.9f : 0.1f;
    cv::Mat blurred;
    cv::GaussianBlur(img, blurred, cv::Size(0, 0), sigma);
    const double w = edge_width_10_90(blurred, cv::Rect(8, 8, 48, 48));
    EXPECT_NEAR(w, 2.563 * sigma, 0.35) << "sigma " << sigma;
    EXPECT_NEAR(edge_width_10_90(cv::Mat(blurred.t()), cv::Rect(8, 8, 48, 48)), w, 0.1);  // horizontal
  }
  EXPECT_TRUE(
      std::isnan(edge_width_10_90(cv::Mat(32, 32, CV_32FC1, cv::Scalar(0.5)), cv::Rect(0, 0, 32, 32))));
  EXPECT_THROW(edge_width_10_90(cv::Mat(32, 32, CV_32FC1), cv::Rect(30, 30, 8, 8)), std::invalid_argument);
}

}  // namespace
}  // namespace omma::pano

namespace omma::pano {
namespace {

// The two edge cards: A at 20 mm (polar 40 deg), B at 60 mm on the other side; the frames of the
// thesis's dome (24 cameras, 5 mm) seeing them, ideal cameras.
struct TwoCards {
  Rig rig = design::thesis_prototype_rig();
  Vec3 da, db;
  std::vector<cv::Mat> frames;
  PanoGrid grid{Projection::kVr180, 540, 540};
  explicit TwoCards(double azimuth_deg) {
    CardScene scene;
    da = direction_from_spherical(deg2rad(40), deg2rad(azimuth_deg));
    db = direction_from_spherical(deg2rad(40), deg2rad(azimuth_deg + 180));
    scene.cards.push_back({da, 20, 12});
    scene.cards.push_back({db, 60, 36});
    frames = render_frames(rig, scene);
  }
  std::pair<double, double> widths(double focus_mm,
                                   double aperture_mm = std::numeric_limits<double>::infinity()) const {
    RefocusOptions o;
    o.grid = grid;
    o.focus_mm = focus_mm;
    o.aperture_mm = aperture_mm;
    o.progress = false;
    const auto r = refocus(rig, frames, o);
    return {edge_width_10_90(r.image, roi_at(grid, da, 32)), edge_width_10_90(r.image, roi_at(grid, db, 32))};
  }
};

TEST(Refocus, SharpOnTheFocalSurfaceBlurredOffIt) {
  // Measured (8 azimuths 5, 50, .. 320 deg; vr180 540x540, 0.33 deg/px, 64 px windows): on the
  // surface 0.83-2.07 px, the other card 15-30 px (focus on A at 20 mm: B 15.4-30.1 px; on B at 60 mm:
  // A 16.5-26.7 px); A at F = 30 mm 3.6-13.3 px and at F = 200 mm 24-35 px (the blur grows with
  // |1/20 - 1/F|); the nearest camera alone 0.94-2.73 px at either card (a seam between two cameras
  // crosses some windows).
  for (double az : {5.0, 230.0}) {
    const TwoCards t(az);
    const auto [a20, b20] = t.widths(20);
    const auto [a60, b60] = t.widths(60);
    EXPECT_LT(a20, 3) << az;
    EXPECT_LT(b60, 3) << az;
    EXPECT_GT(b20, 5 * a20) << az;
    EXPECT_GT(a60, 5 * b60) << az;
    const auto [a30, b30] = t.widths(30);
    const auto [a200, b200] = t.widths(200);
    EXPECT_LT(a20, a30) << az;
    EXPECT_LT(a30, a60) << az;
    EXPECT_LT(a60, a200) << az;
    // A pinhole aperture (the nearest camera only) keeps every depth as sharp as one camera.
    const auto [pa, pb] = t.widths(60, 0);
    EXPECT_LT(pa, 4) << az;
    EXPECT_LT(pb, 4) << az;
  }
}

TEST(Refocus, SeesThroughAGridOccluder) {
  // A textured card 40 mm away behind a grid of 0.15 mm bars every 2 mm, 15 mm away (21 % of the
  // card hidden from each camera; the bars shift by about 7 deg between neighbouring cameras). The
  // unoccluded truth is the same refocus of the card without the grid. Measured (8 azimuths 20, 65,
  // .. 335 deg): PSNR of the nearest camera alone 13.6-14.7 dB, mean 16.2-17.8 (+1.9 to +4.0 dB),
  // median 16.4-18.9; pixels more than 0.1 off: 20-24 % (one camera), 37-41 % (mean: the bars
  // fade but spread over the other cameras' views), 13-25 % (median: 0.33-0.65 of the mean's). The
  // dome sees the card with 2.8 cameras on average: where only two see it, the median is their
  // mean, so the median hides no more of the grid than one camera does.
  const Rig rig = design::thesis_prototype_rig();
  const PanoGrid grid{Projection::kVr180, 540, 540};
  for (double az : {100.0, 155.0, 290.0}) {
    CardScene clear;
    const Vec3 dc = direction_from_spherical(deg2rad(40), deg2rad(az));
    clear.cards.push_back({dc, 40, 30, false});
    CardScene occluded = clear;
    occluded.has_grid = true;
    occluded.grid_card = {dc, 15, 30, false};
    occluded.bar_mm = 0.15;
    occluded.pitch_mm = 2.0;
    const auto fc = render_frames(rig, clear), fo = render_frames(rig, occluded);
    const cv::Rect roi = roi_at(grid, dc, 40);
    auto run = [&](RefocusCombine comb, double aperture, double* bad) {
      RefocusOptions o;
      o.grid = grid;
      o.focus_mm = 40;
      o.combine = comb;
      o.aperture_mm = aperture;
      o.progress = false;
      const auto rc = refocus(rig, fc, o), ro = refocus(rig, fo, o);
      cv::Mat d, g;
      cv::absdiff(ro.image(roi), rc.image(roi), d);
      cv::cvtColor(d, g, cv::COLOR_BGR2GRAY);
      *bad = cv::countNonZero(g > 0.1) / double(g.total());
      return psnr_db(ro.image(roi), rc.image(roi));
    };
    const double inf = std::numeric_limits<double>::infinity();
    double bad_pin, bad_mean, bad_med;
    const double pin = run(RefocusCombine::kMean, 0, &bad_pin);
    const double mean = run(RefocusCombine::kMean, inf, &bad_mean);
    const double med = run(RefocusCombine::kMedian, inf, &bad_med);
    std::printf("az %.0f: PSNR one camera %.2f, mean %.2f, median %.2f dB; bad %.3f %.3f %.3f\n", az, pin,
                mean, med, bad_pin, bad_mean, bad_med);
    EXPECT_GT(mean, pin + 1.5) << az;
    EXPECT_GT(med, pin + 1.5) << az;
    EXPECT_LT(bad_med, 1.15 * bad_pin) << az;
    EXPECT_LT(bad_med, 0.8 * bad_mean) << az;
  }
}

}  // namespace
}  // namespace omma::pano

namespace omma::pano {
namespace {

TEST(Refocus, ColonSharpestWhereInFocus) {
  // The dome in the simulated colon (seed 1: the demo's scene), vr180 540 x 540, one ray per pixel.
  const Rig rig = design::thesis_prototype_rig();
  sim::SimulateOptions so;
  so.effects.supersample = 1;
  so.truth_grid = PanoGrid{Projection::kVr180, 540, 540};
  so.truth_supersample = 1;
  so.progress = false;
  const auto sim = sim::simulate(rig, *sim::make_colon_scene(), so);
  std::vector<cv::Mat> frames;
  for (const auto& f : sim.frames) frames.push_back(f.image);
  // Measured: gradient energy against the truth where the aperture holds >= 2 cameras, by defocus
  // |1/Z - 1/F| bins [0, 0.005), [0.005, 0.015), [0.015, 0.03), >= 0.03 (1/mm):
  //   F = 20 mm: 0.485, 0.317, 0.293, 0.340;  F = 30: 0.536, 0.271, 0.373, (37 px);
  //   F = 60: 0.497, 0.209, 0.178, 0.139     (F = 15: the wall is never that near).
  // In focus 1.4-2.8 times the energy of the bins off it.
  const std::vector<double> edges{0, 0.005, 0.015, 0.03};
  for (double focus : {20.0, 30.0, 60.0}) {
    RefocusOptions o;
    o.grid = so.truth_grid;
    o.focus_mm = focus;
    o.progress = false;
    const auto r = refocus(rig, frames, o);
    const auto bins = sharpness_by_defocus(r.image, sim.truth, sim.truth_depth, focus, edges, r.cameras >= 2);
    std::printf("F %.0f:", focus);
    for (const auto& b : bins)
      std::printf("  [%.3f..%.3f) %ld px %.3f", b.from, b.to, b.pixels, b.energy_ratio);
    std::printf("\n");
    ASSERT_GT(bins[0].pixels, 2000) << focus;
    for (size_t b = 1; b < bins.size(); ++b) {
      if (bins[b].pixels >= 2000) {
        EXPECT_GT(bins[0].energy_ratio, 1.25 * bins[b].energy_ratio) << focus << " bin " << b;
      }
    }
  }
}

}  // namespace
}  // namespace omma::pano
