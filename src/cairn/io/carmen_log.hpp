#pragma once
/// \file
/// CARMEN logs (.clf, .log, read directly from .gz / .bz2): the format of the Freiburg SLAM
/// benchmark (Kuemmerle et al. 2009). Records read: PARAM, ODOM, FLASER, RLASER, ROBOTLASER1;
/// '#' comments skipped; other records (SYNC, TRUEPOS, NMEA, ...) counted and reported.
///
///   ODOM x y theta tv rv accel ipc_timestamp ipc_hostname logger_timestamp
///   FLASER n r_1 .. r_n x y theta odom_x odom_y odom_theta ipc_timestamp ipc_hostname logger_timestamp
///   ROBOTLASER1 laser_type start_angle fov resolution max_range accuracy remission_mode
///               n r_1 .. r_n m rem_1 .. rem_m laser_x laser_y laser_theta robot_x robot_y
///               robot_theta tv rv forward_safety side_safety turn_axis ipc_timestamp host logger_ts
///
/// In raw benchmark logs the FLASER pose fields carry odometry (laser pose = odometry pose plus
/// the laser offset). Times are the ipc_timestamp, kept exactly (core::Timestamp), because the
/// benchmark's relations files name scans by it. Records stay in file order: Intel's timestamps
/// go backwards 631 times in file order, which the report counts.

#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "cairn/core/se2.hpp"
#include "cairn/core/time.hpp"

namespace cairn::io {

/// Beam geometry of a scan: beam k points at start_angle_rad + k * angular_resolution_rad in the
/// laser frame (x forward, counter-clockwise positive).
struct LaserGeometry {
  double start_angle_rad = 0.0;
  double angular_resolution_rad = 0.0;
  /// Readings at or beyond this are no-returns; nullopt when the log does not say.
  std::optional<double> max_range_m;
};

struct LaserScan {
  std::string tag;  ///< FLASER, RLASER or ROBOTLASER1
  core::Timestamp time;
  LaserGeometry geometry;
  std::vector<float> ranges_m;
  std::vector<float> remissions;  ///< ROBOTLASER1 only
  core::SE2 T_odom_laser;         ///< laser pose in the odometry frame
  core::SE2 T_odom_robot;         ///< robot (odometry) pose
  std::size_t line = 0;
};

struct OdometryRecord {
  core::Timestamp time;
  core::SE2 T_odom_robot;
  double translational_velocity_mps = 0.0;
  double rotational_velocity_radps = 0.0;
  std::size_t line = 0;
};

struct CarmenLog {
  std::vector<LaserScan> scans;        ///< file order
  std::vector<OdometryRecord> odometry;  ///< file order
  std::map<std::string, std::string> params;
};

struct CarmenReadReport {
  std::map<std::string, std::size_t> records;          ///< read, by tag
  std::map<std::string, std::size_t> unknown_records;  ///< skipped, by tag
  std::size_t comment_lines = 0;
  /// Laser records whose timestamp is smaller than the previous laser record's.
  std::size_t laser_timestamps_backwards = 0;
  std::size_t first_backwards_line = 0;
  /// Where FLASER/RLASER geometry came from: "PARAM" or "default" (see read_carmen_log).
  std::string flaser_geometry_source;
  /// Records skipped as malformed (CarmenReadOptions::skip_malformed_records), and the first
  /// one's message ("file:line: ...").
  std::size_t malformed_records = 0;
  std::string first_malformed;
  std::vector<std::string> warnings;
};

struct CarmenReadOptions {
  /// Refuse unknown record types instead of counting them.
  bool reject_unknown_records = false;
  /// Skip records that fail to parse (counted in the report) instead of stopping at the first.
  /// Unreadable files (binary, compressed wrongly) still stop.
  bool skip_malformed_records = false;
};

/// Reads a CARMEN log. FLASER/RLASER carry no beam angles: they come from the PARAM lines
/// laser_front_laser_fov / _resolution / _start_angle (degrees) and robot_front_laser_max (m)
/// when present (cairn simulate writes them); otherwise the default is a 180 degree field of
/// view starting at -90 degrees with resolution 180 / n degrees for even n (180 beams:
/// -90 .. +89) and 180 / (n - 1) for odd n (181, 361 beams: -90 .. +90), max range unknown.
/// Throws ParseError naming file and line for malformed records (wrong counts, non-numbers,
/// NaN or negative ranges, a beam count that disagrees with the line).
CarmenLog read_carmen_log(const std::string& path, CarmenReadReport* report = nullptr,
                          const CarmenReadOptions& options = {});

/// A time as CARMEN logs write their ipc_timestamp: "<seconds>.<6 digits>", rounded to the
/// microsecond. Precondition: stamp >= 0.
std::string format_carmen_time(core::Timestamp stamp);

}  // namespace cairn::io
