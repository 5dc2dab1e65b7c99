#pragma once
/// \file
/// What a plot shows, as plain data: a Figure holds panels (Axes) in a grid; each panel holds
/// line/point series, horizontal marker lines, or grouped bars, plus its labels. render.hpp draws
/// it. Nothing here knows about trajectories or metrics.

#include <optional>
#include <string>
#include <vector>

#include "cairn/viz/color.hpp"

namespace cairn::viz {

enum class SeriesStyle {
  kLine,
  kPoints,
};

/// A polyline or a set of points in data units.
struct Series {
  /// Legend entry; empty keeps the series out of the legend.
  std::string label;
  std::vector<double> x;
  std::vector<double> y;
  SeriesStyle style = SeriesStyle::kLine;
  Rgb color = categorical(0);
  /// Stroke width (lines) or point diameter, pixels at the figure's size.
  double width_px = 1.5;
  bool dashed = false;
  /// Optional, one per point: draws each point / each segment in the panel's colour map at this
  /// value (a segment takes the mean of its two ends) instead of `color`.
  std::vector<double> values;
};

/// A horizontal line across the panel at y = value (e.g. the RMSE of an error plot).
struct HorizontalLine {
  std::string label;
  double value = 0;
  Rgb color = kBlack;
  bool dashed = true;
};

/// Bars: one group per category, one bar per BarSet within a group.
struct BarSet {
  std::string label;
  /// One per category; NaN leaves the bar out.
  std::vector<double> values;
  Rgb color = categorical(0);
};

/// A colour map shown as a bar at the right of the panel; used by series with `values`.
struct ColorBar {
  /// With unit, e.g. "APE [m]".
  std::string label;
  double min = 0;
  double max = 1;
};

enum class LegendPlace {
  /// The corner whose legend box would cover the fewest data points (matplotlib's "best").
  kBest,
  kTopRight,
  kTopLeft,
  kBottomRight,
  kBottomLeft,
};

struct Axes {
  std::string title;
  /// With unit in brackets, e.g. "x [m]".
  std::string x_label;
  std::string y_label;
  /// Same metres per pixel on both axes (top views of trajectories and maps).
  bool equal_aspect = false;
  /// Start the y axis at 0 (errors, bars).
  bool y_from_zero = false;
  std::vector<Series> series;
  std::vector<HorizontalLine> horizontal_lines;
  /// Bar chart: category names on the x axis (then `bars` is drawn and `series` ignored).
  std::vector<std::string> categories;
  std::vector<BarSet> bars;
  /// Print each bar's value above it with this many decimals; negative: no labels.
  int bar_value_decimals = -1;
  std::optional<ColorBar> color_bar;
  bool legend = true;
  LegendPlace legend_place = LegendPlace::kBest;
};

struct Figure {
  /// Over all panels; empty for none.
  std::string title;
  /// Image size in pixels (PNG) or points (SVG).
  int width_px = 1000;
  int height_px = 750;
  /// Panels, row by row, `columns` per row.
  std::vector<Axes> panels;
  int columns = 1;
};

}  // namespace cairn::viz
