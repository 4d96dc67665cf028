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

#include "omma/core/geometry.h"

namespace omma::sim {

struct UsafElement {
  int group = 0;
  int element = 1;             // 1..6
  double lp_per_mm = 1;        // line pairs per mm, 2^(group + (element - 1) / 6)
  double bar_mm = 0.5;         // bar width (= gap width) = 1 / (2 lp_per_mm); bar length = 5 bar_mm
  Vec2 vertical_bars_mm;       // centre of the 3 vertical bars (a 5 x 5 bar_mm square)
  Vec2 horizontal_bars_mm;     // centre of the 3 horizontal bars (a 5 x 5 bar_mm square)
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

}  // namespace omma::sim
