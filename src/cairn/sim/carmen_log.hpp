#pragma once
/// \file
/// Writing CARMEN logs (.clf) as the Freiburg benchmark logs are written (aces.clf, intel.clf):
///
///   # ... the same header comment block as the real logs ...
///   PARAM <name> <value> nohost 0
///   ODOM x y theta tv rv accel ipc_timestamp ipc_hostname logger_timestamp
///   FLASER n r_1 ... r_n x y theta odom_x odom_y odom_theta ipc_timestamp ipc_hostname logger_timestamp
///
/// FLASER carries odometry, not ground truth, in its pose fields, as the raw benchmark logs do:
/// (x, y, theta) is the laser's pose T_odom_laser = T_odom_body * T_body_laser and
/// (odom_x, odom_y, odom_theta) the body's T_odom_body. Times are seconds with six decimals
/// (the real logs' precision; the simulator's times are whole milliseconds, so nothing is lost);
/// ipc_hostname is "nohost"; logger_timestamp is the time since the first record. Ranges and poses
/// are written as the shortest text that reads back to the same double. Records are in time
/// order; an ODOM and a FLASER with the same time are written ODOM first.
///
/// PARAM lines (values as CARMEN's carmen.ini names them; angles in degrees):
///   robot_use_laser on                    simulator_num_readings <beams>
///   robot_frontlaser_offset <m>           robot_rearlaser_offset 0
///   laser_front_laser_fov <deg>           = beams * resolution (180 for the default 180 x 1 deg)
///   laser_front_laser_resolution <deg>    angle between beams
///   laser_front_laser_start_angle <deg>   angle of the first beam (-90 by default)
///   robot_front_laser_max <m>             max range; a reading equal to it means "no return"

#include <string>
#include <vector>

#include "cairn/core/se2.hpp"
#include "cairn/core/time.hpp"
#include "cairn/io/carmen_log.hpp"
#include "cairn/sim/lidar.hpp"

namespace cairn::sim {

struct CarmenOdometry {
  core::Timestamp stamp;
  core::SE2 T_odom_body;
  /// Translational and rotational velocity, m/s and rad/s (CARMEN's tv and rv).
  double speed_mps = 0.0;
  double yaw_rate_rad_s = 0.0;
};

struct CarmenScan {
  core::Timestamp stamp;
  std::vector<double> ranges_m;
  core::SE2 T_odom_laser;
  core::SE2 T_odom_body;
};

struct CarmenLog {
  /// Extra comment lines written after the standard header (without the leading "# ").
  std::vector<std::string> comments;
  /// Laser geometry for the PARAM lines. Every scan must have lidar.beams ranges.
  LidarOptions lidar;
  std::vector<CarmenOdometry> odometry;
  std::vector<CarmenScan> scans;
};

/// "<seconds>.<6 digits>", rounded to the microsecond (io/carmen_log.hpp).
using io::format_carmen_time;

/// Writes `log` to `path` atomically. Throws io::ParseError when the file cannot be written.
void write_carmen(const std::string& path, const CarmenLog& log);

}  // namespace cairn::sim
