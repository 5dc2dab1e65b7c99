// Files written by the simulator read back to the same data; the same seed gives the same bytes.
// The CARMEN reader here is deliberately minimal (the full one belongs to slam2d); it checks the
// line layout of the Freiburg logs: FLASER n r_1..r_n x y theta odom_x odom_y odom_theta
// ipc_timestamp ipc_hostname logger_timestamp.

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <numbers>
#include <set>
#include <sstream>

#include "cairn/io/graph_io.hpp"
#include "cairn/io/trajectory.hpp"
#include "cairn/sim/carmen_log.hpp"
#include "cairn/sim/scenario.hpp"
#include "test_data.hpp"

namespace cairn::sim {
namespace {

namespace fs = std::filesystem;
using core::SE2;

fs::path scratch_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("cairn_test_sim_" + std::to_string(::getpid())) / name;
  fs::create_directories(dir);
  return dir;
}

class RemoveScratchDir : public ::testing::Environment {
 public:
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(fs::temp_directory_path() / ("cairn_test_sim_" + std::to_string(::getpid())), ignored);
  }
};
[[maybe_unused]] const auto* const kCleanup = ::testing::AddGlobalTestEnvironment(new RemoveScratchDir);

std::vector<std::string> tokens(const std::string& line) {
  std::istringstream in(line);
  return {std::istream_iterator<std::string>(in), std::istream_iterator<std::string>()};
}

double number(const std::string& text) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  EXPECT_EQ(*end, '\0') << "not a number: " << text;
  return value;
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

struct ParsedScan {
  std::string time_text;
  std::vector<double> ranges;
  double laser[3];
  double odom[3];
};
struct ParsedOdometry {
  std::string time_text;
  double pose[3];
  double tv = 0.0;
  double rv = 0.0;
};
struct ParsedLog {
  std::map<std::string, std::string> params;
  std::vector<ParsedScan> scans;
  std::vector<ParsedOdometry> odometry;
  std::vector<std::string> header;
};

ParsedLog read_carmen_minimal(const fs::path& path) {
  ParsedLog log;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.starts_with("#")) {
      log.header.push_back(line);
      continue;
    }
    const auto t = tokens(line);
    EXPECT_FALSE(t.empty());
    if (t[0] == "PARAM") {
      EXPECT_EQ(t.size(), 5u) << line;
      EXPECT_EQ(t[3], "nohost");
      EXPECT_EQ(t[4], "0");
      log.params[t[1]] = t[2];
    } else if (t[0] == "ODOM") {
      EXPECT_EQ(t.size(), 10u) << line;
      EXPECT_EQ(t[8], "nohost");
      log.odometry.push_back({t[7], {number(t[1]), number(t[2]), number(t[3])}, number(t[4]), number(t[5])});
      EXPECT_EQ(t[6], "0") << "accel";
    } else if (t[0] == "FLASER") {
      const std::size_t n = static_cast<std::size_t>(std::stoul(t[1]));
      EXPECT_EQ(t.size(), 2 + n + 6 + 3) << "FLASER field count";
      ParsedScan scan;
      for (std::size_t i = 0; i < n; ++i) scan.ranges.push_back(number(t[2 + i]));
      for (int i = 0; i < 3; ++i) scan.laser[i] = number(t[2 + n + i]);
      for (int i = 0; i < 3; ++i) scan.odom[i] = number(t[2 + n + 3 + i]);
      scan.time_text = t[2 + n + 6];
      EXPECT_EQ(t[2 + n + 7], "nohost");
      log.scans.push_back(scan);
    } else {
      ADD_FAILURE() << "unexpected record: " << t[0];
    }
  }
  return log;
}

/// One small run, shared by the tests of this file (0.1 s of simulation).
struct SimulatedRun {
  Scenario scenario;
  SimulationResult result;
  fs::path dir;
  std::vector<std::string> files;
};

