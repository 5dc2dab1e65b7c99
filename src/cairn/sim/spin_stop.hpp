#pragma once
/// \file
/// A stop on the way for a fast turn on the spot by whole turns (the `tunnel-spin-3d` scenario:
/// a spin meant to defeat LiDAR-only registration and be carried by an IMU). The robot drives an open route
/// to the stop point (arriving at rest), spins `turns` full turns counter-clockwise with a
/// trapezoidal yaw-rate profile (ramp up at yaw_acceleration, cruise at yaw_rate, ramp down: the
/// profile of sim/trajectory.hpp's turns on the spot, with its own limits), and drives on.

#include <optional>
#include <string>
#include <vector>

#include "cairn/sim/trajectory.hpp"

namespace cairn::sim {

struct SpinStopOptions {
  /// Where the robot stops, metres along the route from its first point (> 0, before the end).
  double at_m = 115.0;
  /// Full counter-clockwise turns, in [1, 20].
  int turns = 1;
  /// Peak yaw rate, rad/s, in (0, 50] (default 8 rad/s = 458 deg/s).
  double yaw_rate_rad_s = 8.0;
  /// Yaw acceleration of both ramps, rad/s^2, in (0, 1000]. With the defaults one turn takes
  /// 0.985 s and spends 0.67 s at >= 360 deg/s.
  double yaw_acceleration_rad_s2 = 40.0;

  bool is_valid(std::string* why) const;
  /// Duration of the spin, seconds.
  double duration_s() const;
};

/// What the spin was, for the manifest: its first and last ground-truth sample (at rest before
/// and after), their times, where, and the peak rate reached.
struct SpinEvent {
  std::size_t first_sample = 0;
  std::size_t last_sample = 0;
  double start_time_s = 0.0;
  double end_time_s = 0.0;
  Vector2 position_world = Vector2::Zero();
  double angle_rad = 0.0;
  double peak_yaw_rate_rad_s = 0.0;
};

/// The trajectory along the open polyline `route` with the spin at spin.at_m (which must lie
/// strictly inside the route; the route's points up to there, the stop, then the rest). `event`,
/// when given, receives the spin's samples and times. Preconditions: options.is_valid(),
/// spin.is_valid(), at_m shorter than the route.
std::vector<TrajectorySample> trajectory_with_spin_stop(const std::vector<Vector2>& route, const TrajectoryOptions& options,
                                                        const SpinStopOptions& spin, SpinEvent* event = nullptr);

}  // namespace cairn::sim
