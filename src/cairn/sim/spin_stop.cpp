#include "cairn/sim/spin_stop.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <numbers>

#include "cairn/core/assert.hpp"
#include "cairn/core/problems.hpp"

namespace cairn::sim {
namespace {

/// Yaw turned (rad, >= 0) and yaw rate (rad/s) `time` seconds into a trapezoidal spin by `total`.
std::pair<double, double> trapezoid(double time, double total, double rate, double acceleration) {
  double peak = rate;
  double ramp = rate / acceleration;
  double cruise = (total - rate * rate / acceleration) / rate;
  if (cruise < 0.0) {  // too short to reach the rate: a triangle
    peak = std::sqrt(total * acceleration);
    ramp = peak / acceleration;
    cruise = 0.0;
  }
  const double duration = 2.0 * ramp + cruise;
  time = std::clamp(time, 0.0, duration);
  if (time < ramp) return {0.5 * acceleration * time * time, acceleration * time};
  if (time < ramp + cruise) return {0.5 * acceleration * ramp * ramp + peak * (time - ramp), peak};
  const double left = duration - time;
  return {total - 0.5 * acceleration * left * left, acceleration * left};
}

/// The route's polyline split at arc length `at_m`: the points up to the split and from it on.
std::pair<std::vector<Vector2>, std::vector<Vector2>> split_route(const std::vector<Vector2>& route, double at_m) {
  std::vector<Vector2> before = {route.front()};
  std::vector<Vector2> after;
  double walked = 0.0;
  for (std::size_t i = 0; i + 1 < route.size(); ++i) {
    const double length = (route[i + 1] - route[i]).norm();
    if (after.empty() && walked + length > at_m) {
      const Vector2 stop = route[i] + (at_m - walked) / length * (route[i + 1] - route[i]);
      before.push_back(stop);
      after = {stop};
    }
    (after.empty() ? before : after).push_back(route[i + 1]);
    walked += length;
  }
  CAIRN_ASSERT(!after.empty(), "trajectory_with_spin_stop: spin.at_m must be shorter than the route");
  return {before, after};
}

}  // namespace

bool SpinStopOptions::is_valid(std::string* why) const {
  core::Problems problems;
  if (!(at_m > 0.0 && at_m <= 1e4)) problems.add("at_m must be in (0, 10000]");
  if (turns < 1 || turns > 20) problems.add("turns must be in [1, 20]");
  if (!(yaw_rate_rad_s > 0.0 && yaw_rate_rad_s <= 50.0)) problems.add("yaw_rate_rad_s must be in (0, 50]");
  if (!(yaw_acceleration_rad_s2 > 0.0 && yaw_acceleration_rad_s2 <= 1000.0)) {
    problems.add("yaw_acceleration_rad_s2 must be in (0, 1000]");
  }
  return problems.report(why);
}

double SpinStopOptions::duration_s() const {
  const double total = 2.0 * std::numbers::pi * turns;
  const double ramp_angle = yaw_rate_rad_s * yaw_rate_rad_s / yaw_acceleration_rad_s2;
  if (total >= ramp_angle) return 2.0 * yaw_rate_rad_s / yaw_acceleration_rad_s2 + (total - ramp_angle) / yaw_rate_rad_s;
  return 2.0 * std::sqrt(total / yaw_acceleration_rad_s2);
}

std::vector<TrajectorySample> trajectory_with_spin_stop(const std::vector<Vector2>& route, const TrajectoryOptions& options,
                                                        const SpinStopOptions& spin, SpinEvent* event) {
  CAIRN_ASSERT(options.is_valid(nullptr) && spin.is_valid(nullptr), "trajectory_with_spin_stop: invalid options");
  const auto [before, after] = split_route(route, spin.at_m);
  TrajectoryOptions once = options;
  once.laps = 1;
  std::vector<TrajectorySample> samples = generate_trajectory(before, once, false);

  // The spin, sampled on the same clock from the arrival sample (at rest) on.
  const TrajectorySample arrival = samples.back();
  const std::int64_t period_ns = std::llround(options.sample_period_s * 1e9);
  const double angle = 2.0 * std::numbers::pi * spin.turns;
  const double duration = spin.duration_s();
  const auto steps = static_cast<std::int64_t>(std::ceil(duration / options.sample_period_s - 1e-9));
  if (event != nullptr) {
    event->first_sample = samples.size() - 1;
    event->start_time_s = arrival.stamp.seconds();
    event->position_world = arrival.T_world_body.translation();
    event->angle_rad = angle;
  }
  double peak = 0.0;
  for (std::int64_t j = 1; j <= steps; ++j) {
    const double time = static_cast<double>(j * period_ns) * 1e-9;
    auto [turned, rate] = trapezoid(time, angle, spin.yaw_rate_rad_s, spin.yaw_acceleration_rad_s2);
    if (j == steps) {  // at rest, whole turns done
      turned = angle;
      rate = 0.0;
    }
    TrajectorySample sample = arrival;
    sample.stamp = core::Timestamp::from_nanoseconds(arrival.stamp.nanoseconds() + j * period_ns);
    sample.T_world_body = core::SE2(arrival.T_world_body.x(), arrival.T_world_body.y(), arrival.T_world_body.angle() + turned);
    sample.speed_mps = 0.0;
    sample.yaw_rate_rad_s = rate;
    peak = std::max(peak, rate);
    samples.push_back(sample);
  }
  if (event != nullptr) {
    event->last_sample = samples.size() - 1;
    event->end_time_s = samples.back().stamp.seconds();
    event->peak_yaw_rate_rad_s = peak;
  }

  // On from the stop: its first sample is the spin's last (at rest, same pose), so it is dropped.
  const std::int64_t offset_ns = samples.back().stamp.nanoseconds() - std::llround(once.start_time_s * 1e9);
  const std::vector<TrajectorySample> rest = generate_trajectory(after, once, false, samples.back().T_world_body.angle());
  for (std::size_t k = 1; k < rest.size(); ++k) {
    TrajectorySample sample = rest[k];
    sample.stamp = core::Timestamp::from_nanoseconds(sample.stamp.nanoseconds() + offset_ns);
    samples.push_back(sample);
  }
  return samples;
}

}  // namespace cairn::sim
