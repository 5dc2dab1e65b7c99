#pragma once
/// \file
/// Owning handles for cairo surfaces and contexts and PNG encoding, shared by every module that
/// draws a raster picture with cairo directly (maps of slam2d, lidar3d, landmarks, the simulator)
/// and by viz's own renderer.

#include <cairo.h>

#include <memory>
#include <string>

namespace cairn::viz {

struct CairoSurfaceDeleter {
  void operator()(cairo_surface_t* s) const { cairo_surface_destroy(s); }
};
struct CairoContextDeleter {
  void operator()(cairo_t* c) const { cairo_destroy(c); }
};
using CairoSurface = std::unique_ptr<cairo_surface_t, CairoSurfaceDeleter>;
using CairoContext = std::unique_ptr<cairo_t, CairoContextDeleter>;

/// The surface (flushed first) as PNG bytes. Throws std::runtime_error with cairo's status text
/// when cairo cannot encode it.
std::string encode_png(cairo_surface_t* surface);

}  // namespace cairn::viz
