#pragma once
/// \file
/// Timestamps as integer nanoseconds since an arbitrary epoch (the file's), like ROS time.
///
/// Stored as int64 so that EuRoC's 19-digit nanosecond stamps and TUM's microsecond decimals
/// survive a read/write round trip exactly; doubles (evo's choice) keep only ~16 digits.

#include <compare>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace cairn::core {

class Timestamp {
 public:
  Timestamp() = default;
  static constexpr Timestamp from_nanoseconds(std::int64_t ns) { return Timestamp(ns); }
  /// Rounds to the nearest nanosecond. Precondition: finite and within +-9.2e9 s.
  static Timestamp from_seconds(double seconds);

  /// Parses decimal seconds ("1305031102.175304", "-0.5", "1.036614e-01") exactly to the
  /// nanosecond when written without exponent (digits past the 9th decimal are rounded half
  /// away from zero); with an exponent the value goes through double. Returns nullopt on
  /// anything else (empty, trailing characters, nan, inf, out of range).
  static std::optional<Timestamp> parse_seconds(std::string_view text);
  /// Parses an integer count of nanoseconds (EuRoC). nullopt when not an integer or out of range.
  static std::optional<Timestamp> parse_nanoseconds(std::string_view text);

  constexpr std::int64_t nanoseconds() const { return ns_; }
  double seconds() const { return static_cast<double>(ns_) * 1e-9; }
  /// Seconds with exactly nine decimals: "1305031102.175304000". Parses back to the same value.
  std::string to_seconds_string() const;

  constexpr auto operator<=>(const Timestamp&) const = default;

 private:
  constexpr explicit Timestamp(std::int64_t ns) : ns_(ns) {}
  std::int64_t ns_ = 0;
};

}  // namespace cairn::core
