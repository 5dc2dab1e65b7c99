#include "cairn/core/time.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>

namespace cairn::core {

Timestamp Timestamp::from_seconds(double seconds) {
  return Timestamp(static_cast<std::int64_t>(std::llround(seconds * 1e9)));
}

std::optional<Timestamp> Timestamp::parse_seconds(std::string_view text) {
  if (text.empty()) return std::nullopt;
  if (text.find_first_of("eE") != std::string_view::npos) {
    double value = 0.0;
    const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (ec != std::errc() || ptr != text.data() + text.size() || !std::isfinite(value) ||
        std::abs(value) > 9.2e9) {
      return std::nullopt;
    }
    return from_seconds(value);
  }
  std::size_t i = 0;
  bool negative = false;
  if (text[i] == '-' || text[i] == '+') {
    negative = text[i] == '-';
    ++i;
  }
  constexpr std::int64_t kMaxSeconds = std::numeric_limits<std::int64_t>::max() / 1'000'000'000 - 1;
  std::int64_t whole = 0;
  std::size_t whole_digits = 0;
  for (; i < text.size() && text[i] >= '0' && text[i] <= '9'; ++i, ++whole_digits) {
    whole = whole * 10 + (text[i] - '0');
    if (whole > kMaxSeconds) return std::nullopt;
  }
  std::int64_t frac = 0;
  std::size_t frac_digits = 0;
  bool round_up = false;
  if (i < text.size() && text[i] == '.') {
    ++i;
    for (; i < text.size() && text[i] >= '0' && text[i] <= '9'; ++i, ++frac_digits) {
      if (frac_digits < 9) {
        frac = frac * 10 + (text[i] - '0');
      } else if (frac_digits == 9) {
        round_up = text[i] >= '5';
      }
    }
  }
  if (i != text.size() || whole_digits + frac_digits == 0) return std::nullopt;
  for (std::size_t k = frac_digits; k < 9; ++k) frac *= 10;
  std::int64_t ns = whole * 1'000'000'000 + frac + (round_up ? 1 : 0);
  return Timestamp(negative ? -ns : ns);
}

std::optional<Timestamp> Timestamp::parse_nanoseconds(std::string_view text) {
  std::int64_t ns = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), ns);
  if (text.empty() || ec != std::errc() || ptr != text.data() + text.size()) return std::nullopt;
  return Timestamp(ns);
}

std::string Timestamp::to_seconds_string() const {
  // Unsigned magnitude: -INT64_MIN does not fit in int64.
  const std::uint64_t abs_ns = ns_ < 0 ? 0 - static_cast<std::uint64_t>(ns_) : static_cast<std::uint64_t>(ns_);
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%s%llu.%09llu", ns_ < 0 ? "-" : "",
                static_cast<unsigned long long>(abs_ns / 1'000'000'000),
                static_cast<unsigned long long>(abs_ns % 1'000'000'000));
  return buffer;
}

}  // namespace cairn::core
