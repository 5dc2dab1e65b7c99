#include "cairn/cli/commands.hpp"

#include "cairn/bag/bag.hpp"
#include "cairn/bag/laser_log.hpp"

#include <limits>

#include "cairn/cli/flag_checks.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::cli {

void LogReplayFlags::add_to(CLI::App& command) {
  command.add_option("--max-scans", max_scans, "Process only the first N scans")->check(checks::count(std::numeric_limits<long>::max()));
  command.add_flag("--lenient", lenient, "Skip malformed log records (counted) instead of stopping");
  command.add_flag("-q,--quiet", quiet, "Print nothing on success");
  command.add_flag("--progress", progress, "Progress as a line every 200 scans on stderr, also when stderr is not a terminal");
  command.add_option("--scan-topic", scan_topic, "Bag input: the sensor_msgs/LaserScan topic (default: the only one)");
  command.add_option("--odom-topic", odometry_topic,
                     "Bag input: the nav_msgs/Odometry topic (default: the only one, if any; 'none' to ignore odometry)");
  command.add_flag("--overwrite", overwrite,
                   "Write into an --out directory that already holds files (those of the same names are replaced)");
}

io::CarmenLog LogReplayFlags::read_log(const std::string& path, io::CarmenReadReport* report) const {
  if (bag::is_bag(path)) return read_bag(path, report);
  if (!scan_topic.empty() || !odometry_topic.empty()) {
    throw UsageError("--scan-topic and --odom-topic go with a bag, and " + path + " is not one");
  }
  io::CarmenReadOptions options;
  options.skip_malformed_records = lenient;
  io::CarmenLog log = io::read_carmen_log(path, report, options);
  if (log.scans.empty()) throw io::ParseError(path, 0, "no laser records (FLASER, RLASER, ROBOTLASER1) in the log");
  return log;
}

io::CarmenLog LogReplayFlags::read_bag(const std::string& path, io::CarmenReadReport* report) const {
  bag::LaserLogReport bag_report;
  io::CarmenLog log = bag::read_laser_log(path, {scan_topic, odometry_topic}, &bag_report);
  if (log.scans.empty()) throw io::ParseError(path, 0, "topic " + bag_report.scan_topic + " holds no message");
  if (report != nullptr) {
    report->records["LaserScan"] = bag_report.scans;
    if (!bag_report.odometry_topic.empty()) report->records["Odometry"] = bag_report.odometry_messages;
    report->warnings.push_back("bag: scans from " + bag_report.scan_topic + ", odometry from " +
                               (bag_report.odometry_topic.empty() ? "none (zero-motion prior)" : bag_report.odometry_topic) +
                               ", laser offset from " + bag_report.laser_offset_source + "; " +
                               std::to_string(bag_report.readings_as_no_return) + " readings taken as no-return");
  }
  return log;
}

}  // namespace cairn::cli