const SimulatedRun& office_run() {
  static const SimulatedRun run = [] {
    SimulatedRun r;
    r.scenario = *make_scenario("office");
    r.scenario.trajectory.laps = 1;
    r.scenario.lidar.forward_offset_m = 0.25;  // so laser and odometry poses differ
    r.scenario.graph.false_loops = 5;
    r.result = simulate(r.scenario, 42);
    r.dir = scratch_dir("office");
    r.files = write_outputs(r.result, r.scenario, 42, r.dir.string());
    return r;
  }();
  return run;
}

TEST(CarmenLog, WrittenLogReadsBackToTheSimulatedData) {
  const SimulatedRun& run = office_run();
  const ParsedLog log = read_carmen_minimal(run.dir / "log.clf");
  // The header of aces.clf / intel.clf, then our comment.
  ASSERT_GE(log.header.size(), 9u);
  EXPECT_EQ(log.header[0], "# message_name [message contents] ipc_timestamp ipc_hostname logger_timestamp");
  EXPECT_EQ(log.header[5], "# FLASER num_readings [range_readings] x y theta odom_x odom_y odom_theta");

  EXPECT_EQ(log.params.at("robot_frontlaser_offset"), "0.25");
  EXPECT_EQ(log.params.at("laser_front_laser_fov"), "180");
  EXPECT_EQ(log.params.at("laser_front_laser_resolution"), "1");
  EXPECT_EQ(log.params.at("laser_front_laser_start_angle"), "-90");
  EXPECT_EQ(log.params.at("robot_front_laser_max"), "30");

  const SimulationResult& result = run.result;
  ASSERT_EQ(log.scans.size(), result.scans.size());
  for (std::size_t i = 0; i < log.scans.size(); ++i) {
    const std::size_t k = result.scan_samples[i];
    const ParsedScan& scan = log.scans[i];
    ASSERT_EQ(scan.ranges, result.scans[i]) << "scan " << i;  // bit for bit
    const SE2& odom = result.odometry.poses[k];
    EXPECT_EQ(scan.odom[0], odom.x());
    EXPECT_EQ(scan.odom[1], odom.y());
    EXPECT_EQ(scan.odom[2], odom.angle());
    // The laser pose is the odometry pose moved 0.25 m forward along its heading.
    EXPECT_NEAR(scan.laser[0], odom.x() + 0.25 * std::cos(odom.angle()), 1e-12);
    EXPECT_NEAR(scan.laser[1], odom.y() + 0.25 * std::sin(odom.angle()), 1e-12);
    EXPECT_EQ(scan.laser[2], odom.angle());
    EXPECT_EQ(core::Timestamp::parse_seconds(scan.time_text), result.truth[k].stamp) << scan.time_text;
  }
  ASSERT_EQ(log.odometry.size(), result.odometry_samples.size());
  for (std::size_t i = 0; i < log.odometry.size(); ++i) {
    const std::size_t k = result.odometry_samples[i];
    EXPECT_EQ(log.odometry[i].pose[0], result.odometry.poses[k].x());
    EXPECT_EQ(log.odometry[i].pose[2], result.odometry.poses[k].angle());
    EXPECT_EQ(core::Timestamp::parse_seconds(log.odometry[i].time_text), result.truth[k].stamp);
  }
}

TEST(CarmenLog, VelocitiesAgreeWithConsecutiveOdometryPoses) {
  const ParsedLog log = read_carmen_minimal(office_run().dir / "log.clf");
  ASSERT_GT(log.odometry.size(), 2u);
  EXPECT_EQ(log.odometry[0].tv, 0.0);
  for (std::size_t i = 1; i < log.odometry.size(); ++i) {
    const auto& a = log.odometry[i - 1];
    const auto& b = log.odometry[i];
    const double dt = number(b.time_text) - number(a.time_text);
    const SE2 motion = SE2(a.pose[0], a.pose[1], a.pose[2]).inverse() * SE2(b.pose[0], b.pose[1], b.pose[2]);
    EXPECT_NEAR(b.tv * dt, motion.x(), 1e-9) << "record " << i;
    EXPECT_NEAR(b.rv * dt, motion.angle(), 1e-9) << "record " << i;
  }
}

