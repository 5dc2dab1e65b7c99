#include "cairn/inertial/imu_input.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "cairn/core/assert.hpp"
#include "cairn/core/problems.hpp"
#include "cairn/inertial/imu_rows.hpp"

namespace cairn::inertial {
namespace {

// A run this long of one repeated extreme reading is taken for clipping when no limit is given.
constexpr std::size_t kMinGuessedRun = 3;

double seconds_between(core::Timestamp a, core::Timestamp b) {
  return static_cast<double>(b.nanoseconds() - a.nanoseconds()) * 1e-9;
}

void add_rates(const std::vector<ImuSample>& samples, double gap_factor, ImuDataReport& report) {
  std::vector<double> steps;
  steps.reserve(samples.size());
  for (std::size_t i = 1; i < samples.size(); ++i) steps.push_back(seconds_between(samples[i - 1].stamp, samples[i].stamp));
  report.duration_s = seconds_between(report.first_stamp, report.last_stamp);
  if (steps.empty()) return;
  report.min_dt_s = *std::min_element(steps.begin(), steps.end());
  report.max_dt_s = *std::max_element(steps.begin(), steps.end());
  report.non_increasing_steps = static_cast<std::size_t>(std::count_if(steps.begin(), steps.end(), [](double dt) { return dt <= 0.0; }));
  std::vector<double> sorted = steps;
  const auto middle = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
  std::nth_element(sorted.begin(), middle, sorted.end());
  report.median_dt_s = *middle;
  if (report.median_dt_s > 0.0) report.median_rate_hz = 1.0 / report.median_dt_s;
  if (report.duration_s > 0.0) report.mean_rate_hz = static_cast<double>(samples.size() - 1) / report.duration_s;
  if (!(report.median_dt_s > 0.0)) return;
  for (std::size_t i = 0; i < steps.size(); ++i) {
    if (steps[i] > gap_factor * report.median_dt_s) {
      report.gaps.push_back({samples[i].stamp, samples[i + 1].stamp, steps[i]});
      report.gap_time_s += steps[i];
    }
  }
}

void add_statistics(const std::vector<ImuSample>& samples, ImuDataReport& report) {
  // Two passes (mean, then squared deviations): an accelerometer's 9.8 m/s^2 would cost the
  // one-pass sum of squares most of its digits.
  Vector3 gyro_sum = Vector3::Zero(), accel_sum = Vector3::Zero();
  for (const ImuSample& s : samples) {
    gyro_sum += s.gyro_rad_s;
    accel_sum += s.accel_mps2;
  }
  const double n = static_cast<double>(samples.size());
  report.gyro_mean_rad_s = gyro_sum / n;
  report.accel_mean_mps2 = accel_sum / n;
  if (samples.size() < 2) return;
  Vector3 gyro_squares = Vector3::Zero(), accel_squares = Vector3::Zero();
  for (const ImuSample& s : samples) {
    gyro_squares += (s.gyro_rad_s - report.gyro_mean_rad_s).cwiseAbs2();
    accel_squares += (s.accel_mps2 - report.accel_mean_mps2).cwiseAbs2();
  }
  report.gyro_std_rad_s = (gyro_squares / (n - 1.0)).cwiseSqrt();
  report.accel_std_mps2 = (accel_squares / (n - 1.0)).cwiseSqrt();
}

// Saturation runs of one sensor's axis; `saturated[i]` is set for every sample in a run.
void find_runs(const std::vector<ImuSample>& samples, bool gyro, int axis, double limit, std::vector<char>& saturated,
               std::vector<ImuSaturationRun>& runs) {
  const auto value = [&](std::size_t i) { return (gyro ? samples[i].gyro_rad_s : samples[i].accel_mps2)[axis]; };
  double lowest = std::numeric_limits<double>::infinity(), highest = -lowest;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    lowest = std::min(lowest, value(i));
    highest = std::max(highest, value(i));
  }
  const bool known = limit > 0.0;
  const auto at_limit = [&](std::size_t i) {
    const double v = value(i);
    return known ? std::abs(v) >= limit : (v == highest || v == lowest);
  };
  std::size_t i = 0;
  while (i < samples.size()) {
    if (!at_limit(i)) {
      ++i;
      continue;
    }
    std::size_t end = i + 1;
    // Known limit: any run of samples beyond it; guessed: one repeated value.
    while (end < samples.size() && at_limit(end) && (known || value(end) == value(i))) ++end;
    if (known || end - i >= kMinGuessedRun) {
      runs.push_back({gyro, axis, samples[i].stamp, samples[end - 1].stamp, end - i, value(i), known});
      for (std::size_t k = i; k < end; ++k) saturated[k] = 1;
    }
    i = end;
  }
}

}  // namespace

