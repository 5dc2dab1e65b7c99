#include "cairn/sim/carmen_log.hpp"

#include <cstdint>
#include <numbers>

#include "cairn/core/assert.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/number_format.hpp"

namespace cairn::sim {
namespace {

constexpr double kDegreesPerRadian = 180.0 / std::numbers::pi;

// The header block of aces.clf and intel.clf, line for line.
constexpr const char* kHeader =
    "# message_name [message contents] ipc_timestamp ipc_hostname logger_timestamp\n"
    "# message formats defined: PARAM SYNC ODOM FLASER RLASER TRUEPOS \n"
    "# PARAM param_name param_value\n"
    "# SYNC tagname\n"
    "# ODOM x y theta tv rv accel\n"
    "# FLASER num_readings [range_readings] x y theta odom_x odom_y odom_theta\n"
    "# RLASER num_readings [range_readings] x y theta odom_x odom_y odom_theta\n"
    "# TRUEPOS true_x true_y true_theta odom_x odom_y odom_theta\n";

void append_pose(std::string& line, const core::SE2& T) {
  line += ' ';
  io::append_number(line, T.x());
  line += ' ';
  io::append_number(line, T.y());
  line += ' ';
  io::append_number(line, T.angle());
}

void append_stamps(std::string& line, core::Timestamp stamp, core::Timestamp first) {
  line += ' ';
  line += format_carmen_time(stamp);
  line += " nohost ";
  line += format_carmen_time(core::Timestamp::from_nanoseconds(stamp.nanoseconds() - first.nanoseconds()));
  line += '\n';
}

}  // namespace

void write_carmen(const std::string& path, const CarmenLog& log) {
  core::Timestamp first;
  bool have_first = false;
  for (const auto& o : log.odometry) {
    if (!have_first || o.stamp < first) first = o.stamp;
    have_first = true;
  }
  for (const auto& s : log.scans) {
    if (!have_first || s.stamp < first) first = s.stamp;
    have_first = true;
  }
  io::write_output(path, [&](std::ostream& out) {
    out << kHeader;
    for (const auto& comment : log.comments) out << "# " << comment << '\n';
    std::string line;
    auto param = [&](const char* name, const std::string& value) {
      out << "PARAM " << name << ' ' << value << " nohost 0\n";
    };
    auto number = [](double value) {
      std::string text;
      io::append_number(text, value);
      return text;
    };
    const LidarOptions& lidar = log.lidar;
    param("robot_use_laser", "on");
    param("simulator_num_readings", std::to_string(lidar.beams));
    param("robot_frontlaser_offset", number(lidar.forward_offset_m));
    param("robot_rearlaser_offset", "0");
    param("laser_front_laser_fov", number(lidar.beams * lidar.angle_increment_rad * kDegreesPerRadian));
    param("laser_front_laser_resolution", number(lidar.angle_increment_rad * kDegreesPerRadian));
    param("laser_front_laser_start_angle", number(lidar.angle_min_rad * kDegreesPerRadian));
    param("robot_front_laser_max", number(lidar.max_range_m));

    std::size_t o = 0;
    std::size_t s = 0;
    while (o < log.odometry.size() || s < log.scans.size()) {
      const bool odometry_next =
          s == log.scans.size() || (o < log.odometry.size() && log.odometry[o].stamp <= log.scans[s].stamp);
      line.clear();
      if (odometry_next) {
        const CarmenOdometry& record = log.odometry[o++];
        line += "ODOM";
        append_pose(line, record.T_odom_body);
        line += ' ';
        io::append_number(line, record.speed_mps);
        line += ' ';
        io::append_number(line, record.yaw_rate_rad_s);
        line += " 0";
        append_stamps(line, record.stamp, first);
      } else {
        const CarmenScan& record = log.scans[s++];
        CAIRN_ASSERT(record.ranges_m.size() == static_cast<std::size_t>(lidar.beams),
                     "write_carmen: a scan's range count differs from lidar.beams");
        line += "FLASER ";
        line += std::to_string(record.ranges_m.size());
        for (double r : record.ranges_m) {
          line += ' ';
          io::append_number(line, r);
        }
        append_pose(line, record.T_odom_laser);
        append_pose(line, record.T_odom_body);
        append_stamps(line, record.stamp, first);
      }
      out << line;
    }
  });
}

}  // namespace cairn::sim