TEST(CarmenLog, TimeFormatHasSixDecimals) {
  EXPECT_EQ(format_carmen_time(core::Timestamp::from_nanoseconds(0)), "0.000000");
  EXPECT_EQ(format_carmen_time(core::Timestamp::from_nanoseconds(70289900000)), "70.289900");
  EXPECT_EQ(format_carmen_time(core::Timestamp::from_nanoseconds(976052857337530000)), "976052857.337530");
  EXPECT_EQ(format_carmen_time(core::Timestamp::from_nanoseconds(1999999)), "0.002000");  // rounded
}

TEST(GroundTruth, TumFileHoldsTheTruthAtEveryScan) {
  const SimulatedRun& run = office_run();
  const io::Trajectory truth = io::read_tum((run.dir / "ground_truth.tum").string());
  ASSERT_EQ(truth.size(), run.result.scan_samples.size());
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const TrajectorySample& s = run.result.truth[run.result.scan_samples[i]];
    EXPECT_EQ(truth.stamps[i], s.stamp);
    EXPECT_EQ(truth.poses[i].translation().x(), s.T_world_body.x());
    EXPECT_EQ(truth.poses[i].translation().y(), s.T_world_body.y());
    EXPECT_EQ(truth.poses[i].translation().z(), 0.0);
    const Quaternion& q = truth.poses[i].unit_quaternion();
    EXPECT_NEAR(std::remainder(2.0 * std::atan2(q.z(), q.w()) - s.T_world_body.angle(), 2 * std::numbers::pi), 0.0, 1e-12);
  }
}

TEST(Relations, FileMatchesTheGroundTruthAndTheLogTimes) {
  const SimulatedRun& run = office_run();
  const ParsedLog log = read_carmen_minimal(run.dir / "log.clf");
  std::set<std::string> scan_times;
  for (const auto& scan : log.scans) scan_times.insert(scan.time_text);
  const io::Trajectory truth = io::read_tum((run.dir / "ground_truth.tum").string());
  std::map<core::Timestamp, core::SE3> by_time;
  for (std::size_t i = 0; i < truth.size(); ++i) by_time[truth.stamps[i]] = truth.poses[i];

  std::ifstream in(run.dir / "log.relations");
  std::string line;
  std::size_t count = 0;
  std::size_t long_ones = 0;
  while (std::getline(in, line)) {
    const auto t = tokens(line);
    ASSERT_EQ(t.size(), 8u) << line;  // t_i t_j x y z roll pitch yaw, as aces.relations
    EXPECT_TRUE(scan_times.contains(t[0])) << t[0];
    EXPECT_TRUE(scan_times.contains(t[1])) << t[1];
    EXPECT_EQ(number(t[4]), 0.0);
    EXPECT_EQ(number(t[5]), 0.0);
    EXPECT_EQ(number(t[6]), 0.0);
    const auto from = core::Timestamp::parse_seconds(t[0]);
    const auto to = core::Timestamp::parse_seconds(t[1]);
    ASSERT_TRUE(from && to);
    EXPECT_LT(*from, *to);
    if ((*to).seconds() - (*from).seconds() > 29.0) ++long_ones;
    // Independent path: the relation from the TUM ground truth, through SE(3).
    const core::SE3 T = by_time.at(*from).inverse() * by_time.at(*to);
    EXPECT_NEAR(number(t[2]), T.translation().x(), 1e-9);
    EXPECT_NEAR(number(t[3]), T.translation().y(), 1e-9);
    const Quaternion& q = T.unit_quaternion();
    EXPECT_NEAR(std::remainder(number(t[7]) - 2.0 * std::atan2(q.z(), q.w()), 2 * std::numbers::pi), 0.0, 1e-9);
    ++count;
  }
  EXPECT_EQ(count, run.result.relations.size());
  EXPECT_GT(count, 100u);
  EXPECT_GT(long_ones, 10u);  // one lap still revisits the ring corridor's start
}

