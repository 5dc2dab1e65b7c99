#pragma once
/// \file
/// A bag's sensor_msgs/LaserScan topic (with nav_msgs/Odometry when there is one) as the laser
/// log cairn's 2D pipelines replay (io::CarmenLog), so `cairn slam2d BAG` and `cairn localize2d
/// BAG` run the same code as on a CARMEN log.
///
/// Conversion (REP 117 for the ranges): beam k points at angle_min + k * angle_increment;
/// max_range_m = range_max; a reading that is not finite, above range_max or below range_min
/// (drivers write 0 or NaN for no return, +inf for nothing within range) becomes range_max, which
/// the 2D pipelines treat as a no-return, and is counted. Odometry (x, y, yaw of its pose) is
/// interpolated at each scan's stamp; without an odometry topic every scan gets the identity
/// (the scan matcher then works from a zero-motion prior). The laser's offset on the robot
/// comes from /tf_static (odometry child frame -> scan frame) when the bag has it, else identity.

#include <cstddef>
#include <string>
#include <vector>

#include "cairn/io/carmen_log.hpp"

namespace cairn::bag {

struct LaserLogOptions {
  std::string scan_topic;      ///< "" = the only LaserScan topic
  std::string odometry_topic;  ///< "" = the only Odometry topic if there is one; "none" = ignore odometry
};

struct LaserLogReport {
  std::string scan_topic;
  std::string odometry_topic;  ///< "" when none was used
  std::size_t scans = 0;
  std::size_t odometry_messages = 0;
  /// Readings replaced by range_max (not finite, above range_max or below range_min).
  std::size_t readings_as_no_return = 0;
  /// Scans before the first or after the last odometry message (given the nearest odometry pose).
  std::size_t scans_outside_odometry = 0;
  std::string laser_frame;
  /// Where T_robot_laser came from: "tf_static" or "identity".
  std::string laser_offset_source = "identity";
};

/// Reads the bag at `path` (any format bag::Bag opens) into a laser log in stamp order.
/// Throws io::ParseError (no LaserScan topic, several, a message that does not decode).
io::CarmenLog read_laser_log(const std::string& path, const LaserLogOptions& options, LaserLogReport* report = nullptr);

}  // namespace cairn::bag
