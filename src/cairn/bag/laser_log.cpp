#include "cairn/bag/laser_log.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "cairn/bag/bag.hpp"
#include "cairn/bag/message_decoder.hpp"
#include "cairn/bag/sensor_messages.hpp"
#include "cairn/bag/tf_tree.hpp"
#include "cairn/bag/topic_choice.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::bag {
namespace {

struct OdometrySample {
  std::int64_t stamp_ns = 0;
  core::SE2 T_odom_robot;
};

/// What the stream of the bag gives before poses are assigned.
struct Collected {
  std::vector<io::LaserScan> scans;
  std::vector<OdometrySample> odometry;
  std::string robot_frame;
  TfTree tf;
};

double yaw_of(const Eigen::Quaterniond& q) {
  return std::atan2(2.0 * (q.w() * q.z() + q.x() * q.y()), 1.0 - 2.0 * (q.y() * q.y() + q.z() * q.z()));
}

/// REP 117: a reading outside [range_min, range_max] or not finite carries no return.
io::LaserScan to_log_scan(const LaserScan& scan, std::size_t index, LaserLogReport* report) {
  io::LaserScan out;
  out.tag = "LaserScan";
  out.time = core::Timestamp::from_nanoseconds(scan.header.stamp_ns);
  out.geometry.start_angle_rad = scan.angle_min_rad;
  out.geometry.angular_resolution_rad = scan.angle_increment_rad;
  out.geometry.max_range_m = scan.range_max_m;
  out.ranges_m.reserve(scan.ranges_m.size());
  const auto max_range = static_cast<float>(scan.range_max_m);
  for (const float r : scan.ranges_m) {
    const bool no_return = !std::isfinite(r) || r > max_range || static_cast<double>(r) < scan.range_min_m;
    if (no_return) ++report->readings_as_no_return;
    out.ranges_m.push_back(no_return ? max_range : r);
  }
  out.remissions = scan.intensities;
  out.line = index + 1;
  return out;
}

void check_scan(const LaserScan& scan, const std::string& where) {
  const bool geometry_ok = std::isfinite(scan.angle_min_rad) && std::isfinite(scan.angle_increment_rad) &&
                           scan.angle_increment_rad != 0.0 && std::isfinite(scan.range_max_m) && scan.range_max_m > 0.0;
  if (!geometry_ok || scan.ranges_m.empty()) {
    throw io::ParseError(where, 0, "a LaserScan needs finite angle_min and angle_increment != 0, range_max > 0 and "
                                   "ranges; found angle_increment " + std::to_string(scan.angle_increment_rad) +
                                   ", range_max " + std::to_string(scan.range_max_m) + ", " +
                                   std::to_string(scan.ranges_m.size()) + " ranges");
  }
}

Collected collect(Bag& bag, std::size_t scan_topic, std::optional<std::size_t> odometry_topic, LaserLogReport* report) {
  std::vector<std::size_t> topics{scan_topic};
  if (odometry_topic) topics.push_back(*odometry_topic);
  const std::vector<std::size_t> tf_topics = topics_of_type(bag, {"tf2_msgs/TFMessage", "tf/tfMessage"});
  for (const std::size_t t : tf_topics) {
    if (bag.topics()[t].name == "/tf_static") topics.push_back(t);
  }
  MessageDecoder decoder(bag);
  Collected collected;
  const auto stream = bag.read(topics);
  BagMessage message;
  while (stream->next(&message)) {
    const std::string where = bag.path() + ": " + bag.topics()[message.topic].name + " message " +
                              std::to_string(message.message.log_time_ns) + " ns";
    try {
      const Value value = decoder.decode(message);
      if (message.topic == scan_topic) {
        const LaserScan scan = to_laser_scan(value);
        check_scan(scan, where);
        if (report->laser_frame.empty()) report->laser_frame = scan.header.frame_id;
        collected.scans.push_back(to_log_scan(scan, collected.scans.size(), report));
      } else if (odometry_topic && message.topic == *odometry_topic) {
        const Odometry odometry = to_odometry(value);
        if (collected.robot_frame.empty()) collected.robot_frame = odometry.child_frame_id;
        collected.odometry.push_back({odometry.header.stamp_ns, core::SE2(odometry.position.x(), odometry.position.y(),
                                                                          yaw_of(odometry.orientation))});
      } else {
        for (const TransformStamped& transform : to_tf_message(value)) collected.tf.add(transform, true);
      }
    } catch (const std::runtime_error& e) {
      if (dynamic_cast<const io::ParseError*>(&e) != nullptr) throw;
      throw io::ParseError(where, 0, e.what());
    }
  }
  return collected;
}

/// The odometry pose at `stamp_ns`, interpolated between the samples around it (SE(2) geodesic).
core::SE2 odometry_at(const std::vector<OdometrySample>& odometry, std::int64_t stamp_ns, LaserLogReport* report) {
  const auto after = std::lower_bound(odometry.begin(), odometry.end(), stamp_ns,
                                      [](const OdometrySample& s, std::int64_t t) { return s.stamp_ns < t; });
  if (after == odometry.begin() || after == odometry.end()) {
    if (after == odometry.end() || after->stamp_ns != stamp_ns) ++report->scans_outside_odometry;
    return after == odometry.end() ? odometry.back().T_odom_robot : after->T_odom_robot;
  }
  const OdometrySample& a = *std::prev(after);
  const double s = static_cast<double>(stamp_ns - a.stamp_ns) / static_cast<double>(after->stamp_ns - a.stamp_ns);
  const core::SE2 delta = a.T_odom_robot.inverse() * after->T_odom_robot;
  return a.T_odom_robot * core::SE2::exp(s * delta.log());
}

void assign_poses(Collected* collected, LaserLogReport* report) {
  std::stable_sort(collected->odometry.begin(), collected->odometry.end(),
                   [](const OdometrySample& a, const OdometrySample& b) { return a.stamp_ns < b.stamp_ns; });
  core::SE2 T_robot_laser;
  if (!collected->tf.empty() && !report->laser_frame.empty()) {
    const std::string robot = collected->robot_frame.empty() ? "base_link" : collected->robot_frame;
    if (const auto T = collected->tf.lookup(robot, report->laser_frame, 0)) {
      T_robot_laser = core::SE2(T->translation().x(), T->translation().y(),
                                yaw_of(Eigen::Quaterniond(T->linear())));
      report->laser_offset_source = "tf_static";
    }
  }
  for (io::LaserScan& scan : collected->scans) {
    scan.T_odom_robot = collected->odometry.empty() ? core::SE2() : odometry_at(collected->odometry, scan.time.nanoseconds(), report);
    scan.T_odom_laser = scan.T_odom_robot * T_robot_laser;
  }
}

}  // namespace

io::CarmenLog read_laser_log(const std::string& path, const LaserLogOptions& options, LaserLogReport* report) {
  LaserLogReport local;
  LaserLogReport& r = report != nullptr ? *report : local;
  r = {};
  Bag bag = Bag::open(path);
  const std::size_t scan_topic =
      choose_topic(bag, options.scan_topic, {{"sensor_msgs/LaserScan"}, "laser scan", "--scan-topic"});
  const std::optional<std::size_t> odometry_topic =
      choose_optional_topic(bag, options.odometry_topic, {{"nav_msgs/Odometry"}, "odometry", "--odom-topic"});
  r.scan_topic = bag.topics()[scan_topic].name;
  if (odometry_topic) r.odometry_topic = bag.topics()[*odometry_topic].name;
  Collected collected = collect(bag, scan_topic, odometry_topic, &r);
  assign_poses(&collected, &r);
  r.scans = collected.scans.size();
  r.odometry_messages = collected.odometry.size();
  io::CarmenLog log;
  log.scans = std::move(collected.scans);
  return log;
}

}  // namespace cairn::bag