TEST(Relations, SameLineLayoutAsTheBenchmarkFile) {
  CAIRN_REQUIRE_DATA("laser2d/aces/aces.relations");
  std::ifstream in(test::data_path("laser2d/aces/aces.relations"));
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  const auto theirs = tokens(line);
  std::ifstream ours_in(office_run().dir / "log.relations");
  ASSERT_TRUE(std::getline(ours_in, line));
  const auto ours = tokens(line);
  ASSERT_EQ(ours.size(), theirs.size());
  // Times with six decimals, as theirs.
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(theirs[i].size() - theirs[i].find('.'), 7u);
    EXPECT_EQ(ours[i].size() - ours[i].find('.'), 7u);
  }
}

TEST(PoseGraph, G2oFileReadsBackAndMeasurementsAreConsistentWithTheirInformation) {
  const SimulatedRun& run = office_run();
  const io::GraphFile file = io::read_graph((run.dir / "graph.g2o").string());
  const auto& graph = std::get<io::PoseGraph2D>(file.graph);
  const SimulatedGraph& sim = run.result.graph;
  ASSERT_EQ(graph.vertices.size(), sim.truth.size());
  ASSERT_EQ(graph.edges.size(), sim.graph.edges.size());
  EXPECT_EQ(graph.fixed, std::vector<std::int64_t>{0});
  const io::Trajectory nodes = io::read_tum((run.dir / "graph_nodes.tum").string());
  ASSERT_EQ(nodes.size(), sim.truth.size());

  // Normalised squared error of each odometry edge against the truth is chi^2 with 3 degrees
  // of freedom: mean 3, variance 6.
  double sum = 0.0;
  std::size_t odometry_edges = 0;
  std::size_t false_edges = 0;
  std::set<std::pair<std::int64_t, std::int64_t>> false_pairs;
  for (const auto& loop : sim.loops) {
    if (loop.is_false) false_pairs.insert({loop.from, loop.to});
  }
  for (const auto& edge : graph.edges) {
    const SE2 truth = sim.truth[static_cast<std::size_t>(edge.from)].inverse() * sim.truth[static_cast<std::size_t>(edge.to)];
    const Vector3 xi = (truth.inverse() * edge.T_from_to).log();
    const double chi2 = xi.dot(edge.information * xi);
    if (edge.to == edge.from + 1) {
      sum += chi2;
      ++odometry_edges;
    } else if (false_pairs.contains({edge.from, edge.to})) {
      ++false_edges;
      EXPECT_GT(chi2, 100.0);  // a false loop is far from the truth in its own metric
    } else {
      EXPECT_LT(chi2, 40.0);  // a true loop: chi^2_3 beyond 40 has probability ~1e-8
    }
  }
  ASSERT_GT(odometry_edges, 100u);
  const double n = static_cast<double>(odometry_edges);
  EXPECT_NEAR(sum / n, 3.0, 5.0 * std::sqrt(6.0 / n));
  EXPECT_EQ(false_edges, 5u);

  // loop_closures.csv lists the same loops.
  std::ifstream in(run.dir / "loop_closures.csv");
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "from,to,kind");
  std::size_t rows = 0;
  while (std::getline(in, line)) ++rows;
  EXPECT_EQ(rows, sim.loops.size());
}

TEST(WorldFile, ListsEveryWallAndCircleExactly) {
  const SimulatedRun& run = office_run();
  const World& world = run.result.world.world;
  std::ifstream in(run.dir / "world.txt");
  std::string line;
  std::size_t walls = 0;
  std::size_t circles = 0;
  while (std::getline(in, line)) {
    if (line.starts_with("#")) continue;
    const auto t = tokens(line);
    if (t[0] == "WALL") {
      ASSERT_EQ(t.size(), 5u);
      const Segment& wall = world.walls.at(walls++);
      EXPECT_EQ(number(t[1]), wall.a.x());
      EXPECT_EQ(number(t[2]), wall.a.y());
      EXPECT_EQ(number(t[3]), wall.b.x());
      EXPECT_EQ(number(t[4]), wall.b.y());
    } else if (t[0] == "CIRCLE") {
      ASSERT_EQ(t.size(), 4u);
      const Circle& circle = world.circles.at(circles++);
      EXPECT_EQ(number(t[1]), circle.center.x());
      EXPECT_EQ(number(t[3]), circle.radius_m);
    } else {
      ADD_FAILURE() << "unexpected line: " << line;  // the office run has no landmarks or people
    }
  }
  EXPECT_EQ(walls, world.walls.size());
  EXPECT_EQ(circles, world.circles.size());
}

