#include "cairn/io/carmen_log.hpp"

#include <charconv>
#include <cmath>
#include <numbers>

#include "cairn/core/assert.hpp"
#include "cairn/io/compressed_file.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/text_reader.hpp"

namespace cairn::io {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;

core::Timestamp parse_time(const TextReader& reader, std::string_view token) {
  const auto t = core::Timestamp::parse_seconds(token);
  if (!t) reader.fail("expected an ipc_timestamp in seconds, found " + quote_token(token));
  return *t;
}

std::size_t parse_count(const TextReader& reader, std::string_view token, const char* what) {
  const std::int64_t n = parse_id(reader, token, what);
  if (n > 100000) reader.fail(std::string(what) + " of " + std::to_string(n) + " is implausible: expected at most 100000");
  return static_cast<std::size_t>(n);
}

float parse_range(const TextReader& reader, std::string_view token) {
  const double r = parse_double(reader, token, "a range reading");
  if (r < 0.0) reader.fail("negative range reading " + quote_token(token) + ": expected >= 0");
  return static_cast<float>(r);
}

class Parser {
 public:
  Parser(TextReader& reader, CarmenReadReport& report, const CarmenReadOptions& options)
      : reader_(reader), report_(report), options_(options) {}

  void line(const std::vector<std::string_view>& t) {
    const std::string_view tag = t[0];
    if (tag == "PARAM") return param(t);
    if (tag == "ODOM") return odom(t);
    if (tag == "FLASER" || tag == "RLASER") return flaser(t);
    if (tag == "ROBOTLASER1") return robotlaser(t);
    if (options_.reject_unknown_records) {
      reader_.fail("unknown record type " + quote_token(tag) + ": expected PARAM, ODOM, FLASER, RLASER or ROBOTLASER1");
    }
    ++report_.unknown_records[std::string(tag.substr(0, 40))];
  }

  CarmenLog finish() {
    if (log_.scans.empty() && log_.odometry.empty()) {
      throw ParseError(reader_.path(), 0, "no laser or odometry records: expected a CARMEN log (FLASER, ODOM, ...)");
    }
    // FLASER/RLASER geometry, now that every PARAM has been seen.
    const auto param = [&](const char* name) -> std::optional<double> {
      const auto it = log_.params.find(name);
      if (it == log_.params.end()) return std::nullopt;
      double v = 0.0;
      const auto [ptr, ec] = std::from_chars(it->second.data(), it->second.data() + it->second.size(), v);
      if (ec != std::errc() || ptr != it->second.data() + it->second.size() || !std::isfinite(v)) {
        throw ParseError(reader_.path(), 0, std::string("PARAM ") + name + " is not a number: '" + it->second + "'");
      }
      return v;
    };
    const auto resolution = param("laser_front_laser_resolution");
    const auto start = param("laser_front_laser_start_angle");
    const auto max_range = param("robot_front_laser_max");
    report_.flaser_geometry_source = resolution && start ? "PARAM" : "default";
    for (auto& scan : log_.scans) {
      if (scan.tag == "ROBOTLASER1") continue;
      const std::size_t n = scan.ranges_m.size();
      if (resolution && start) {
        scan.geometry.start_angle_rad = *start * kDegree;
        scan.geometry.angular_resolution_rad = *resolution * kDegree;
      } else {
        scan.geometry.start_angle_rad = -std::numbers::pi / 2.0;
        const double steps = static_cast<double>(n % 2 == 0 ? n : n - 1);
        scan.geometry.angular_resolution_rad = steps > 0.0 ? std::numbers::pi / steps : 0.0;
      }
      scan.geometry.max_range_m = max_range;
    }
    if (report_.laser_timestamps_backwards > 0) {
      report_.warnings.push_back(std::to_string(report_.laser_timestamps_backwards) +
                                 " laser records have a smaller timestamp than the record before them (first at line " +
                                 std::to_string(report_.first_backwards_line) + "); kept in file order");
    }
    for (const auto& [tag, count] : report_.unknown_records) {
      report_.warnings.push_back("skipped " + std::to_string(count) + " unknown " + tag + " record(s)");
    }
    return std::move(log_);
  }

 private:
  void count(std::string_view tag) { ++report_.records[std::string(tag)]; }

  void expect(const std::vector<std::string_view>& t, std::size_t n, const char* layout) const {
    if (t.size() != n) {
      reader_.fail(std::string(t[0]) + " expects " + std::to_string(n - 1) + " fields after the tag (" + layout +
                   "), found " + std::to_string(t.size() - 1));
    }
  }

  void param(const std::vector<std::string_view>& t) {
    if (t.size() < 3) reader_.fail("PARAM expects a name and a value");
    count("PARAM");
    log_.params[std::string(t[1])] = std::string(t[2]);
  }

  void odom(const std::vector<std::string_view>& t) {
    expect(t, 10, "x y theta tv rv accel ipc_timestamp ipc_hostname logger_timestamp");
    count("ODOM");
    OdometryRecord o;
    o.T_odom_robot = core::SE2(parse_double(reader_, t[1], "x"), parse_double(reader_, t[2], "y"),
                               parse_double(reader_, t[3], "theta"));
    o.translational_velocity_mps = parse_double(reader_, t[4], "tv");
    o.rotational_velocity_radps = parse_double(reader_, t[5], "rv");
    parse_double(reader_, t[6], "accel");
    o.time = parse_time(reader_, t[7]);
    o.line = reader_.line_number();
    log_.odometry.push_back(o);
  }

