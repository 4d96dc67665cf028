#include "omma/sim/usaf.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

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
    for (int e = 1; e <= 6; ++e)
      h += (e > 1 ? 2 : 0) * (0.5 / usaf_lp_per_mm(g, e)) + 5 * (0.5 / usaf_lp_per_mm(g, e));
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

namespace {

// Bilinear luma (BT.601 on BGR) of `img` (CV_32F, 1 or 3 channels) at continuous pixel (x, y).
double luma_at(const cv::Mat& img, const PanoGrid& grid, double x, double y) {
  const bool wrap = grid.projection != Projection::kVr180;
  const double sx = x - 0.5, sy = std::clamp(y - 0.5, 0.0, img.rows - 1.0);
  const int x0f = static_cast<int>(std::floor(sx)), y0 = static_cast<int>(std::floor(sy));
  const double ax = sx - x0f, ay = sy - y0;
  auto col = [&](int c) {
    return wrap ? ((c % img.cols) + img.cols) % img.cols : std::clamp(c, 0, img.cols - 1);
  };
  const int xa = col(x0f), xb = col(x0f + 1), y1 = std::min(y0 + 1, img.rows - 1);
  auto px = [&](int r, int c) {
    if (img.channels() == 1) return static_cast<double>(img.at<float>(r, c));
    const cv::Vec3f v = img.at<cv::Vec3f>(r, c);
    return 0.114 * v[0] + 0.587 * v[1] + 0.299 * v[2];
  };
  return (px(y0, xa) * (1 - ax) + px(y0, xb) * ax) * (1 - ay) +
         (px(y1, xa) * (1 - ax) + px(y1, xb) * ax) * ay;
}

}  // namespace

// The viewpoint an element is seen from in the panorama (see usaf.h).
int choose_viewpoint(const Vec3& X, const std::vector<UsafViewpoint>& cams) {
  int best = -1, best_any = -1;
  double best_dot = -2, best_any_dot = -2;
  for (size_t c = 0; c < cams.size(); ++c) {
    const Vec3 w = (X - cams[c].position_mm).normalized();
    const double dc = w.dot(cams[c].axis);
    if (dc > best_any_dot) best_any_dot = dc, best_any = static_cast<int>(c);
    bool nearest = true;
    for (size_t k = 0; k < cams.size() && nearest; ++k) nearest = w.dot(cams[k].axis) <= dc + 1e-12;
    if (nearest && dc > best_dot) best_dot = dc, best = static_cast<int>(c);
  }
  return best >= 0 ? best : best_any;
}

UsafMeasurement measure_usaf(const cv::Mat& pano, const PanoGrid& grid, double distance, double min_contrast,
                             const std::vector<UsafViewpoint>& cameras) {
  if (pano.empty() || pano.cols != grid.width || pano.rows != grid.height)
    throw std::invalid_argument(fmt::format("panorama is {}x{} but the grid is {}x{}", pano.cols, pano.rows,
                                            grid.width, grid.height));
  if (!(distance > 0)) throw std::invalid_argument("the chart distance must be positive");
  Vec3 observer = Vec3::Zero();
  cv::Mat img;
  const double scale = pano.depth() == CV_8U ? 1.0 / 255 : pano.depth() == CV_16U ? 1.0 / 65535 : 1.0;
  pano.convertTo(img, CV_MAKETYPE(CV_32F, pano.channels()), scale);
  if (img.channels() == 4) cv::extractChannel(img, img, 0);
  auto sample = [&](const Vec2& p) {
    const auto px = grid.pixel(Vec3(p.x(), p.y(), distance) - observer);
    if (!px) throw std::invalid_argument("the USAF chart is not inside the panorama grid");
    return luma_at(img, grid, px->x(), px->y());
  };
  UsafMeasurement m;
  m.min_contrast = min_contrast;
  // Level at offset `k` bar widths across the bars (k = -2, 0, 2: bars; -1, 1: gaps), averaged over
  // the central half of that bar or gap and over the middle 60 % of the bar length.
  auto level = [&](const Vec2& c, double b, bool across_x, double k) {
    double sum = 0;
    int n = 0;
    for (int i = -2; i <= 2; ++i)
      for (int j = -3; j <= 3; ++j) {
        const double a = (k + 0.25 * i / 2) * b;  // across: within +-0.25 b of the centre
        const double l = 1.5 * b * j / 3;         // along: within +-1.5 b (60 % of 5 b)
        sum += sample(across_x ? c + Vec2(a, l) : c + Vec2(l, a));
        ++n;
      }
    return sum / n;
  };
  auto contrast = [&](const Vec2& c, double b, bool across_x) {
    const double bar =
        std::max({level(c, b, across_x, -2), level(c, b, across_x, 0), level(c, b, across_x, 2)});
    const double gap = std::min(level(c, b, across_x, -1), level(c, b, across_x, 1));
    return (gap - bar) / std::max(gap + bar, 1e-9);
  };
  bool all = true;
  for (const auto& e : usaf_chart()) {
    UsafReading r;
    r.element = e;
    // Each bar set is located from its own viewpoint (the two sets may come from different cameras).
    auto view = [&](const Vec2& centre) {
      const Vec3 X(centre.x(), centre.y(), distance);
      const int cam = cameras.empty() ? -1 : choose_viewpoint(X, cameras);
      observer = cam >= 0 ? cameras[cam].position_mm : Vec3::Zero();
      return cam;
    };
    r.camera = view(e.vertical_bars_mm);
    r.contrast_x = contrast(e.vertical_bars_mm, e.bar_mm, true);
    const Vec3 c = Vec3(e.vertical_bars_mm.x(), e.vertical_bars_mm.y(), distance) - observer;
    r.bar_deg = rad2deg(std::atan2(e.bar_mm * c.z() / c.norm(), c.norm()));
    r.bar_deg_centre = rad2deg(std::atan(e.bar_mm / distance));
    view(e.horizontal_bars_mm);
    r.contrast_y = contrast(e.horizontal_bars_mm, e.bar_mm, false);
    r.resolved = r.contrast_x >= min_contrast && r.contrast_y >= min_contrast;
    all = all && r.resolved;
    const int i = static_cast<int>(m.readings.size());
    if (all) m.strict_limit_index = i;
    if (r.resolved && i > 0 && m.readings.back().resolved) m.limit_index = i;
    m.readings.push_back(r);
  }
  return m;
}

}  // namespace omma::sim
