#pragma once
/// \file
/// Drawing a Figure with cairo into PNG or SVG bytes. Writing the bytes to disk is the caller's
/// job (the CLI writes them atomically), so this module needs no file I/O of its own.

#include <optional>
#include <string>
#include <string_view>

#include "cairn/viz/figure.hpp"

namespace cairn::viz {

enum class ImageFormat {
  kPng,
  kSvg,
};

/// From the extension (.png / .svg, any case); nullopt otherwise.
std::optional<ImageFormat> image_format_from_path(std::string_view path);
std::string_view extension(ImageFormat format);

/// Encoded image, or an error message (cairo's status text).
struct RenderResult {
  bool ok = false;
  std::string bytes;
  std::string message;
};

/// Draws every panel: frame, nice ticks with labels, axis labels, title, series (colour-mapped
/// when they carry values), horizontal lines, bars, legend and colour bar. Empty panels and
/// series without finite points are drawn as empty axes, never fail.
RenderResult render(const Figure& figure, ImageFormat format);

}  // namespace cairn::viz
