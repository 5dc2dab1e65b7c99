#include "cairn/inertial/static_initialization.hpp"

#include <algorithm>
#include <cmath>
#include <utility>
#include <sstream>

#include "cairn/core/problems.hpp"

namespace cairn::inertial {

bool StaticInitializationOptions::is_valid(std::string* why) const {
  core::Problems problems;
  if (!(std::isfinite(window_s) && window_s > 0.0)) problems.add("window_s must be finite and > 0");
  for (const auto& [value, name] : {std::pair{block_s, "block_s"}, std::pair{gyro_block_spread_max_rad_s, "gyro_block_spread_max_rad_s"},
                                     std::pair{accel_block_spread_max_mps2, "accel_block_spread_max_mps2"}}) {
    if (!(std::isfinite(value) && value > 0.0)) problems.add(std::string(name) + " must be finite and > 0");
  }
  if (!(std::isfinite(gravity_mps2) && gravity_mps2 > 0.0)) problems.add("gravity_mps2 must be finite and > 0");
  return problems.report(why);
}

namespace {

/// Mean and population standard deviation of the window's gyro and accel, per axis.
void window_moments(const std::vector<ImuSample>& samples, std::size_t count, StaticInitialization& result) {
  Vector3 gyro_sum = Vector3::Zero(), accel_sum = Vector3::Zero();
  for (std::size_t k = 0; k < count; ++k) {
    gyro_sum += samples[k].gyro_rad_s;
    accel_sum += samples[k].accel_mps2;
  }
  const double n = static_cast<double>(count);
  result.gyro_bias_rad_s = gyro_sum / n;
  result.mean_accel_mps2 = accel_sum / n;
  Vector3 gyro_var = Vector3::Zero(), accel_var = Vector3::Zero();
  for (std::size_t k = 0; k < count; ++k) {
    gyro_var += (samples[k].gyro_rad_s - result.gyro_bias_rad_s).cwiseAbs2();
    accel_var += (samples[k].accel_mps2 - result.mean_accel_mps2).cwiseAbs2();
  }
  result.gyro_std_rad_s = (gyro_var / n).cwiseSqrt();
  result.accel_std_mps2 = (accel_var / n).cwiseSqrt();
  result.gyro_bias_sigma_rad_s = result.gyro_std_rad_s / std::sqrt(n);
}

/// Largest |block mean - window mean| over blocks of block_s seconds and the three axes, for the
/// gyro and the accelerometer; and whether every block mean lies within its limit: the option's,
/// or 4 standard errors of a block mean (the axis' standard deviation / sqrt(block samples)) when
/// vibration makes that larger.
bool block_spreads(const std::vector<ImuSample>& samples, std::size_t count, const StaticInitializationOptions& options,
                   StaticInitialization& result) {
  const std::int64_t block_ns = std::max<std::int64_t>(1, std::llround(options.block_s * 1e9));
  bool still = true;
  std::size_t begin = 0;
  while (begin < count) {
    std::size_t end = begin;
    Vector3 gyro = Vector3::Zero(), accel = Vector3::Zero();
    while (end < count && samples[end].stamp.nanoseconds() - samples[begin].stamp.nanoseconds() < block_ns) {
      gyro += samples[end].gyro_rad_s;
      accel += samples[end].accel_mps2;
      ++end;
    }
    const double n = static_cast<double>(end - begin);
    const Vector3 gyro_off = (gyro / n - result.gyro_bias_rad_s).cwiseAbs();
    const Vector3 accel_off = (accel / n - result.mean_accel_mps2).cwiseAbs();
    result.gyro_block_spread_rad_s = std::max(result.gyro_block_spread_rad_s, gyro_off.maxCoeff());
    result.accel_block_spread_mps2 = std::max(result.accel_block_spread_mps2, accel_off.maxCoeff());
    for (int a = 0; a < 3; ++a) {
      still = still && gyro_off[a] <= std::max(options.gyro_block_spread_max_rad_s, 4.0 * result.gyro_std_rad_s[a] / std::sqrt(n));
      still = still && accel_off[a] <= std::max(options.accel_block_spread_max_mps2, 4.0 * result.accel_std_mps2[a] / std::sqrt(n));
    }
    begin = end;
  }
  return still;
}

}  // namespace

StaticInitialization initialize_static(const std::vector<ImuSample>& samples,
                                       const StaticInitializationOptions& options) {
  StaticInitialization result;
  if (samples.empty()) {
    result.message = "no IMU samples";
    return result;
  }
  const core::Timestamp end = core::Timestamp::from_nanoseconds(
      samples.front().stamp.nanoseconds() + static_cast<std::int64_t>(std::llround(options.window_s * 1e9)));
  std::size_t count = 0;
  while (count < samples.size() && samples[count].stamp <= end) ++count;
  result.samples = static_cast<int>(count);
  result.start_s = samples.front().stamp.seconds();
  result.end_s = samples[count - 1].stamp.seconds();
  if (count < 10) {
    result.message = "only " + std::to_string(count) + " samples in the first " + std::to_string(options.window_s) +
                     " s (at least 10 needed)";
    return result;
  }
  window_moments(samples, count, result);
  if (!block_spreads(samples, count, options, result)) {
    std::ostringstream why;
    why << "the IMU is not still in the first " << options.window_s << " s: its " << options.block_s
        << " s means move by up to " << result.gyro_block_spread_rad_s << " rad/s (limit "
        << options.gyro_block_spread_max_rad_s << ") and " << result.accel_block_spread_mps2 << " m/s^2 (limit "
        << options.accel_block_spread_max_mps2 << "; or 4 standard errors of a block mean, when larger)";
    result.message = why.str();
    return result;
  }
  const double norm = result.mean_accel_mps2.norm();
  if (!(norm > 0.5 * options.gravity_mps2 && norm < 1.5 * options.gravity_mps2)) {
    result.message = "the mean specific force is " + std::to_string(norm) + " m/s^2, not gravity's " +
                     std::to_string(options.gravity_mps2) + " m/s^2: wrong units (g instead of m/s^2?) or free fall";
    return result;
  }
  const Vector3 up_body = result.mean_accel_mps2 / norm;
  result.gravity_direction_body = -up_body;
  // Roll and pitch that bring the body's up direction to world +z (from_rpy's Rz Ry Rx, yaw 0):
  // R^T e_z = up_body gives roll = atan2(u_y, u_z), pitch = atan2(-u_x, hypot(u_y, u_z)).
  const double roll = std::atan2(up_body.y(), up_body.z());
  const double pitch = std::atan2(-up_body.x(), std::hypot(up_body.y(), up_body.z()));
  result.R_world_body = core::SO3::from_rpy(roll, pitch, 0.0);
  result.accel_bias_along_gravity_mps2 = norm - options.gravity_mps2;
  result.ok = true;
  return result;
}

}  // namespace cairn::inertial