bool ImuInputOptions::is_valid(std::string* why) const {
  core::Problems problems;
  if (!(std::isfinite(time_offset_s) && std::abs(time_offset_s) <= kMaxAbsTimeOffsetS)) {
    problems.add("time_offset_s must be finite and within +-9.2e9 s");
  }
  if (!T_body_imu.translation().allFinite()) problems.add("T_body_imu must have a finite translation");
  if (!(std::isfinite(gyro_saturation_rad_s) && gyro_saturation_rad_s >= 0.0)) {
    problems.add("gyro_saturation_rad_s must be finite and >= 0 (0: unknown)");
  }
  if (!(std::isfinite(accel_saturation_mps2) && accel_saturation_mps2 >= 0.0)) {
    problems.add("accel_saturation_mps2 must be finite and >= 0 (0: unknown)");
  }
  if (!(std::isfinite(gap_factor) && gap_factor > 1.0)) problems.add("gap_factor must be finite and > 1");
  return problems.report(why);
}

ImuDataReport check_imu_data(const std::vector<ImuSample>& samples, const ImuInputOptions& options) {
  CAIRN_ASSERT(options.is_valid(nullptr), "check_imu_data needs valid ImuInputOptions (call is_valid first)");
  ImuDataReport report;
  report.samples = samples.size();
  report.gap_factor = options.gap_factor;
  report.gyro_limit_known = options.gyro_saturation_rad_s > 0.0;
  report.accel_limit_known = options.accel_saturation_mps2 > 0.0;
  if (samples.empty()) return report;
  report.first_stamp = samples.front().stamp;
  report.last_stamp = samples.back().stamp;
  add_rates(samples, options.gap_factor, report);
  add_statistics(samples, report);
  for (const bool gyro : {true, false}) {
    std::vector<char> saturated(samples.size(), 0);
    for (int axis = 0; axis < 3; ++axis) {
      find_runs(samples, gyro, axis, gyro ? options.gyro_saturation_rad_s : options.accel_saturation_mps2, saturated,
                report.saturation);
    }
    (gyro ? report.gyro_saturated_samples : report.accel_saturated_samples) =
        static_cast<std::size_t>(std::count(saturated.begin(), saturated.end(), 1));
  }
  return report;
}

std::vector<ImuSample> apply_imu_input(const std::vector<ImuSample>& samples, const ImuInputOptions& options) {
  CAIRN_ASSERT(options.is_valid(nullptr), "apply_imu_input needs valid ImuInputOptions (call is_valid first)");
  const auto offset_ns = static_cast<std::int64_t>(std::llround(options.time_offset_s * 1e9));
  const Matrix3 R_body_imu = options.T_body_imu.rotation_matrix();
  std::vector<ImuSample> out;
  out.reserve(samples.size());
  for (const ImuSample& s : samples) {
    // Compared before adding, so that neither the test nor the sum can overflow int64.
    const std::int64_t ns = s.stamp.nanoseconds();
    if ((offset_ns > 0 && ns > kMaxAbsImuStampNs - offset_ns) || (offset_ns < 0 && ns < -kMaxAbsImuStampNs - offset_ns)) {
      throw std::out_of_range("IMU stamp " + s.stamp.to_seconds_string() + " s shifted by time_offset_s leaves +-9.2e9 s");
    }
    out.push_back({core::Timestamp::from_nanoseconds(ns + offset_ns), R_body_imu * s.gyro_rad_s, R_body_imu * s.accel_mps2});
  }
  return out;
}

nlohmann::json to_json(const ImuDataReport& report) {
  const auto vector = [](const Vector3& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); };
  nlohmann::json gaps = nlohmann::json::array();
  for (const ImuGap& gap : report.gaps) {
    gaps.push_back({{"before_ns", gap.before.nanoseconds()}, {"after_ns", gap.after.nanoseconds()}, {"dt_s", gap.dt_s}});
  }
  nlohmann::json runs = nlohmann::json::array();
  for (const ImuSaturationRun& run : report.saturation) {
    runs.push_back({{"sensor", run.gyro ? "gyro" : "accel"},
                    {"axis", std::string(1, static_cast<char>('x' + run.axis))},
                    {"first_ns", run.first.nanoseconds()},
                    {"last_ns", run.last.nanoseconds()},
                    {"samples", run.samples},
                    {"value", run.value},
                    {"from_limit", run.from_limit}});
  }
  return {{"samples", report.samples},
          {"first_stamp_ns", report.first_stamp.nanoseconds()},
          {"last_stamp_ns", report.last_stamp.nanoseconds()},
          {"duration_s", report.duration_s},
          {"median_dt_s", report.median_dt_s},
          {"median_rate_hz", report.median_rate_hz},
          {"mean_rate_hz", report.mean_rate_hz},
          {"min_dt_s", report.min_dt_s},
          {"max_dt_s", report.max_dt_s},
          {"non_increasing_steps", report.non_increasing_steps},
          {"gap_factor", report.gap_factor},
          {"gaps", gaps},
          {"gap_time_s", report.gap_time_s},
          {"gyro_limit_known", report.gyro_limit_known},
          {"accel_limit_known", report.accel_limit_known},
          {"gyro_saturated_samples", report.gyro_saturated_samples},
          {"accel_saturated_samples", report.accel_saturated_samples},
          {"saturation", runs},
          {"gyro_mean_rad_s", vector(report.gyro_mean_rad_s)},
          {"gyro_std_rad_s", vector(report.gyro_std_rad_s)},
          {"accel_mean_mps2", vector(report.accel_mean_mps2)},
          {"accel_std_mps2", vector(report.accel_std_mps2)}};
}

}  // namespace cairn::inertial
