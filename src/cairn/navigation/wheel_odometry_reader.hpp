#pragma once
/// \file
/// Wheel odometry from a bag (`read_wheel_odometry_bag`): nav_msgs/Odometry messages of a topic
/// as the forward speeds GnssInertialOdometry uses (twist.linear.x in the child frame, with
/// twist_covariance[0]) and the poses the odometry integrated itself (T_odom_child, for comparing
/// the fusion with wheel odometry alone).

#include <string>
#include <vector>

#include "cairn/io/trajectory.hpp"
#include "cairn/navigation/gnss_inertial_odometry.hpp"

namespace cairn::navigation {

struct WheelOdometryRecording {
  std::vector<WheelSpeed> speeds;
  io::Trajectory poses;       ///< T_odom_child at the same stamps
  std::string frame_id;       ///< the odometry frame (header.frame_id)
  std::string child_frame_id; ///< the vehicle frame
};

/// Reads the nav_msgs/Odometry messages of `topic` (empty: the bag's only such topic). Throws
/// io::ParseError naming the bag, topic and message for a missing or ambiguous topic, a message
/// that does not decode, a non-finite speed or pose, a quaternion of norm 0, a negative or
/// non-finite speed variance, or header stamps that do not increase.
WheelOdometryRecording read_wheel_odometry_bag(const std::string& bag_path, const std::string& topic = "");

}  // namespace cairn::navigation
