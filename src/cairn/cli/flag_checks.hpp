#pragma once
/// \file
/// The one validation layer for the values of command-line flags (docs/conventions.md, "Flags").
///
/// CLI11's own PositiveNumber / NonNegativeNumber / Range let NaN through (NaN compares false both
/// ways) and print their bounds with std::to_string (a 309-digit DBL_MAX). Every numeric flag of
/// every command is checked here instead:
///
/// * a number must be finite (`nan`, `inf` and `1e999` are refused by name);
/// * bounds are printed as the user would write them (`0.5`, `1e+09`), and a message says what the
///   flag needs (`--extent: expected a finite number > 0, got nan`);
/// * a count is a whole number >= 1; where 0 has a meaning, the flag says so in its help
///   ("0 = off", "0 = all cores") and the check is `count_or_zero`;
/// * a thread count above what this machine can run is clamped to its hardware threads, with a
///   warning (TBB's arena with 100,000 threads takes minutes to start and crashes at shutdown).

#include <CLI/CLI.hpp>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "cairn/cli/commands.hpp"
#include "cairn/io/parameters.hpp"

namespace cairn::cli::checks {

/// Any finite number.
CLI::Validator finite();
/// A finite number > 0.
CLI::Validator positive();
/// A finite number >= 0.
CLI::Validator non_negative();
/// A finite number in [lo, hi].
CLI::Validator in_range(double lo, double hi);
/// A finite number in (lo, hi] (lo excluded).
CLI::Validator above(double lo, double hi = std::numeric_limits<double>::max());
/// A whole number >= 1 (and <= hi).
CLI::Validator count(long long hi = std::numeric_limits<int>::max());
/// A whole number >= 0 (and <= hi); the flag's help says what 0 means.
CLI::Validator count_or_zero(long long hi = std::numeric_limits<int>::max());
/// A whole number in [lo, hi].
CLI::Validator whole_range(long long lo, long long hi);
/// A thread count: a whole number >= 0 (0 = every hardware thread); above the machine's
/// hardware threads it is clamped to them with a warning on standard error. It changes the value,
/// so it is given with `->transform(...)` (CLI11's `check` discards a validator's changes).
CLI::Validator threads();

/// How a bound or value is shown in a message: the shortest text that reads back to the same
/// double ("0.5", "1e+09", "1.7976931348623157e+308").
std::string format_number(double value);

/// The number of hardware threads (>= 1).
int hardware_threads();

/// The IMU's companion flags (slam3d's and vslam's --imu-calibration, the sensor's extrinsic,
/// --imu-time-offset) mean nothing without --imu PATH or --imu-topic TOPIC: without them, a
/// UsageError names the first companion given. `extrinsic_flag` is --lidar-extrinsic or
/// --camera-extrinsic.
void refuse_imu_companions_without_imu(bool uses_imu, bool calibration_given, const char* extrinsic_flag, bool extrinsic_given,
                                       bool offset_given);

/// --config FILE (when given) and then every --set section.key=value over `options`. A bad file
/// throws io::ParseError (its file and line); a bad assignment is a UsageError (exit status 2).
template <class Options>
void apply_configuration(const io::Configuration<Options>& configuration, const std::string& config_file,
                         const std::vector<std::string>& assignments, Options& options) {
  if (!config_file.empty()) configuration.load(config_file, options);
  for (const std::string& assignment : assignments) {
    try {
      configuration.set(assignment, options);
    } catch (const std::invalid_argument& e) {
      throw UsageError(e.what());
    }
  }
}

}  // namespace cairn::cli::checks
