#include "cairn/viz/render.hpp"

#include "cairn/core/utf8.hpp"
#include "cairn/viz/cairo_image.hpp"

#include <cairo-svg.h>
#include <cairo.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "cairn/viz/ticks.hpp"

namespace cairn::viz {
namespace {

using Surface = CairoSurface;
using Context = CairoContext;

cairo_status_t append_to_string(void* closure, const unsigned char* data, unsigned int length) {
  static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
  return CAIRO_STATUS_SUCCESS;
}

constexpr const char* kFont = "DejaVu Sans";
constexpr double kTickFont = 12;
constexpr double kLabelFont = 14;
constexpr double kTitleFont = 15;
constexpr double kFigureTitleFont = 17;
constexpr int kColorLevels = 64;

struct Rect {
  double x = 0;
  double y = 0;
  double w = 0;
  double h = 0;
};

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void add(double v) {
    if (!std::isfinite(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  bool valid() const { return lo <= hi; }
  double span() const { return hi - lo; }
};

void set_color(cairo_t* cr, const Rgb& c, double alpha = 1.0) { cairo_set_source_rgba(cr, c.r, c.g, c.b, alpha); }

void set_font(cairo_t* cr, double size, bool bold = false) {
  cairo_select_font_face(cr, kFont, CAIRO_FONT_SLANT_NORMAL, bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size);
}

double text_width(cairo_t* cr, const std::string& text) {
  cairo_text_extents_t e;
  cairo_text_extents(cr, text.c_str(), &e);
  return e.x_advance;
}

/// Draws `text` with its anchor at (x, y): ax, ay in {0, 0.5, 1} = left/centre/right,
/// top/middle/baseline-ish bottom.
void draw_text(cairo_t* cr, const std::string& raw_text, double x, double y, double ax, double ay) {
  const std::string text = core::valid_utf8(raw_text);  // titles hold file names, which are bytes
  cairo_text_extents_t e;
  cairo_text_extents(cr, text.c_str(), &e);
  cairo_font_extents_t f;
  cairo_font_extents(cr, &f);
  const double height = f.ascent * 0.8;  // cap height, near enough for labels
  cairo_move_to(cr, x - ax * e.x_advance, y + (1.0 - ay) * height);
  cairo_show_text(cr, text.c_str());
}

void set_dash(cairo_t* cr, bool dashed, double width) {
  if (dashed) {
    const double dashes[2] = {4.0 * std::max(width, 1.0), 3.0 * std::max(width, 1.0)};
    cairo_set_dash(cr, dashes, 2, 0);
  } else {
    cairo_set_dash(cr, nullptr, 0, 0);
  }
}

/// Data-to-pixel mapping of one panel.
struct Mapping {
  Rect plot;
  Range x;
  Range y;
  double px(double v) const { return plot.x + (v - x.lo) / x.span() * plot.w; }
  double py(double v) const { return plot.y + plot.h - (v - y.lo) / y.span() * plot.h; }
};

void pad(Range& r, double fraction, bool keep_zero_floor) {
  if (!r.valid()) {
    r.lo = 0;
    r.hi = 1;
    return;
  }
  if (r.span() <= 0) {
    const double half = r.lo == 0 ? 1.0 : 0.5 * std::abs(r.lo);
    if (keep_zero_floor && r.lo >= 0) {
      r.hi = r.lo + 2 * half;
      r.lo = std::min(r.lo, 0.0);
    } else {
      r.lo -= half;
      r.hi += half;
    }
    return;
  }
  const double d = fraction * r.span();
  if (!(keep_zero_floor && r.lo == 0)) r.lo -= d;
  r.hi += d;
}

Rgb map_color(const ColorBar& bar, double value) {
  const double span = bar.max - bar.min;
  double t = span > 0 ? (value - bar.min) / span : 0.5;
  t = std::clamp(t, 0.0, 1.0);
  t = std::round(t * (kColorLevels - 1)) / (kColorLevels - 1);  // fewer path pieces in SVG
  return viridis(t);
}

bool finite_point(const Series& s, std::size_t i) { return std::isfinite(s.x[i]) && std::isfinite(s.y[i]); }

void draw_series(cairo_t* cr, const Mapping& m, const Series& s, const std::optional<ColorBar>& bar) {
  const std::size_t n = std::min(s.x.size(), s.y.size());
  const bool mapped = bar.has_value() && s.values.size() == n;
  cairo_set_line_width(cr, s.width_px);
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
  set_dash(cr, s.dashed, s.width_px);
  if (s.style == SeriesStyle::kPoints) {
    for (std::size_t i = 0; i < n; ++i) {
      if (!finite_point(s, i)) continue;
      set_color(cr, mapped ? map_color(*bar, s.values[i]) : s.color);
      cairo_arc(cr, m.px(s.x[i]), m.py(s.y[i]), 0.5 * s.width_px, 0, 2 * std::numbers::pi);
      cairo_fill(cr);
    }
    return;
  }
  if (!mapped) {
    set_color(cr, s.color);
    bool pen_down = false;
    for (std::size_t i = 0; i < n; ++i) {
      if (!finite_point(s, i)) {
        pen_down = false;
        continue;
      }
      if (pen_down) {
        cairo_line_to(cr, m.px(s.x[i]), m.py(s.y[i]));
      } else {
        cairo_move_to(cr, m.px(s.x[i]), m.py(s.y[i]));
        pen_down = true;
      }
    }
    cairo_stroke(cr);
    return;
  }
  // Colour-mapped polyline: runs of segments with the same quantised colour become one path.
  std::size_t i = 0;
  while (i + 1 < n) {
    if (!finite_point(s, i) || !finite_point(s, i + 1)) {
      ++i;
      continue;
    }
    const Rgb c = map_color(*bar, 0.5 * (s.values[i] + s.values[i + 1]));
    cairo_move_to(cr, m.px(s.x[i]), m.py(s.y[i]));
    std::size_t j = i + 1;
    cairo_line_to(cr, m.px(s.x[j]), m.py(s.y[j]));
    while (j + 1 < n && finite_point(s, j + 1)) {
      const Rgb next = map_color(*bar, 0.5 * (s.values[j] + s.values[j + 1]));
      if (next.r != c.r || next.g != c.g || next.b != c.b) break;
      ++j;
      cairo_line_to(cr, m.px(s.x[j]), m.py(s.y[j]));
    }
    set_color(cr, c);
    cairo_stroke(cr);
    i = j;
  }
}

struct LegendEntry {
  std::string label;
  Rgb color;
  bool dashed = false;
  bool mapped = false;
  bool box = false;  // bar sets
  bool point = false;
  double width = 1.5;
};

/// The legend box at `place` (not kBest) for a legend of size w x h.
Rect legend_box(const Rect& plot, double w, double h, LegendPlace place) {
  const bool right = place == LegendPlace::kTopRight || place == LegendPlace::kBottomRight;
  const bool top = place == LegendPlace::kTopRight || place == LegendPlace::kTopLeft;
  return {right ? plot.x + plot.w - w - 8 : plot.x + 8, top ? plot.y + 8 : plot.y + plot.h - h - 8, w, h};
}

/// kBest: the corner covering the fewest of `points` (pixels); top right wins ties.
LegendPlace best_place(const Rect& plot, double w, double h, const std::vector<std::pair<double, double>>& points) {
  LegendPlace best = LegendPlace::kTopRight;
  std::size_t fewest = std::numeric_limits<std::size_t>::max();
  for (LegendPlace place :
       {LegendPlace::kTopRight, LegendPlace::kTopLeft, LegendPlace::kBottomRight, LegendPlace::kBottomLeft}) {
    const Rect box = legend_box(plot, w, h, place);
    std::size_t covered = 0;
    for (const auto& [x, y] : points) {
      if (x >= box.x && x <= box.x + box.w && y >= box.y && y <= box.y + box.h) ++covered;
    }
    if (covered < fewest) {
      fewest = covered;
      best = place;
    }
  }
  return best;
}

void draw_legend(cairo_t* cr, const Rect& plot, const std::vector<LegendEntry>& entries, LegendPlace place,
                 const std::vector<std::pair<double, double>>& points) {
  if (entries.empty()) return;
  set_font(cr, kTickFont);
  double text_w = 0;
  for (const auto& e : entries) text_w = std::max(text_w, text_width(cr, e.label));
  const double row = 18;
  const double sample = 26;
  const double w = 8 + sample + 6 + text_w + 8;
  const double h = 6 + row * static_cast<double>(entries.size()) + 2;
  if (place == LegendPlace::kBest) place = best_place(plot, w, h, points);
  const Rect box = legend_box(plot, w, h, place);
  const double x = box.x;
  const double y = box.y;
  cairo_rectangle(cr, x, y, w, h);
  cairo_set_source_rgba(cr, 1, 1, 1, 0.88);
  cairo_fill_preserve(cr);
  cairo_set_source_rgb(cr, 0.7, 0.7, 0.7);
  cairo_set_line_width(cr, 1);
  set_dash(cr, false, 1);
  cairo_stroke(cr);
  for (std::size_t k = 0; k < entries.size(); ++k) {
    const LegendEntry& e = entries[k];
    const double cy = y + 6 + row * (static_cast<double>(k) + 0.5);
    const double x0 = x + 8;
    if (e.box) {
      set_color(cr, e.color);
      cairo_rectangle(cr, x0 + 4, cy - 6, sample - 8, 12);
      cairo_fill(cr);
    } else if (e.point) {
      set_color(cr, e.color);
      cairo_arc(cr, x0 + sample / 2, cy, std::max(2.5, e.width / 2), 0, 2 * std::numbers::pi);
      cairo_fill(cr);
    } else if (e.mapped) {
      cairo_set_line_width(cr, std::max(e.width, 2.5));
      set_dash(cr, false, 1);
      for (int piece = 0; piece < 3; ++piece) {
        set_color(cr, viridis(0.15 + 0.35 * piece));
        cairo_move_to(cr, x0 + sample * piece / 3.0, cy);
        cairo_line_to(cr, x0 + sample * (piece + 1) / 3.0, cy);
        cairo_stroke(cr);
      }
    } else {
      set_color(cr, e.color);
      cairo_set_line_width(cr, std::max(e.width, 1.5));
      set_dash(cr, e.dashed, std::max(e.width, 1.5) * 0.7);
      cairo_move_to(cr, x0, cy);
      cairo_line_to(cr, x0 + sample, cy);
      cairo_stroke(cr);
    }
    set_color(cr, kBlack);
    draw_text(cr, e.label, x0 + sample + 6, cy, 0, 0.5);
  }
  set_dash(cr, false, 1);
}

void draw_color_bar(cairo_t* cr, const Rect& plot, const ColorBar& bar) {
  const double x = plot.x + plot.w + 16;
  const double w = 16;
  const Rect r{x, plot.y, w, plot.h};
  cairo_pattern_t* gradient = cairo_pattern_create_linear(0, r.y + r.h, 0, r.y);
  for (int k = 0; k <= 16; ++k) {
    const double t = k / 16.0;
    const Rgb c = viridis(t);
    cairo_pattern_add_color_stop_rgb(gradient, t, c.r, c.g, c.b);
  }
  cairo_rectangle(cr, r.x, r.y, r.w, r.h);
  cairo_set_source(cr, gradient);
  cairo_fill_preserve(cr);
  cairo_pattern_destroy(gradient);
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_set_line_width(cr, 1);
  cairo_stroke(cr);
  set_font(cr, kTickFont);
  const double span = bar.max - bar.min;
  if (span > 0) {
    const Ticks ticks = nice_ticks(bar.min, bar.max, std::max(3, static_cast<int>(plot.h / 60)));
    for (double v : ticks.values) {
      const double y = r.y + r.h - (v - bar.min) / span * r.h;
      cairo_move_to(cr, r.x + r.w, y);
      cairo_line_to(cr, r.x + r.w + 4, y);
      cairo_stroke(cr);
      draw_text(cr, format_tick(v, ticks.decimals), r.x + r.w + 7, y, 0, 0.5);
    }
  } else {
    draw_text(cr, format_tick(bar.min, 3), r.x + r.w + 7, r.y + r.h / 2, 0, 0.5);
  }
  set_font(cr, kLabelFont);
  cairo_save(cr);
  cairo_translate(cr, r.x + r.w + 62, r.y + r.h / 2);
  cairo_rotate(cr, -std::numbers::pi / 2);
  draw_text(cr, bar.label, 0, 0, 0.5, 1);
  cairo_restore(cr);
}

void draw_axes(cairo_t* cr, const Axes& axes, const Rect& cell) {
  const bool bars = !axes.categories.empty();
  const double top = 10 + (axes.title.empty() ? 0 : 26);
  const double left = 78;
  const double bottom = 58;
  const double right = 22 + (axes.color_bar ? 96 : 0);
  Mapping m;
  m.plot = {cell.x + left, cell.y + top, std::max(10.0, cell.w - left - right), std::max(10.0, cell.h - top - bottom)};

  if (bars) {
    m.x.lo = -0.5;
    m.x.hi = static_cast<double>(axes.categories.size()) - 0.5;
    m.y.add(0);
    for (const BarSet& set : axes.bars) {
      for (double v : set.values) m.y.add(v);
    }
    for (const HorizontalLine& line : axes.horizontal_lines) m.y.add(line.value);
    pad(m.y, axes.bar_value_decimals >= 0 ? 0.12 : 0.05, true);
  } else {
    for (const Series& s : axes.series) {
      for (double v : s.x) m.x.add(v);
      for (double v : s.y) m.y.add(v);
    }
    for (const HorizontalLine& line : axes.horizontal_lines) m.y.add(line.value);
    if (axes.y_from_zero) m.y.add(0);
    pad(m.x, 0.03, false);
    pad(m.y, 0.05, axes.y_from_zero);
    if (axes.equal_aspect) {
      const double sx = m.plot.w / m.x.span();
      const double sy = m.plot.h / m.y.span();
      if (sx > sy) {
        const double extra = (m.plot.w / sy - m.x.span()) / 2;
        m.x.lo -= extra;
        m.x.hi += extra;
      } else {
        const double extra = (m.plot.h / sx - m.y.span()) / 2;
        m.y.lo -= extra;
        m.y.hi += extra;
      }
    }
  }

  // Grid and ticks.
  const Ticks x_ticks = nice_ticks(m.x.lo, m.x.hi, std::max(3, static_cast<int>(m.plot.w / 90)));
  const Ticks y_ticks = nice_ticks(m.y.lo, m.y.hi, std::max(3, static_cast<int>(m.plot.h / 55)));
  cairo_set_line_width(cr, 1);
  set_dash(cr, false, 1);
  cairo_set_source_rgb(cr, 0.90, 0.90, 0.90);
  if (!bars) {
    for (double v : x_ticks.values) {
      cairo_move_to(cr, std::round(m.px(v)) + 0.5, m.plot.y);
      cairo_line_to(cr, std::round(m.px(v)) + 0.5, m.plot.y + m.plot.h);
    }
  }
  for (double v : y_ticks.values) {
    cairo_move_to(cr, m.plot.x, std::round(m.py(v)) + 0.5);
    cairo_line_to(cr, m.plot.x + m.plot.w, std::round(m.py(v)) + 0.5);
  }
  cairo_stroke(cr);

  set_font(cr, kTickFont);
  cairo_set_source_rgb(cr, 0, 0, 0);
  if (bars) {
    for (std::size_t k = 0; k < axes.categories.size(); ++k) {
      draw_text(cr, axes.categories[k], m.px(static_cast<double>(k)), m.plot.y + m.plot.h + 8, 0.5, 0);
    }
  } else {
    for (double v : x_ticks.values) {
      const double x = std::round(m.px(v)) + 0.5;
      cairo_move_to(cr, x, m.plot.y + m.plot.h);
      cairo_line_to(cr, x, m.plot.y + m.plot.h + 5);
      cairo_stroke(cr);
      draw_text(cr, format_tick(v, x_ticks.decimals), x, m.plot.y + m.plot.h + 9, 0.5, 0);
    }
  }
  for (double v : y_ticks.values) {
    const double y = std::round(m.py(v)) + 0.5;
    cairo_move_to(cr, m.plot.x - 5, y);
    cairo_line_to(cr, m.plot.x, y);
    cairo_stroke(cr);
    draw_text(cr, format_tick(v, y_ticks.decimals), m.plot.x - 8, y, 1, 0.5);
  }

  // Data, clipped to the plot area.
  cairo_save(cr);
  cairo_rectangle(cr, m.plot.x, m.plot.y, m.plot.w, m.plot.h);
  cairo_clip(cr);
  std::vector<LegendEntry> legend;
  if (bars) {
    const double group = 0.8;
    const double n = static_cast<double>(std::max<std::size_t>(axes.bars.size(), 1));
    for (std::size_t s = 0; s < axes.bars.size(); ++s) {
      const BarSet& set = axes.bars[s];
      for (std::size_t k = 0; k < set.values.size() && k < axes.categories.size(); ++k) {
        const double v = set.values[k];
        if (!std::isfinite(v)) continue;
        const double x0 = static_cast<double>(k) - group / 2 + group * static_cast<double>(s) / n;
        const double x1 = x0 + group / n;
        set_color(cr, set.color);
        cairo_rectangle(cr, m.px(x0), m.py(v), m.px(x1) - m.px(x0) - 1, m.py(0) - m.py(v));
        cairo_fill(cr);
        if (axes.bar_value_decimals >= 0) {
          set_font(cr, kTickFont - 1);
          cairo_set_source_rgb(cr, 0.15, 0.15, 0.15);
          draw_text(cr, format_tick(v, axes.bar_value_decimals), m.px((x0 + x1) / 2), m.py(v) - 4, 0.5, 1);
        }
      }
      if (!set.label.empty()) legend.push_back({set.label, set.color, false, false, true, false, 1});
    }
  } else {
    for (const Series& s : axes.series) {
      draw_series(cr, m, s, axes.color_bar);
      if (!s.label.empty()) {
        const bool mapped = axes.color_bar.has_value() && !s.values.empty();
        legend.push_back({s.label, s.color, s.dashed, mapped, false, s.style == SeriesStyle::kPoints, s.width_px});
      }
    }
  }
  for (const HorizontalLine& line : axes.horizontal_lines) {
    set_color(cr, line.color);
    cairo_set_line_width(cr, 1.5);
    set_dash(cr, line.dashed, 1.2);
    cairo_move_to(cr, m.plot.x, m.py(line.value));
    cairo_line_to(cr, m.plot.x + m.plot.w, m.py(line.value));
    cairo_stroke(cr);
    if (!line.label.empty()) legend.push_back({line.label, line.color, line.dashed, false, false, false, 1.5});
  }
  set_dash(cr, false, 1);
  if (axes.legend) {
    // Pixel positions of the data (bar tops for bar charts), for LegendPlace::kBest.
    std::vector<std::pair<double, double>> points;
    for (const Series& s : axes.series) {
      for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i) {
        if (finite_point(s, i)) points.emplace_back(m.px(s.x[i]), m.py(s.y[i]));
      }
    }
    for (const BarSet& set : axes.bars) {
      for (std::size_t k = 0; k < set.values.size(); ++k) {
        if (!std::isfinite(set.values[k])) continue;
        for (double dx : {-0.35, 0.0, 0.35}) {
          for (double v = 0; v <= 1.0; v += 0.1) {
            points.emplace_back(m.px(static_cast<double>(k) + dx), m.py(v * set.values[k]));
          }
        }
      }
    }
    draw_legend(cr, m.plot, legend, axes.legend_place, points);
  }
  cairo_restore(cr);

  // Frame, labels, title, colour bar.
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_set_line_width(cr, 1);
  cairo_rectangle(cr, std::round(m.plot.x) + 0.5, std::round(m.plot.y) + 0.5, std::round(m.plot.w),
                  std::round(m.plot.h));
  cairo_stroke(cr);
  set_font(cr, kLabelFont);
  draw_text(cr, axes.x_label, m.plot.x + m.plot.w / 2, m.plot.y + m.plot.h + 32, 0.5, 0);
  cairo_save(cr);
  cairo_translate(cr, cell.x + 18, m.plot.y + m.plot.h / 2);
  cairo_rotate(cr, -std::numbers::pi / 2);
  draw_text(cr, axes.y_label, 0, 0, 0.5, 0.5);
  cairo_restore(cr);
  if (!axes.title.empty()) {
    set_font(cr, kTitleFont, true);
    draw_text(cr, axes.title, m.plot.x + m.plot.w / 2, cell.y + 10, 0.5, 0);
  }
  if (axes.color_bar) draw_color_bar(cr, m.plot, *axes.color_bar);
}

void draw_figure(cairo_t* cr, const Figure& figure) {
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  double top = 0;
  if (!figure.title.empty()) {
    set_font(cr, kFigureTitleFont, true);
    cairo_set_source_rgb(cr, 0, 0, 0);
    draw_text(cr, figure.title, figure.width_px / 2.0, 10, 0.5, 0);
    top = 34;
  }
  const int columns = std::max(1, figure.columns);
  const auto panels = static_cast<int>(figure.panels.size());
  const int rows = std::max(1, (panels + columns - 1) / columns);
  const double cell_w = figure.width_px / static_cast<double>(columns);
  const double cell_h = (figure.height_px - top) / static_cast<double>(rows);
  for (int k = 0; k < panels; ++k) {
    const Rect cell{cell_w * (k % columns), top + cell_h * (k / columns), cell_w, cell_h};
    draw_axes(cr, figure.panels[static_cast<std::size_t>(k)], cell);
  }
}

}  // namespace

std::optional<ImageFormat> image_format_from_path(std::string_view path) {
  const auto dot = path.rfind('.');
  if (dot == std::string_view::npos) return std::nullopt;
  std::string ext(path.substr(dot + 1));
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == "png") return ImageFormat::kPng;
  if (ext == "svg") return ImageFormat::kSvg;
  return std::nullopt;
}

std::string_view extension(ImageFormat format) { return format == ImageFormat::kPng ? ".png" : ".svg"; }

RenderResult render(const Figure& figure, ImageFormat format) {
  RenderResult result;
  if (figure.width_px < 50 || figure.height_px < 50 || figure.width_px > 20000 || figure.height_px > 20000) {
    result.message = "figure size must be 50..20000 pixels each way, got " + std::to_string(figure.width_px) + "x" +
                     std::to_string(figure.height_px);
    return result;
  }
  Surface surface;
  if (format == ImageFormat::kPng) {
    surface.reset(cairo_image_surface_create(CAIRO_FORMAT_RGB24, figure.width_px, figure.height_px));
  } else {
    surface.reset(cairo_svg_surface_create_for_stream(append_to_string, &result.bytes, figure.width_px,
                                                      figure.height_px));
  }
  if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS) {
    result.message = std::string("cairo: ") + cairo_status_to_string(cairo_surface_status(surface.get()));
    return result;
  }
  {
    Context context(cairo_create(surface.get()));
    cairo_t* cr = context.get();
    cairo_set_antialias(cr, CAIRO_ANTIALIAS_BEST);
    draw_figure(cr, figure);
    if (cairo_status(cr) != CAIRO_STATUS_SUCCESS) {
      result.message = std::string("cairo: ") + cairo_status_to_string(cairo_status(cr));
      return result;
    }
  }
  if (format == ImageFormat::kPng) {
    try {
      result.bytes = encode_png(surface.get());
    } catch (const std::runtime_error& e) {
      result.message = e.what();
      return result;
    }
  } else {
    cairo_surface_finish(surface.get());
    if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS) {
      result.message = std::string("cairo: ") + cairo_status_to_string(cairo_surface_status(surface.get()));
      return result;
    }
  }
  result.ok = true;
  return result;
}

}  // namespace cairn::viz