  void add_scan(LaserScan scan) {
    if (last_laser_time_ && scan.time < *last_laser_time_) {
      if (report_.laser_timestamps_backwards++ == 0) report_.first_backwards_line = scan.line;
    }
    last_laser_time_ = scan.time;
    log_.scans.push_back(std::move(scan));
  }

  void flaser(const std::vector<std::string_view>& t) {
    if (t.size() < 2) reader_.fail(std::string(t[0]) + " expects the number of readings after the tag");
    const std::size_t n = parse_count(reader_, t[1], "the number of readings");
    expect(t, 2 + n + 9, "n, n ranges, x y theta odom_x odom_y odom_theta ipc_timestamp ipc_hostname logger_timestamp");
    count(t[0]);
    LaserScan scan;
    scan.tag = std::string(t[0]);
    scan.ranges_m.reserve(n);
    for (std::size_t k = 0; k < n; ++k) scan.ranges_m.push_back(parse_range(reader_, t[2 + k]));
    const std::size_t p = 2 + n;
    scan.T_odom_laser = core::SE2(parse_double(reader_, t[p], "x"), parse_double(reader_, t[p + 1], "y"),
                                  parse_double(reader_, t[p + 2], "theta"));
    scan.T_odom_robot = core::SE2(parse_double(reader_, t[p + 3], "odom_x"), parse_double(reader_, t[p + 4], "odom_y"),
                                  parse_double(reader_, t[p + 5], "odom_theta"));
    scan.time = parse_time(reader_, t[p + 6]);
    scan.line = reader_.line_number();
    add_scan(std::move(scan));
  }

  void robotlaser(const std::vector<std::string_view>& t) {
    constexpr const char* kLayout =
        "laser_type start_angle fov resolution max_range accuracy remission_mode n ranges m remissions laser_x "
        "laser_y laser_theta robot_x robot_y robot_theta tv rv forward_safety side_safety turn_axis ipc_timestamp "
        "ipc_hostname logger_timestamp";
    if (t.size() < 9) reader_.fail(std::string("ROBOTLASER1 is truncated: expected ") + kLayout);
    const std::size_t n = parse_count(reader_, t[8], "the number of readings");
    if (t.size() < 10 + n) reader_.fail(std::string("ROBOTLASER1 is truncated: expected ") + kLayout);
    const std::size_t m = parse_count(reader_, t[9 + n], "the number of remissions");
    expect(t, 10 + n + m + 14, kLayout);
    count("ROBOTLASER1");
    LaserScan scan;
    scan.tag = "ROBOTLASER1";
    scan.geometry.start_angle_rad = parse_double(reader_, t[2], "start_angle");
    scan.geometry.angular_resolution_rad = parse_double(reader_, t[4], "angular_resolution");
    scan.geometry.max_range_m = parse_double(reader_, t[5], "maximum_range");
    scan.ranges_m.reserve(n);
    for (std::size_t k = 0; k < n; ++k) scan.ranges_m.push_back(parse_range(reader_, t[9 + k]));
    for (std::size_t k = 0; k < m; ++k) {
      scan.remissions.push_back(static_cast<float>(parse_double(reader_, t[10 + n + k], "a remission")));
    }
    const std::size_t p = 10 + n + m;
    scan.T_odom_laser = core::SE2(parse_double(reader_, t[p], "laser_x"), parse_double(reader_, t[p + 1], "laser_y"),
                                  parse_double(reader_, t[p + 2], "laser_theta"));
    scan.T_odom_robot = core::SE2(parse_double(reader_, t[p + 3], "robot_x"), parse_double(reader_, t[p + 4], "robot_y"),
                                  parse_double(reader_, t[p + 5], "robot_theta"));
    scan.time = parse_time(reader_, t[p + 11]);
    scan.line = reader_.line_number();
    add_scan(std::move(scan));
  }

  TextReader& reader_;
  CarmenReadReport& report_;
  const CarmenReadOptions& options_;
  CarmenLog log_;
  std::optional<core::Timestamp> last_laser_time_;
};

}  // namespace

CarmenLog read_carmen_log(const std::string& path, CarmenReadReport* report, const CarmenReadOptions& options) {
  CarmenReadReport local;
  CarmenReadReport& out = report != nullptr ? *report : local;
  TextReader reader(path, read_maybe_compressed(path));
  Parser parser(reader, out, options);
  while (reader.next_line()) {
    if (is_blank_or_comment(reader.line())) {
      ++out.comment_lines;
      continue;
    }
    if (!options.skip_malformed_records) {
      parser.line(split_whitespace(reader.line()));
      continue;
    }
    try {
      parser.line(split_whitespace(reader.line()));
    } catch (const ParseError& e) {
      if (out.malformed_records == 0) out.first_malformed = e.what();
      ++out.malformed_records;
    }
  }
  CarmenLog log = parser.finish();
  if (reader.last_line_unterminated()) out.warnings.push_back(reader.unterminated_last_line_warning());
  return log;
}

std::string format_carmen_time(core::Timestamp stamp) {
  CAIRN_ASSERT(stamp.nanoseconds() >= 0, "format_carmen_time: negative time");
  const std::int64_t microseconds = (stamp.nanoseconds() + 500) / 1000;
  std::string fraction = std::to_string(microseconds % 1000000);
  fraction.insert(0, 6 - fraction.size(), '0');
  return std::to_string(microseconds / 1000000) + "." + fraction;
}

}  // namespace cairn::io