TEST(Determinism, SameSeedGivesIdenticalBytesAndAnotherSeedDoesNot) {
  Scenario scenario = *make_scenario("corridor-aliasing");
  scenario.trajectory.laps = 1;
  scenario.graph.false_loops = 3;
  const fs::path a = scratch_dir("det_a");
  const fs::path b = scratch_dir("det_b");
  const fs::path c = scratch_dir("det_c");
  const auto files = write_outputs(simulate(scenario, 7), scenario, 7, a.string());
  write_outputs(simulate(scenario, 7), scenario, 7, b.string());
  write_outputs(simulate(scenario, 8), scenario, 8, c.string());
  ASSERT_FALSE(files.empty());
  for (const auto& name : files) {
    const std::string bytes = read_file(a / name);
    EXPECT_FALSE(bytes.empty()) << name;
    EXPECT_EQ(bytes, read_file(b / name)) << name << " differs between two runs with seed 7";
  }
  EXPECT_NE(read_file(a / "log.clf"), read_file(c / "log.clf"));
  EXPECT_NE(read_file(a / "graph.g2o"), read_file(c / "graph.g2o"));
  // The world and the ground truth do not depend on the noise seed.
  EXPECT_EQ(read_file(a / "ground_truth.tum"), read_file(c / "ground_truth.tum"));
}

TEST(Landmarks, ObservationFileReadsBack) {
  Scenario scenario = *make_scenario("landmarks");
  scenario.trajectory.laps = 1;
  const SimulationResult result = simulate(scenario, 3);
  const fs::path dir = scratch_dir("landmarks");
  const auto files = write_outputs(result, scenario, 3, dir.string());
  ASSERT_FALSE(result.landmark_observations.empty());

  std::ifstream map_in(dir / "landmarks.csv");
  std::string line;
  std::getline(map_in, line);
  EXPECT_EQ(line, "id,x_m,y_m");
  std::size_t i = 0;
  while (std::getline(map_in, line)) {
    std::replace(line.begin(), line.end(), ',', ' ');
    const auto t = tokens(line);
    ASSERT_EQ(t.size(), 3u);
    const Landmark& landmark = result.world.world.landmarks.at(i++);
    EXPECT_EQ(std::stoll(t[0]), landmark.id);
    EXPECT_EQ(number(t[1]), landmark.position.x());
    EXPECT_EQ(number(t[2]), landmark.position.y());
  }
  EXPECT_EQ(i, result.world.world.landmarks.size());

  std::ifstream in(dir / "landmark_observations.csv");
  std::getline(in, line);
  EXPECT_EQ(line, "time_s,landmark_id,range_m,bearing_rad");
  i = 0;
  while (std::getline(in, line)) {
    std::replace(line.begin(), line.end(), ',', ' ');
    const auto t = tokens(line);
    ASSERT_EQ(t.size(), 4u);
    const LandmarkObservation& o = result.landmark_observations.at(i++);
    EXPECT_EQ(core::Timestamp::parse_seconds(t[0]), o.stamp);
    EXPECT_EQ(std::stoll(t[1]), o.landmark_id);
    EXPECT_EQ(number(t[2]), o.range_m);
    EXPECT_EQ(number(t[3]), o.bearing_rad);
  }
  EXPECT_EQ(i, result.landmark_observations.size());
}

}  // namespace
}  // namespace cairn::sim
