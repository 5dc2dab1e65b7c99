#include "cairn/viz/cairo_image.hpp"
#include "cairn/sim/render.hpp"

#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <ostream>

#include "cairn/core/utf8.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::sim {
namespace {

/// Largest image side, pixels: a wildly drifting dead reckoning shrinks the scale instead.
constexpr double kMaxSidePx = 4000.0;


}  // namespace

void render_png(const std::string& path, const World& world, const std::vector<Vector2>& truth,
                const std::vector<Vector2>& dead_reckoning, const RenderOptions& options) {
  Bounds box = world.bounds();
  for (const auto* points : {&truth, &dead_reckoning}) {
    for (const auto& p : *points) {
      if (!p.allFinite()) continue;  // a break in the path
      box.min = box.min.cwiseMin(p);
      box.max = box.max.cwiseMax(p);
    }
  }
  const Vector2 size = box.max - box.min;
  const double scale = std::min(options.pixels_per_m, kMaxSidePx / std::max({size.x(), size.y(), 1.0}));
  const double margin = options.margin_px;
  const double legend_height = 70.0;
  const int width = static_cast<int>(std::ceil(size.x() * scale + 2 * margin));
  const int height = static_cast<int>(std::ceil(size.y() * scale + 2 * margin + legend_height));

  viz::CairoSurface surface(cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height));
  viz::CairoContext context(cairo_create(surface.get()));
  cairo_t* cr = context.get();
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);

  // World to image: x right, y up (image rows grow downwards).
  auto to_image = [&](const Vector2& p) {
    return Vector2(margin + (p.x() - box.min.x()) * scale, margin + (box.max.y() - p.y()) * scale);
  };
  auto move_to = [&](const Vector2& p) {
    const Vector2 q = to_image(p);
    cairo_move_to(cr, q.x(), q.y());
  };
  auto line_to = [&](const Vector2& p) {
    const Vector2 q = to_image(p);
    cairo_line_to(cr, q.x(), q.y());
  };
  auto polyline = [&](const std::vector<Vector2>& points, double r, double g, double b, double line_width) {
    if (points.size() < 2) return;
    cairo_set_source_rgba(cr, r, g, b, 0.85);
    cairo_set_line_width(cr, line_width);
    cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
    bool pen_down = false;
    for (const auto& p : points) {
      if (!p.allFinite()) {
        pen_down = false;
      } else if (pen_down) {
        line_to(p);
      } else {
        move_to(p);
        pen_down = true;
      }
    }
    cairo_stroke(cr);
  };

  cairo_set_source_rgb(cr, 0.55, 0.55, 0.55);
  for (const auto& circle : world.circles) {
    const Vector2 c = to_image(circle.center);
    cairo_arc(cr, c.x(), c.y(), std::max(circle.radius_m * scale, 1.5), 0, 2 * std::numbers::pi);
    cairo_fill(cr);
  }
  // Walkers: their track (thin, purple) and where they are at the start.
  for (const auto& walker : world.walkers) {
    cairo_set_source_rgba(cr, 0.6, 0.2, 0.7, 0.6);
    cairo_set_line_width(cr, 1.0);
    move_to(walker.from);
    line_to(walker.to);
    cairo_stroke(cr);
    const Circle disc = walker.at(0.0);
    const Vector2 c = to_image(disc.center);
    cairo_arc(cr, c.x(), c.y(), std::max(disc.radius_m * scale, 2.0), 0, 2 * std::numbers::pi);
    cairo_fill(cr);
  }
  cairo_set_line_width(cr, std::max(2.0, 0.1 * scale));
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_SQUARE);
  for (const auto& wall : world.walls) {
    if (wall.glass) {
      cairo_set_source_rgb(cr, 0.35, 0.7, 0.95);  // glass: light blue
    } else {
      cairo_set_source_rgb(cr, 0, 0, 0);
    }
    move_to(wall.a);
    line_to(wall.b);
    cairo_stroke(cr);
  }
  cairo_set_source_rgb(cr, 0.85, 0.1, 0.1);
  cairo_set_line_width(cr, 1.5);
  for (const auto& landmark : world.landmarks) {
    const Vector2 c = to_image(landmark.position);
    cairo_move_to(cr, c.x() - 4, c.y() - 4);
    cairo_line_to(cr, c.x() + 4, c.y() + 4);
    cairo_move_to(cr, c.x() - 4, c.y() + 4);
    cairo_line_to(cr, c.x() + 4, c.y() - 4);
    cairo_stroke(cr);
  }
  polyline(dead_reckoning, 0.95, 0.5, 0.0, 1.5);
  polyline(truth, 0.1, 0.3, 0.9, 1.5);
  if (!truth.empty() && truth.front().allFinite()) {
    const Vector2 s = to_image(truth.front());
    cairo_set_source_rgb(cr, 0.0, 0.65, 0.0);
    cairo_arc(cr, s.x(), s.y(), 5, 0, 2 * std::numbers::pi);
    cairo_fill(cr);
  }

  // Legend and scale bar under the map.
  const double y0 = height - legend_height + 10;
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, 13);
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_move_to(cr, margin, y0 + 12);
  cairo_show_text(cr, core::valid_utf8(options.title).c_str());
  auto legend_entry = [&](double x, double r, double g, double b, const char* text) {
    cairo_set_source_rgb(cr, r, g, b);
    cairo_set_line_width(cr, 3);
    cairo_move_to(cr, x, y0 + 32);
    cairo_line_to(cr, x + 25, y0 + 32);
    cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_move_to(cr, x + 32, y0 + 37);
    cairo_show_text(cr, text);
  };
  legend_entry(margin, 0.1, 0.3, 0.9, "ground truth");
  legend_entry(margin + 140, 0.95, 0.5, 0.0, "dead reckoning");
  const double bar = 5.0 * scale;
  const double bar_x = margin + 300;
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_set_line_width(cr, 3);
  cairo_move_to(cr, bar_x, y0 + 32);
  cairo_line_to(cr, bar_x + bar, y0 + 32);
  cairo_stroke(cr);
  cairo_move_to(cr, bar_x + bar + 8, y0 + 37);
  cairo_show_text(cr, "5 m");

  const std::string png = viz::encode_png(surface.get());
  io::write_output(path, [&](std::ostream& out) { out << png; });
}

}  // namespace cairn::sim
