#include "omma/design/svg_plot.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

namespace omma::design {
namespace {

std::string escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string tick_label(double v, double step) {
  const int decimals = step >= 1 ? 0 : std::min(6, static_cast<int>(std::ceil(-std::log10(step))));
  return fmt::format("{:.{}f}", v, decimals);
}

// Draws one plot into the box (x0, y0, w, h).
std::string plot_body(const Plot& p, double x0, double y0, double w, double h) {
  double xmin = std::numeric_limits<double>::infinity(), xmax = -xmin, ymin = xmin, ymax = -xmin;
  for (const auto& s : p.series)
    for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      xmin = std::min(xmin, s.x[i]);
      xmax = std::max(xmax, s.x[i]);
      ymin = std::min(ymin, s.y[i]);
      ymax = std::max(ymax, s.y[i]);
    }
  if (!std::isfinite(xmin)) xmin = 0, xmax = 1, ymin = 0, ymax = 1;
  if (xmax <= xmin) xmax = xmin + 1;
  ymin = std::min(ymin, 0.0);
  if (ymax <= ymin) ymax = ymin + 1;
  const auto xt = nice_ticks(xmin, xmax), yt = nice_ticks(ymin, ymax);
  xmin = std::min(xmin, xt.front());
  xmax = std::max(xmax, xt.back());
  ymin = std::min(ymin, yt.front());
  ymax = std::max(ymax, yt.back());
  const double ml = 62, mr = 16, mt = 34, mb = 48;  // margins
  const double pw = w - ml - mr, ph = h - mt - mb, px = x0 + ml, py = y0 + mt;
  auto X = [&](double v) { return px + (v - xmin) / (xmax - xmin) * pw; };
  auto Y = [&](double v) { return py + ph - (v - ymin) / (ymax - ymin) * ph; };
  std::string o;
  o += fmt::format(
      "<g>\n<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" "
      "fill=\"white\" stroke=\"#333\"/>\n",
      px, py, pw, ph);
  const double xstep = xt.size() > 1 ? xt[1] - xt[0] : 1, ystep = yt.size() > 1 ? yt[1] - yt[0] : 1;
  for (double v : xt) {
    o += fmt::format(
        "<line x1=\"{0:.1f}\" y1=\"{1:.1f}\" x2=\"{0:.1f}\" y2=\"{2:.1f}\" "
        "stroke=\"#ddd\"/>\n",
        X(v), py, py + ph);
    o += fmt::format(
        "<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"11\" text-anchor=\"middle\">{}"
        "</text>\n",
        X(v), py + ph + 15, tick_label(v, xstep));
  }
  for (double v : yt) {
    o += fmt::format(
        "<line x1=\"{0:.1f}\" y1=\"{1:.1f}\" x2=\"{2:.1f}\" y2=\"{1:.1f}\" "
        "stroke=\"#ddd\"/>\n",
        px, Y(v), px + pw);
    o += fmt::format(
        "<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"11\" text-anchor=\"end\">{}"
        "</text>\n",
        px - 5, Y(v) + 4, tick_label(v, ystep));
  }
  o += fmt::format(
      "<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"14\" font-weight=\"bold\" "
      "text-anchor=\"middle\">{}</text>\n",
      px + pw / 2, y0 + 20, escape(p.title));
  o += fmt::format(
      "<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"12\" text-anchor=\"middle\">{}"
      "</text>\n",
      px + pw / 2, y0 + h - 10, escape(p.x_label));
  o += fmt::format(
      "<text x=\"{0:.1f}\" y=\"{1:.1f}\" font-size=\"12\" text-anchor=\"middle\" "
      "transform=\"rotate(-90 {0:.1f} {1:.1f})\">{2}</text>\n",
      x0 + 16, py + ph / 2, escape(p.y_label));
  // Series.
  for (const auto& s : p.series) {
    std::string path;
    bool pen = false;
    double last_y = 0;
    for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) {
        pen = false;
        continue;
      }
      if (pen && s.step) path += fmt::format(" L{:.1f},{:.1f}", X(s.x[i]), Y(last_y));
      path += fmt::format("{}{:.1f},{:.1f}", pen ? " L" : " M", X(s.x[i]), Y(s.y[i]));
      pen = true;
      last_y = s.y[i];
    }
    if (!path.empty())
      o += fmt::format("<path d=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"2\"/>\n", path, s.color);
    for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i)
      if (std::isfinite(s.x[i]) && std::isfinite(s.y[i]))
        o += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"2.2\" fill=\"{}\"/>\n", X(s.x[i]),
                         Y(s.y[i]), s.color);
  }
  // Legend (top right inside the plot area).
  const double lw = 150, lh = 8 + 18.0 * p.series.size();
  const double lx = px + pw - lw - 8, ly = py + 8;
  o += fmt::format(
      "<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" "
      "fill=\"white\" fill-opacity=\"0.85\" stroke=\"#999\"/>\n",
      lx, ly, lw, lh);
  for (size_t i = 0; i < p.series.size(); ++i) {
    const double yy = ly + 16 + 18.0 * i;
    o += fmt::format(
        "<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"{}\" "
        "stroke-width=\"3\"/>\n",
        lx + 8, yy - 4, lx + 32, yy - 4, p.series[i].color);
    o += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"12\">{}</text>\n", lx + 38, yy,
                     escape(p.series[i].name));
  }
  o += "</g>\n";
  return o;
}

std::string header(int w, int h) {
  return fmt::format(
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/"
      "2000/svg\" version=\"1.1\" width=\"{0}\" height=\"{1}\" viewBox=\"0 0 {0} {1}\" "
      "font-family=\"sans-serif\">\n<rect width=\"100%\" height=\"100%\" "
      "fill=\"#f7f7f7\"/>\n",
      w, h);
}

}  // namespace

std::vector<double> nice_ticks(double lo, double hi, int count) {
  if (!(hi > lo)) hi = lo + 1;
  const double raw = (hi - lo) / std::max(count - 1, 1);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
    if (m * mag >= raw) {
      step = m * mag;
      break;
    }
  std::vector<double> t;
  for (double v = std::floor(lo / step) * step; v <= hi + 1e-9 * step; v += step) t.push_back(v);
  if (t.back() < hi - 1e-9 * step) t.push_back(t.back() + step);
  return t;
}

std::string svg_plot(const Plot& plot, int width, int height) {
  return header(width, height) + plot_body(plot, 0, 0, width, height) + "</svg>\n";
}

std::string svg_plot_grid(const std::vector<Plot>& plots, int columns, const std::string& title,
                          int cell_width, int cell_height) {
  columns = std::max(1, columns);
  const int rows = (static_cast<int>(plots.size()) + columns - 1) / columns;
  const int top = 36;
  std::string o = header(columns * cell_width, rows * cell_height + top);
  o += fmt::format(
      "<text x=\"{}\" y=\"24\" font-size=\"17\" font-weight=\"bold\" "
      "text-anchor=\"middle\">{}</text>\n",
      columns * cell_width / 2, escape(title));
  for (size_t i = 0; i < plots.size(); ++i)
    o += plot_body(plots[i], static_cast<double>(i % columns) * cell_width,
                   top + static_cast<double>(i / columns) * cell_height, cell_width, cell_height);
  return o + "</svg>\n";
}

}  // namespace omma::design
