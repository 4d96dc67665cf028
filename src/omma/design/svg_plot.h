// A small SVG writer for line plots (sweeps of Fig. 3.3, 3.7, 3.9): axes with ticks, labels,
// title and legend. Produces self-contained SVG 1.1 text.
#pragma once

#include <string>
#include <vector>

namespace omma::design {

struct PlotSeries {
  std::string name;          // legend text
  std::string color;         // any SVG colour, e.g. "#d62728"
  std::vector<double> x, y;  // same length; non-finite y values break the line
  bool step = false;         // draw as a staircase (a count that holds until the next x)
};

struct Plot {
  std::string title, x_label, y_label;
  std::vector<PlotSeries> series;
};

// One plot of width x height pixels.
std::string svg_plot(const Plot& plot, int width = 640, int height = 420);
// Several plots in a grid with `columns` columns and an overall title.
std::string svg_plot_grid(const std::vector<Plot>& plots, int columns, const std::string& title,
                          int cell_width = 520, int cell_height = 360);

// "Nice" tick values covering [lo, hi] (about `count` of them).
std::vector<double> nice_ticks(double lo, double hi, int count = 6);

}  // namespace omma::design
