// CARMEN logs: the Freiburg benchmark logs read directly from .bz2 with the counts of their
// SOURCE.txt census, relations timestamps that match scan timestamps exactly, and malformed
// input refused with file and line.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "cairn/io/carmen_log.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/text_reader.hpp"
#include "graph_test_utils.hpp"
#include "test_data.hpp"

namespace cairn::io {
namespace {

TEST(CarmenRealData, AcesMatchesItsCensus) {
  CAIRN_REQUIRE_DATA("laser2d/aces/aces.clf.bz2");
  CarmenReadReport report;
  const CarmenLog log = read_carmen_log(test::data_path("laser2d/aces/aces.clf.bz2").string(), &report);
  // laser2d/aces/SOURCE.txt: FLASER 7374, ODOM 7375, PARAM 4, comment 9; 180 beams; first and
  // last laser timestamps 70.289900 and 1435.809999; largest reading 50.000.
  EXPECT_EQ(report.records["FLASER"], 7374u);
  EXPECT_EQ(report.records["ODOM"], 7375u);
  EXPECT_EQ(report.records["PARAM"], 4u);
  EXPECT_EQ(report.comment_lines, 9u);
  ASSERT_EQ(log.scans.size(), 7374u);
  EXPECT_EQ(log.scans.front().time, *core::Timestamp::parse_seconds("70.289900"));
  EXPECT_EQ(log.scans.back().time, *core::Timestamp::parse_seconds("1435.809999"));
  float largest = 0.0f;
  for (const auto& s : log.scans) {
    ASSERT_EQ(s.ranges_m.size(), 180u);
    largest = std::max(largest, *std::max_element(s.ranges_m.begin(), s.ranges_m.end()));
  }
  EXPECT_FLOAT_EQ(largest, 50.0f);
  EXPECT_EQ(report.laser_timestamps_backwards, 0u);
  EXPECT_EQ(report.flaser_geometry_source, "default");
  EXPECT_NEAR(log.scans[0].geometry.start_angle_rad, -M_PI / 2, 1e-15);
  EXPECT_NEAR(log.scans[0].geometry.angular_resolution_rad, M_PI / 180, 1e-15);

  // Every timestamp of the relations file names a scan exactly (SOURCE.txt says so).
  std::set<core::Timestamp> times;
  for (const auto& s : log.scans) times.insert(s.time);
  TextReader relations(test::data_path("laser2d/aces/aces.relations").string());
  std::size_t checked = 0;
  while (relations.next_line()) {
    const auto t = split_whitespace(relations.line());
    if (t.size() < 2) continue;
    ASSERT_TRUE(times.contains(*core::Timestamp::parse_seconds(t[0]))) << relations.line_number();
    ASSERT_TRUE(times.contains(*core::Timestamp::parse_seconds(t[1]))) << relations.line_number();
    ++checked;
  }
  EXPECT_EQ(checked, 1279u);
}

TEST(CarmenRealData, IntelTimestampsGoBackwards631Times) {
  CAIRN_REQUIRE_DATA("laser2d/intel/intel.clf.bz2");
  CarmenReadReport report;
  const CarmenLog log = read_carmen_log(test::data_path("laser2d/intel/intel.clf.bz2").string(), &report);
  EXPECT_EQ(report.records["FLASER"], 13631u);
  EXPECT_EQ(report.records["ODOM"], 26915u);
  EXPECT_EQ(report.laser_timestamps_backwards, 631u);  // intel/SOURCE.txt
  EXPECT_EQ(log.scans.front().time, *core::Timestamp::parse_seconds("976052857.337530"));
}

TEST(CarmenRealData, MitCsailHas361BeamsOverHalfACircle) {
  CAIRN_REQUIRE_DATA("laser2d/mit-csail/mit-csail.clf.bz2");
  const CarmenLog log = read_carmen_log(test::data_path("laser2d/mit-csail/mit-csail.clf.bz2").string());
  ASSERT_EQ(log.scans.size(), 1988u);
  EXPECT_TRUE(log.odometry.empty());
  const auto& g = log.scans[0].geometry;
  EXPECT_EQ(log.scans[0].ranges_m.size(), 361u);
  EXPECT_NEAR(g.start_angle_rad + 360 * g.angular_resolution_rad, M_PI / 2, 1e-12);
}

const char* kLog =
    "# a comment\n"
    "PARAM laser_front_laser_fov 4 nohost 0\n"
    "PARAM laser_front_laser_resolution 1 nohost 0\n"
    "PARAM laser_front_laser_start_angle -2 nohost 0\n"
    "PARAM robot_front_laser_max 30 nohost 0\n"
    "ODOM 1 2 0.5 0.1 0.2 0 10.5 nohost 0.1\n"
    "FLASER 4 1.5 2 30 0.25 1 2 0.5 1 2 0.5 10.55 nohost 0.15\n"
    "SYNC x 10.6 nohost 0.2\n"
    "ROBOTLASER1 0 -1.5 3.0 1.0 20 0.01 0 3 1 2 3 0 1 2 0.5 1 2 0.5 0 0 0 0 0 10.7 nohost 0.3\n";

TEST(CarmenReader, ReadsEveryRecordKind) {
  CarmenReadReport report;
  const CarmenLog log = read_carmen_log(test::temp_file("small.clf", kLog), &report);
  ASSERT_EQ(log.scans.size(), 2u);
  ASSERT_EQ(log.odometry.size(), 1u);
  EXPECT_EQ(log.odometry[0].T_odom_robot.angle(), 0.5);
  EXPECT_EQ(log.odometry[0].time, *core::Timestamp::parse_seconds("10.5"));
  const LaserScan& f = log.scans[0];
  EXPECT_EQ(f.ranges_m, (std::vector<float>{1.5f, 2.0f, 30.0f, 0.25f}));
  EXPECT_NEAR(f.geometry.start_angle_rad, -2 * M_PI / 180, 1e-15);
  EXPECT_NEAR(f.geometry.angular_resolution_rad, M_PI / 180, 1e-15);
  EXPECT_EQ(f.geometry.max_range_m, 30.0);
  EXPECT_EQ(report.flaser_geometry_source, "PARAM");
  const LaserScan& r = log.scans[1];
  EXPECT_EQ(r.tag, "ROBOTLASER1");
  EXPECT_EQ(r.geometry.start_angle_rad, -1.5);
  EXPECT_EQ(r.geometry.max_range_m, 20.0);
  EXPECT_EQ(r.ranges_m.size(), 3u);
  EXPECT_EQ(r.time, *core::Timestamp::parse_seconds("10.7"));
  EXPECT_EQ(report.unknown_records["SYNC"], 1u);
  CarmenReadOptions strict;
  strict.reject_unknown_records = true;
  EXPECT_THROW(read_carmen_log(test::temp_file("small2.clf", kLog), nullptr, strict), ParseError);
}

void expect_error(const std::string& name, const std::string& content, std::size_t line, const std::string& phrase) {
  const std::string path = test::temp_file(name, content);
  try {
    read_carmen_log(path);
    ADD_FAILURE() << name << ": expected ParseError containing " << phrase;
  } catch (const ParseError& e) {
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_NE(std::string(e.what()).find(phrase), std::string::npos) << e.what();
  }
}

TEST(CarmenReader, RefusesMalformedRecords) {
  expect_error("c1.clf", "FLASER 4 1 2 3 0 0 0 0 0 0 1.0 nohost 0\n", 1, "FLASER expects 14 fields after the tag");
  expect_error("c2.clf", "FLASER 2 nan 2 0 0 0 0 0 0 1.0 nohost 0\n", 1, "expected a finite number for a range reading");
  expect_error("c3.clf", "FLASER 2 -1 2 0 0 0 0 0 0 1.0 nohost 0\n", 1, "negative range reading");
  expect_error("c4.clf", "ODOM 1 2 3 0 0 0 abc nohost 0\n", 1, "expected an ipc_timestamp");
  expect_error("c5.clf", "FLASER 99999999 1\n", 1, "implausible");
  expect_error("c6.clf", "", 0, "no laser or odometry records");
  const std::string binary("ODOM 1 2 3 0 0 0 1.0 nohost 0\nFLASER 2 1 2\0\x01 0 0 0 0 0 0 1.0 nohost 0\n", 70);
  expect_error("c7.clf", binary, 2, "binary data");
}

TEST(CarmenReader, RefusesTruncatedCompressedData) {
  CAIRN_REQUIRE_DATA("laser2d/aces/aces.clf.bz2");
  std::ifstream in(test::data_path("laser2d/aces/aces.clf.bz2"), std::ios::binary);
  std::ostringstream buffer;
  buffer << in.rdbuf();
  std::string bytes = buffer.str();
  bytes.resize(bytes.size() / 2);
  const std::string path = test::temp_file("truncated.clf.bz2", bytes);
  try {
    read_carmen_log(path);
    FAIL() << "expected ParseError";
  } catch (const ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("bzip2 data is corrupt or truncated"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace cairn::io
