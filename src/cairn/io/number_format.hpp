#pragma once
/// \file
/// Shortest decimal text that parses back to the same double (std::to_chars), for writers.

#include <charconv>
#include <string>

namespace cairn::io {

inline void append_number(std::string& out, double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  out.append(buffer, result.ptr);
}

}  // namespace cairn::io
