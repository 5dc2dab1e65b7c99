#pragma once
/// \file
/// A motion prediction handed to the odometry from outside (an IMU's, lidar3d/inertial_fusion.hpp):
/// the sensor's pose at instants that span a sweep. The odometry takes its prediction for the
/// registration from it instead of the constant-velocity model, and deskews every point by the
/// pose at the point's own time (p -> T_world_sensor(t_mid)^-1 T_world_sensor(t_point) p), as
/// LIO-SAM's imageProjection and FAST-LIO2's backward propagation do with the IMU's poses.

#include <vector>

#include "cairn/core/se3.hpp"

namespace cairn::lidar3d {

struct MotionPrior {
  /// Strictly increasing, seconds (the scans' clock); at least one.
  std::vector<double> times_s;
  /// T_world_sensor at each of times_s, in the odometry's world frame.
  std::vector<core::SE3> T_world_sensor;

  /// The pose at `time_s`: interpolated between the neighbouring samples (slerp and linear),
  /// held at the first or last sample outside their span. Precondition: not empty.
  core::SE3 at(double time_s) const;
  /// Whether time_s lies within [times_s.front(), times_s.back()].
  bool covers(double time_s) const;
};

}  // namespace cairn::lidar3d
