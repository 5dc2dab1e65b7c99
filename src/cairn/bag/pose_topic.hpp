#pragma once
/// \file
/// A trajectory from a bag topic, as evo's `evo_ape bag` reads one: nav_msgs/Odometry,
/// geometry_msgs/PoseStamped, PoseWithCovarianceStamped or TransformStamped messages, each pose
/// T_frame_child at its header stamp (the frame the messages name; cairn does not chain TF here).
/// Poses come out in the bag's log-time order; stamps must increase strictly, as cairn's
/// trajectory readers require of files.
///
/// Also the `BAG:/topic` form the command line takes for a trajectory argument.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>

#include "cairn/io/trajectory.hpp"

namespace cairn::bag {

class Value;

/// One pose message: its header stamp and T_frame_child as position and (unnormalised) quaternion.
struct StampedPose {
  std::int64_t stamp_ns = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};

/// The pose of a decoded nav_msgs/Odometry, geometry_msgs/TransformStamped, PoseStamped or
/// PoseWithCovarianceStamped (`type` normalised). Throws std::runtime_error for a missing field.
StampedPose pose_of(const std::string& type, const Value& message);

/// Reads `topic` of the bag at `path`. Throws io::ParseError (no such topic, a type that holds no
/// pose, stamps that do not increase, a quaternion of norm 0 or a non-finite value).
io::Trajectory read_pose_topic(const std::string& path, const std::string& topic);

/// Splits "BAG:/topic" into the bag and the topic when the part before the last ":/" is a bag
/// (bag::is_bag); nothing otherwise (a plain file name, which may itself hold ':').
std::optional<std::pair<std::string, std::string>> split_bag_topic(const std::string& argument);

}  // namespace cairn::bag
