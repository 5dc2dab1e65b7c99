#include "cairn/bag/mcap_format.hpp"

#include <zlib.h>

#include <algorithm>

namespace cairn::bag::mcap {

std::uint32_t crc32_of(std::span<const std::uint8_t> bytes, std::uint32_t crc) {
  uLong value = crc;
  for (std::size_t at = 0; at < bytes.size();) {
    const std::size_t piece = std::min<std::size_t>(bytes.size() - at, std::size_t{1} << 30);
    value = crc32(value, bytes.data() + at, static_cast<uInt>(piece));
    at += piece;
  }
  return static_cast<std::uint32_t>(value);
}

}  // namespace cairn::bag::mcap
