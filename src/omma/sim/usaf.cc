#include "omma/sim/usaf.h"

#include <cmath>

namespace omma::sim {

double usaf_lp_per_mm(int group, int element) { return std::pow(2.0, group + (element - 1) / 6.0); }

namespace {

constexpr int kFirstGroup = -1;
constexpr int kLastGroup = 3;
constexpr double kMarginMm = 2.0;

struct Layout {
  std::vector<UsafElement> elements;
  Vec2 half_size;
};

// Columns: group g occupies a column 12 bar widths (of its element 1) wide: vertical bars (5),
// a gap (2), horizontal bars (5). Elements are stacked downwards with a gap of 2 of their bar widths.
Layout make_layout() {
  Layout L;
  std::vector<double> col_width, col_height;
  for (int g = kFirstGroup; g <= kLastGroup; ++g) {
    const double b1 = 0.5 / usaf_lp_per_mm(g, 1);
    col_width.push_back(12 * b1);
    double h = 0;
    for (int e = 1; e <= 6; ++e) h += (e > 1 ? 2 : 0) * (0.5 / usaf_lp_per_mm(g, e)) + 5 * (0.5 / usaf_lp_per_mm(g, e));
    col_height.push_back(h);
  }
  const double gap = 2.0;  // mm between columns
  double total_w = gap * (col_width.size() - 1), max_h = 0;
  for (size_t i = 0; i < col_width.size(); ++i) {
    total_w += col_width[i];
    max_h = std::max(max_h, col_height[i]);
  }
  double x = -total_w / 2;
  for (int g = kFirstGroup; g <= kLastGroup; ++g) {
    const size_t i = g - kFirstGroup;
    const double b1 = 0.5 / usaf_lp_per_mm(g, 1);
    double y = col_height[i] / 2;  // top of the column (chart y up), columns centred vertically
    for (int e = 1; e <= 6; ++e) {
      UsafElement el;
      el.group = g;
      el.element = e;
      el.lp_per_mm = usaf_lp_per_mm(g, e);
      el.bar_mm = 0.5 / el.lp_per_mm;
      const double b = el.bar_mm;
      const double cy = y - 2.5 * b;
      el.vertical_bars_mm = Vec2(x + 2.5 * b, cy);
      el.horizontal_bars_mm = Vec2(x + 5 * b1 + 2 * b1 + 2.5 * b, cy);
      L.elements.push_back(el);
      y -= 5 * b + 2 * b;
    }
    x += col_width[i] + gap;
  }
  L.half_size = Vec2(total_w / 2 + kMarginMm, max_h / 2 + kMarginMm);
  return L;
}

const Layout& layout() {
  static const Layout L = make_layout();
  return L;
}

// Is p on one of the three bars of a 5x5 bar square centred at c? `vertical`: bars long along y.
bool on_bars(const Vec2& p, const Vec2& c, double b, bool vertical) {
  const double dx = p.x() - c.x(), dy = p.y() - c.y();
  if (std::abs(dx) > 2.5 * b || std::abs(dy) > 2.5 * b) return false;
  const double across = vertical ? dx : dy;  // coordinate across the bars
  const double k = (across + 2.5 * b) / b;   // 0..5: bar, gap, bar, gap, bar
  const int cell = std::min(4, static_cast<int>(std::floor(k)));
  return cell % 2 == 0;
}

}  // namespace

const std::vector<UsafElement>& usaf_chart() { return layout().elements; }

Vec2 usaf_card_half_size_mm() { return layout().half_size; }

UsafPaint usaf_paint(const Vec2& p) {
  const Layout& L = layout();
  if (std::abs(p.x()) > L.half_size.x() || std::abs(p.y()) > L.half_size.y()) return UsafPaint::kOutside;
  for (const auto& e : L.elements) {
    if (on_bars(p, e.vertical_bars_mm, e.bar_mm, true) || on_bars(p, e.horizontal_bars_mm, e.bar_mm, false))
      return UsafPaint::kBlack;
  }
  return UsafPaint::kWhite;
}

}  // namespace omma::sim
