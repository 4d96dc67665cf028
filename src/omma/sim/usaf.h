// Geometry of the simulated USAF 1951 resolution chart (thesis §5.5.2, Fig. 5.23).
//
// Element (group G, element E) has 2^(G + (E - 1) / 6) line pairs per mm; a bar is half a line pair
// wide and five bar widths long; each element is a set of three vertical bars (long along chart y,
// resolving detail along x) beside a set of three horizontal bars (long along x), bars separated by
// one bar width. Groups -1 .. 3 are laid out in columns, coarsest at the left, element 1 at the top
// of each column, on a white card centred on the chart origin.
//
// Chart coordinates (mm): the chart plane is z = distance in the dome frame; chart x = dome x,
// chart y = dome y (so in a vr180 panorama chart x points right and chart y up).
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "omma/core/geometry.h"
#include "omma/core/grid.h"

namespace omma::sim {

struct UsafElement {
  int group = 0;
  int element = 1;          // 1..6
  double lp_per_mm = 1;     // line pairs per mm, 2^(group + (element - 1) / 6)
  double bar_mm = 0.5;      // bar width (= gap width) = 1 / (2 lp_per_mm); bar length = 5 bar_mm
  Vec2 vertical_bars_mm;    // centre of the 3 vertical bars (a 5 x 5 bar_mm square)
  Vec2 horizontal_bars_mm;  // centre of the 3 horizontal bars (a 5 x 5 bar_mm square)
};

// Line pairs per mm of USAF 1951 group/element.
double usaf_lp_per_mm(int group, int element);

// All elements of the chart, group -1 element 1 first, group 3 element 6 last.
const std::vector<UsafElement>& usaf_chart();

// Reflectance classes of a chart point.
enum class UsafPaint { kOutside, kWhite, kBlack };
UsafPaint usaf_paint(const Vec2& xy_mm);

// Extent of the white card: |x| <= half_width, |y| <= half_height (mm).
Vec2 usaf_card_half_size_mm();

// Reading the chart in a panorama (thesis §5.5.2): for each element and bar direction, the image is
// sampled (bilinear, luma of the stored values) along lines across the three bars, averaged over
// the middle 60 % of the bar length; Ibar = the largest of the three bar-centre levels, Igap = the
// smaller of the two gap-centre levels (each over the central half of its bar/gap). The element is
// resolved in that direction if the modulation (Igap - Ibar) / (Igap + Ibar) >= min_contrast.
struct UsafReading {
  UsafElement element;
  double contrast_x = 0;      // vertical bars, detail along chart x
  double contrast_y = 0;      // horizontal bars, detail along chart y
  double bar_deg = 0;         // angle of one bar seen from the viewpoint, degrees
  double bar_deg_centre = 0;  // atan(bar / distance): the thesis's figure (seen from the dome centre)
  int camera = -1;            // index into `cameras` of the viewpoint used, -1: the dome centre
  bool resolved = false;      // both directions reach min_contrast
};
// Reading the limit: `limit` is the finest element resolved together with the next coarser one
// (two in a row: an isolated pass is aliasing, an isolated failure of a large element is a seam
// cutting through it); `strict_limit` is the last element of the unbroken run of resolved elements
// from the coarsest one.
struct UsafMeasurement {
  std::vector<UsafReading> readings;  // every element, coarsest first
  int limit_index = -1;               // -1: none
  int strict_limit_index = -1;        // -1: the coarsest element is not resolved
  double min_contrast = 0.1;
  const UsafReading* limit() const { return limit_index >= 0 ? &readings[limit_index] : nullptr; }
  const UsafReading* strict_limit() const {
    return strict_limit_index >= 0 ? &readings[strict_limit_index] : nullptr;
  }
};

// Where a chart point appears in the panorama. A stitched panorama is built for far objects: a
// near chart point X seen by camera c (centre p_c) lands at direction X - p_c, not X (parallax: the
// chart is only 25 mm away, the cameras 5 mm off centre). With `cameras` given, each element is
// located as camera c puts it, c being the camera whose optical axis is nearest to X - p_c among
// those that are also the nearest-axis camera of that direction (the nn rule, eq. 2.6-2.7); with no
// cameras (a ground truth), as seen from the dome centre. Blending methods that mix cameras show
// ghosts there, which lowers the contrast: that is part of what the measurement measures.
struct UsafViewpoint {
  Vec3 position_mm = Vec3::Zero();
  Vec3 axis = Vec3::UnitZ();
};
// `pano`: 8U/16U/32F, 1 or 3 channels, on `grid`; the chart is the plane z = distance_mm of the
// dome frame. Throws std::invalid_argument if the chart is not inside the grid.
UsafMeasurement measure_usaf(const cv::Mat& pano, const PanoGrid& grid, double distance_mm = 25.0,
                             double min_contrast = 0.1, const std::vector<UsafViewpoint>& cameras = {});

}  // namespace omma::sim
