#include "cairn/viz/cairo_image.hpp"

#include <stdexcept>

namespace cairn::viz {
namespace {

cairo_status_t append_to_string(void* closure, const unsigned char* data, unsigned int length) {
  static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
  return CAIRO_STATUS_SUCCESS;
}

}  // namespace

std::string encode_png(cairo_surface_t* surface) {
  cairo_surface_flush(surface);
  std::string bytes;
  const cairo_status_t status = cairo_surface_write_to_png_stream(surface, append_to_string, &bytes);
  if (status != CAIRO_STATUS_SUCCESS) throw std::runtime_error(std::string("cairo cannot encode the PNG: ") + cairo_status_to_string(status));
  return bytes;
}

}  // namespace cairn::viz
