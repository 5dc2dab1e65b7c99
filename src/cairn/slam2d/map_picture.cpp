#include "cairn/slam2d/map_picture.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "cairn/core/utf8.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::slam2d {

GridCrop known_crop(const ProbabilityGrid& grid, int margin) {
  int i0 = grid.width(), j0 = grid.height(), i1 = -1, j1 = -1;
  for (int j = 0; j < grid.height(); ++j) {
    for (int i = 0; i < grid.width(); ++i) {
      if (!grid.cell_known(i, j)) continue;
      i0 = std::min(i0, i);
      i1 = std::max(i1, i);
      j0 = std::min(j0, j);
      j1 = std::max(j1, j);
    }
  }
  if (i1 < 0) return {};
  GridCrop c;
  c.i0 = std::max(0, i0 - margin);
  c.j0 = std::max(0, j0 - margin);
  c.width = std::min(grid.width(), i1 + margin + 1) - c.i0;
  c.height = std::min(grid.height(), j1 + margin + 1) - c.j0;
  return c;
}

MapPicture::MapPicture(const ProbabilityGrid& grid, const std::string& path) {
  constexpr int kLegend = 28;
  const GridCrop crop = known_crop(grid, 10);
  width_ = std::max(480, crop.width);
  height_ = crop.height;
  resolution_ = grid.resolution();
  origin_ = grid.origin() + Eigen::Vector2d(crop.i0, crop.j0) * resolution_;
  surface_.reset(cairo_image_surface_create(CAIRO_FORMAT_RGB24, width_, height_ + kLegend));
  if (cairo_surface_status(surface_.get()) != CAIRO_STATUS_SUCCESS) throw io::ParseError(path, 0, "the map is too large for a PNG");
  unsigned char* data = cairo_image_surface_get_data(surface_.get());
  const int stride = cairo_image_surface_get_stride(surface_.get());
  cairo_surface_flush(surface_.get());
  for (int row = 0; row < height_ + kLegend; ++row) {
    auto* pixels = reinterpret_cast<std::uint32_t*>(data + static_cast<std::ptrdiff_t>(row) * stride);
    for (int i = 0; i < width_; ++i) {
      std::uint32_t grey = row < height_ ? 0xcdu : 0xffu;
      const int gi = i + crop.i0, gj = height_ - 1 - row + crop.j0;
      if (row < height_ && grid.cell_known(gi, gj)) grey = static_cast<std::uint32_t>(std::lround(255.0 * (1.0 - grid.cell_probability(gi, gj))));
      pixels[i] = (grey << 16) | (grey << 8) | grey;
    }
  }
  cairo_surface_mark_dirty(surface_.get());
  context_.reset(cairo_create(surface_.get()));
  cairo_select_font_face(context_.get(), "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(context_.get(), 12.0);
}

void MapPicture::legend_text(const char* text) {
  cairo_t* c = cr();
  cairo_select_font_face(c, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(c, 12.0);
  cairo_set_source_rgb(c, 0, 0, 0);
  cairo_move_to(c, legend_x_ + 22.0, legend_y() - 3.0);
  cairo_show_text(c, core::valid_utf8(text).c_str());
  cairo_text_extents_t extents;
  cairo_text_extents(c, text, &extents);
  legend_x_ += 22.0 + extents.x_advance + 14.0;
}

void MapPicture::legend_swatch(double red, double green, double blue, const char* text) {
  cairo_set_source_rgb(cr(), red, green, blue);
  cairo_rectangle(cr(), legend_x_, legend_y() - 9.0, 18.0, 4.0);
  cairo_fill(cr());
  legend_text(text);
}

void MapPicture::scale_bar() {
  double bar_m = 1.0;
  for (const double length : {10.0, 5.0, 2.0}) {
    if (legend_x_ + length / resolution_ + 50.0 <= width_) {
      bar_m = length;
      break;
    }
  }
  cairo_t* c = cr();
  cairo_set_source_rgb(c, 0, 0, 0);
  cairo_rectangle(c, legend_x_, legend_y() - 9.0, bar_m / resolution_, 4.0);
  cairo_fill(c);
  cairo_move_to(c, legend_x_ + bar_m / resolution_ + 6.0, legend_y() - 3.0);
  cairo_show_text(c, (std::to_string(static_cast<int>(bar_m)) + " m").c_str());
}

void MapPicture::write(const std::string& path) const {
  const std::string png = viz::encode_png(surface_.get());
  io::write_output(path, [&](std::ostream& out) { out << png; });
}

}  // namespace cairn::slam2d
