#pragma once
/// \file
/// Ground-truth trajectories: a smooth, timed path through waypoints.
///
/// The path is the route's polyline with every corner replaced by a circular arc tangent to
/// both legs (heading is continuous; curvature steps at arc ends), or, for corners sharper
/// than `max_arc_turn_rad`, by a stop and a turn on the spot. Along each stretch between stops
/// the speed follows the classic time-optimal profile under limits: v <= max_speed, yaw rate
/// v / R <= max_yaw_rate on arcs, |dv/dt| <= max_acceleration (a forward pass accelerating from
/// each stop and a backward pass braking into the next; e.g. Lynch & Park, "Modern Robotics",
/// 2017, section 9.4.4). Turns on the spot follow a trapezoidal yaw-rate profile.
/// The robot is a unicycle: it never moves sideways, so T_prev^-1 * T_next has y ~ 0.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "cairn/core/se2.hpp"
#include "cairn/core/time.hpp"

namespace cairn::sim {

struct TrajectoryOptions {
  /// Top forward speed, m/s (> 0).
  double max_speed_mps = 1.0;
  /// Largest |dv/dt|, m/s^2 (> 0); used for both speeding up and braking.
  double max_acceleration_mps2 = 0.5;
  /// Largest yaw rate while driving an arc, rad/s (> 0).
  double max_yaw_rate_rad_s = 0.8;
  /// Radius of the arc replacing a corner, metres (> 0); shrunk where a leg is too short.
  double corner_radius_m = 0.8;
  /// Corners turning more than this (rad, in (0, pi]) become a stop and a turn on the spot.
  double max_arc_turn_rad = 2.0;
  /// Yaw rate and yaw acceleration of turns on the spot, rad/s and rad/s^2 (> 0). "Fast turns"
  /// scenarios raise these and lower max_arc_turn_rad so every corner is a quick spin.
  double spin_yaw_rate_rad_s = 0.8;
  double spin_yaw_acceleration_rad_s2 = 1.5;
  /// How many times the route is driven, in [1, 50]; every lap after the first revisits the world.
  int laps = 2;
  /// Time between ground-truth samples, seconds (>= 0.001). Sensors sample at multiples of it.
  double sample_period_s = 0.01;
  /// Time stamp of the first sample, seconds (>= 0).
  double start_time_s = 0.0;

  /// Checks every field; on failure returns false and writes every problem to `why`.
  bool is_valid(std::string* why) const;
};

/// The robot's state at one instant.
struct TrajectorySample {
  core::Timestamp stamp;
  /// Ground truth body pose in the world frame.
  core::SE2 T_world_body;
  /// Forward speed (m/s) and yaw rate (rad/s) at that instant.
  double speed_mps = 0.0;
  double yaw_rate_rad_s = 0.0;
};

/// Samples every sample_period_s from start to end (at rest at both ends; the last sample is
/// the first multiple of the period at or after arrival). `route` needs >= 2 distinct
/// consecutive points. A closed route ends back at its first point; an open one
/// (`closed_route` false) ends at its last point (with several laps, each lap after the first
/// starts with a leg from the last point back to the first). The robot starts facing the first
/// leg, or, with `start_heading_rad`, facing that way and turning on the spot (the spin
/// profile) to the first leg before it drives: a robot put down somewhere, or a session that
/// starts where another left off. Precondition: options.is_valid().
std::vector<TrajectorySample> generate_trajectory(const std::vector<Vector2>& route, const TrajectoryOptions& options,
                                                  bool closed_route = true,
                                                  std::optional<double> start_heading_rad = std::nullopt);

/// Path length of a sampled trajectory (sum of distances between samples), metres.
double path_length(const std::vector<TrajectorySample>& samples);

}  // namespace cairn::sim
