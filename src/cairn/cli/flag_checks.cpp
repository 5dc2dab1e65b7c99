#include "cairn/cli/flag_checks.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <optional>
#include <thread>
#include <utility>

#include "cairn/cli/commands.hpp"
#include "cairn/io/number_format.hpp"

namespace cairn::cli::checks {
namespace {

// The text shown for a value the user gave: cut, so a 10,000-digit argument does not flood
// the terminal.
std::string shown(const std::string& text) { return text.size() <= 40 ? "'" + text + "'" : "'" + text.substr(0, 40) + "...'"; }

// The whole text as a double, or nullopt: strtod reads what CLI11 converts afterwards ("1e3",
// "0x10"); "nan", "inf" and an overflowing "1e999" parse here and are refused by the caller.
std::optional<double> parse_number(const std::string& text) {
  if (text.empty()) return std::nullopt;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size()) return std::nullopt;
  return value;
}

// The whole text as an integer, or nullopt (a decimal point or an exponent is not a count).
std::optional<long long> parse_whole(const std::string& text) {
  long long value = 0;
  const char* first = text.data();
  const char* last = text.data() + text.size();
  if (first != last && *first == '+') ++first;
  const auto [end, error] = std::from_chars(first, last, value);
  if (error != std::errc{} || end != last || first == last) return std::nullopt;
  return value;
}

// "" when `text` is a finite number inside the bounds, else the message.
CLI::Validator number_check(double lo, bool lo_open, double hi, const std::string& wanted) {
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        const std::optional<double> value = parse_number(text);
        if (!value) return "expected " + wanted + ", got " + shown(text) + " (not a number)";
        if (!std::isfinite(*value)) return "expected " + wanted + ", got " + shown(text);
        if (*value < lo || (lo_open && *value == lo) || *value > hi) return "expected " + wanted + ", got " + shown(text);
        return {};
      },
      wanted, "cairn-number");
}

CLI::Validator whole_check(long long lo, long long hi, const std::string& wanted) {
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        const std::optional<long long> value = parse_whole(text);
        if (!value) return "expected " + wanted + ", got " + shown(text) + " (not a whole number)";
        if (*value < lo || *value > hi) return "expected " + wanted + ", got " + shown(text);
        return {};
      },
      wanted, "cairn-count");
}

std::string bounds(double lo, const char* lo_sign, double hi) {
  std::string s = std::string("a finite number ") + lo_sign + " " + format_number(lo);
  if (hi < std::numeric_limits<double>::max()) s += " and <= " + format_number(hi);
  return s;
}

}  // namespace

std::string format_number(double value) {
  std::string text;
  io::append_number(text, value);
  return text;
}

int hardware_threads() { return static_cast<int>(std::max(1u, std::thread::hardware_concurrency())); }

CLI::Validator finite() {
  return number_check(std::numeric_limits<double>::lowest(), false, std::numeric_limits<double>::max(), "a finite number");
}
CLI::Validator positive() { return number_check(0.0, true, std::numeric_limits<double>::max(), "a finite number > 0"); }
CLI::Validator non_negative() { return number_check(0.0, false, std::numeric_limits<double>::max(), "a finite number >= 0"); }
CLI::Validator in_range(double lo, double hi) {
  return number_check(lo, false, hi, "a number from " + format_number(lo) + " to " + format_number(hi));
}
CLI::Validator above(double lo, double hi) { return number_check(lo, true, hi, bounds(lo, ">", hi)); }

// The type's own limit is not shown: "a whole number >= 1", not "from 1 to 9223372036854775807".
CLI::Validator count(long long hi) {
  return whole_check(1, hi, hi >= std::numeric_limits<int>::max() ? "a whole number >= 1"
                                                                  : "a whole number from 1 to " + std::to_string(hi));
}
CLI::Validator count_or_zero(long long hi) {
  return whole_check(0, hi, hi >= std::numeric_limits<int>::max() ? "a whole number >= 0"
                                                                  : "a whole number from 0 to " + std::to_string(hi));
}

CLI::Validator whole_range(long long lo, long long hi) {
  return whole_check(lo, hi, "a whole number from " + std::to_string(lo) + " to " + std::to_string(hi));
}

CLI::Validator threads() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        const std::optional<long long> value = parse_whole(text);
        if (!value || *value < 0) {
          return "expected a whole number >= 0 (0 = every hardware thread), got " + shown(text);
        }
        const int machine = hardware_threads();
        if (*value > machine) {
          std::cerr << "cairn: warning: --threads " << text << ": this machine runs " << machine
                    << " hardware threads; using " << machine << '\n';
          text = std::to_string(machine);
        }
        return {};
      },
      "a whole number >= 0 (0 = every hardware thread)", "cairn-threads");
}

void refuse_imu_companions_without_imu(bool uses_imu, bool calibration_given, const char* extrinsic_flag, bool extrinsic_given,
                                       bool offset_given) {
  if (uses_imu) return;
  for (const auto& [given, name] : {std::pair<bool, const char*>{calibration_given, "--imu-calibration"},
                                    std::pair<bool, const char*>{extrinsic_given, extrinsic_flag},
                                    std::pair<bool, const char*>{offset_given, "--imu-time-offset"}}) {
    if (given) throw UsageError(std::string(name) + " goes with --imu PATH or --imu-topic TOPIC, and neither was given");
  }
}

}  // namespace cairn::cli::checks
