#pragma once
/// \file
/// The raster map picture shared by `cairn slam2d`'s and `cairn localize2d`'s map.png: the grid's
/// known part as grey levels (black occupied, white free, grey unknown), a white legend strip
/// below it, legend entries and a scale bar. The callers draw their trajectories and marks on it.

#include <Eigen/Core>
#include <string>

#include "cairn/slam2d/probability_grid.hpp"
#include "cairn/viz/cairo_image.hpp"

namespace cairn::slam2d {

/// Cells [i0, i0 + width) x [j0, j0 + height) of a grid.
struct GridCrop {
  int i0 = 0, j0 = 0, width = 1, height = 1;
};
/// The known cells' bounding box plus `margin` cells, clamped to the grid; one cell when none is known.
GridCrop known_crop(const ProbabilityGrid& grid, int margin);

class MapPicture {
 public:
  /// The known part plus 10 cells, at least 480 px wide, with a 28 px legend strip. Throws
  /// io::ParseError naming `path` when cairo cannot make a surface that large.
  MapPicture(const ProbabilityGrid& grid, const std::string& path);

  cairo_t* cr() const { return context_.get(); }
  int width() const { return width_; }
  int height() const { return height_; }  ///< of the map part
  double resolution() const { return resolution_; }
  /// Pixel coordinates of a point in the grid's (world / map) frame.
  Eigen::Vector2d to_image(const Eigen::Vector2d& p) const {
    return Eigen::Vector2d((p.x() - origin_.x()) / resolution_, height_ - (p.y() - origin_.y()) / resolution_);
  }

  /// Where the next legend entry's 18 px symbol goes (the caller may draw one there).
  double legend_x() const { return legend_x_; }
  double legend_y() const { return height_ + 18.0; }
  /// The label of the entry whose symbol is at legend_x(); moves to the next slot.
  void legend_text(const char* text);
  /// A coloured bar as the symbol, then the label.
  void legend_swatch(double red, double green, double blue, const char* text);
  /// The longest of 10, 5, 2 or 1 m that fits beside the legend.
  void scale_bar();
  /// The picture as PNG, written whole or not at all.
  void write(const std::string& path) const;

 private:
  viz::CairoSurface surface_;
  viz::CairoContext context_;
  int width_ = 0, height_ = 0;
  double resolution_ = 1.0;
  Eigen::Vector2d origin_ = Eigen::Vector2d::Zero();
  double legend_x_ = 8.0;
};

}  // namespace cairn::slam2d
