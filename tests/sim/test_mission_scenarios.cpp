// The mission scenarios (building-yard, outdoor-stretch, kidnapping, long-absence,
// second-session) provoke what they promise, measured from the simulated data rather than read
// from the plan: blind yard scans, doors as the only ways out, a jump in the ground truth that
// the odometry does not see, a revisit after a long absence, a second session in the same frame.

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <queue>
#include <set>
#include <sstream>

#include "cairn/sim/mission_worlds.hpp"
#include "cairn/sim/ray_cast.hpp"
#include "cairn/sim/scenario.hpp"

namespace cairn::sim {
namespace {

namespace fs = std::filesystem;

/// Each scenario simulated once with seed 1 and shared by the tests (a run takes 0.1-0.4 s).
const SimulationResult& simulated(const std::string& name) {
  static std::map<std::string, SimulationResult> runs;
  auto it = runs.find(name);
  if (it == runs.end()) it = runs.emplace(name, simulate(*make_scenario(name), 1)).first;
  return it->second;
}

int returns(const std::vector<double>& scan, double max_range_m) {
  return static_cast<int>(std::count_if(scan.begin(), scan.end(), [&](double r) { return r < max_range_m; }));
}

Vector2 scan_position(const SimulationResult& r, std::size_t scan) {
  return r.truth[r.scan_samples[scan]].T_world_body.translation();
}

bool inside(const Bounds& box, const Vector2& p) {
  return (p.array() >= box.min.array()).all() && (p.array() <= box.max.array()).all();
}

/// Whether free space joins `from` to the border of `box`: a flood fill over cells of `cell_m`,
/// a cell blocked when a wall or circle passes within `cell_m` of its centre.
bool reaches_border(const World& world, const Vector2& from, const Bounds& box, double cell_m) {
  const int nx = static_cast<int>(std::ceil((box.max.x() - box.min.x()) / cell_m));
  const int ny = static_cast<int>(std::ceil((box.max.y() - box.min.y()) / cell_m));
  auto center = [&](int i, int j) { return Vector2(box.min.x() + (i + 0.5) * cell_m, box.min.y() + (j + 0.5) * cell_m); };
  std::vector<char> seen(static_cast<std::size_t>(nx * ny), 0);
  std::queue<std::pair<int, int>> open;
  const int i0 = static_cast<int>((from.x() - box.min.x()) / cell_m);
  const int j0 = static_cast<int>((from.y() - box.min.y()) / cell_m);
  open.emplace(i0, j0);
  seen[static_cast<std::size_t>(j0 * nx + i0)] = 1;
  while (!open.empty()) {
    const auto [i, j] = open.front();
    open.pop();
    if (i == 0 || j == 0 || i == nx - 1 || j == ny - 1) return true;
    for (const auto& [di, dj] : {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
      const int a = i + di;
      const int b = j + dj;
      char& mark = seen[static_cast<std::size_t>(b * nx + a)];
      if (mark != 0) continue;
      mark = 1;
      if (world.clearance(center(a, b)) > cell_m) open.emplace(a, b);
    }
  }
  return false;
}

/// `world` with a wall across `door`'s opening.
World closed(World world, const Doorway& door) {
  const Vector2 along(-door.outward.y(), door.outward.x());
  const double half = 0.5 * door.width_m + 0.05;
  world.add_wall(door.center - half * along, door.center + half * along);
  return world;
}

TEST(BuildingYard, MostYardScansHaveFewOrNoReturns) {
  const Scenario scenario = *make_scenario("building-yard");
  const SimulationResult& r = simulated("building-yard");
  const Bounds building = OfficeFloor(scenario.office).bounds();
  std::size_t yard = 0;
  std::size_t few = 0;
  std::size_t none = 0;
  std::size_t indoor_few = 0;
  for (std::size_t k = 0; k < r.scans.size(); ++k) {
    const int n = returns(r.scans[k], scenario.lidar.max_range_m);
    if (inside(building, scan_position(r, k))) {
      indoor_few += n < 10 ? 1 : 0;
      continue;
    }
    ++yard;
    few += n < 10 ? 1 : 0;
    none += n == 0 ? 1 : 0;
  }
  ASSERT_GT(yard, 2000u);
  const double few_fraction = static_cast<double>(few) / static_cast<double>(yard);
  EXPECT_GT(few_fraction, 0.75) << few << " of " << yard << " yard scans have fewer than 10 returns";
  EXPECT_GT(static_cast<double>(none) / static_cast<double>(yard), 0.2) << none << " yard scans see nothing";
  EXPECT_EQ(indoor_few, 0u) << "inside, every scan sees walls";
  // The manifest's numbers are these.
  ASSERT_TRUE(r.mission.has_value());
  std::size_t reported = 0;
  for (const auto& s : r.mission->segments) reported += s.region == "yard" ? s.few_return_scans : 0;
  EXPECT_EQ(reported, few);
}

TEST(BuildingYard, DoorsAAndBAreTheOnlyWaysOut) {
  const Scenario scenario = *make_scenario("building-yard");
  const WorldWithRoute built = build_world(scenario);
  ASSERT_EQ(built.doors.size(), 2u);
  const Doorway& a = built.doors[0];
  const Doorway& b = built.doors[1];
  EXPECT_EQ(a.name, "A");
  EXPECT_EQ(b.name, "B");
  EXPECT_GT((a.center - b.center).norm(), 20.0);
  EXPECT_LT(a.outward.dot(b.outward), 0.5) << "on different sides of the building";
  const Bounds building = OfficeFloor(scenario.office).bounds();
  const Bounds box{building.min - Vector2(3, 3), building.max + Vector2(3, 3)};
  const Vector2 start = built.route.front();
  EXPECT_TRUE(reaches_border(built.world, start, box, 0.1));
  EXPECT_TRUE(reaches_border(closed(built.world, a), start, box, 0.1)) << "out through B";
  EXPECT_TRUE(reaches_border(closed(built.world, b), start, box, 0.1)) << "out through A";
  EXPECT_FALSE(reaches_border(closed(closed(built.world, a), b), start, box, 0.1)) << "another way out";
}

TEST(BuildingYard, OutThroughAAcrossALargeSparseYardInThroughBThenRevisits) {
  const Scenario scenario = *make_scenario("building-yard");
  const SimulationResult& r = simulated("building-yard");
  const auto& segments = r.mission->segments;
  ASSERT_EQ(segments.size(), 3u);
  EXPECT_EQ(segments[0].region, "building");
  EXPECT_EQ(segments[1].region, "yard");
  EXPECT_EQ(segments[2].region, "building");
  const auto& doors = r.world.doors;
  EXPECT_LT((scan_position(r, segments[1].first_scan) - doors[0].center).norm(), 0.5) << "leaves through A";
  EXPECT_LT((scan_position(r, segments[2].first_scan) - doors[1].center).norm(), 0.5) << "comes back through B";
  // The yard the route crosses is at least 60 m x 40 m.
  Bounds yard{scan_position(r, segments[1].first_scan), scan_position(r, segments[1].first_scan)};
  for (std::size_t k = segments[1].first_scan; k <= segments[1].last_scan; ++k) {
    yard.min = yard.min.cwiseMin(scan_position(r, k));
    yard.max = yard.max.cwiseMax(scan_position(r, k));
  }
  EXPECT_GE(yard.max.x() - yard.min.x(), 60.0);
  EXPECT_GE(yard.max.y() - yard.min.y(), 40.0);
  // A handful of features in the yard, far apart (benches are walls: count the circles).
  const Bounds building = OfficeFloor(scenario.office).bounds();
  std::vector<Vector2> features;
  for (const auto& c : r.world.world.circles) {
    if (!inside(building, c.center)) features.push_back(c.center);
  }
  EXPECT_GE(features.size(), 3u);
  EXPECT_LE(features.size(), 10u);
  for (std::size_t i = 0; i < features.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) EXPECT_GT((features[i] - features[j]).norm(), 15.0);
  }
  // Back inside, the robot drives where it drove on the first lap.
  std::size_t revisiting = 0;
  for (const auto& v : r.mission->revisits) {
    revisiting += v.later >= segments[2].first_scan && v.earlier <= segments[0].last_scan ? 1 : 0;
  }
  EXPECT_GT(revisiting, 200u);
  EXPECT_GE(r.min_clearance_m, 0.3);
}

// outdoor.glass_facades: the walls of the two facades that face the path become glass, nothing
// else changes; and a laser at building 1's door, looking 30 degrees off the facade's normal,
// reads through the pane (farther than the facade) where the opaque world stops at it.
TEST(OutdoorStretch, GlassFacadesAreTheFacingWallsAndTheLaserSeesThroughThem) {
  const Scenario scenario = *make_scenario("outdoor-stretch");
  OutdoorStretchOptions glass = scenario.outdoor;
  glass.glass_facades = true;
  const WorldWithRoute opaque = outdoor_stretch_world(scenario.office, scenario.outdoor);
  const WorldWithRoute glazed = outdoor_stretch_world(scenario.office, glass);
  ASSERT_EQ(opaque.world.walls.size(), glazed.world.walls.size());
  const double x_1 = opaque.doors[0].center.x(), x_2 = opaque.doors[1].center.x();
  std::size_t panes = 0;
  for (std::size_t i = 0; i < glazed.world.walls.size(); ++i) {
    const Segment& a = opaque.world.walls[i];
    const Segment& b = glazed.world.walls[i];
    EXPECT_FALSE(a.glass);
    EXPECT_EQ(a.a, b.a);
    EXPECT_EQ(a.b, b.b);
    const bool on_facade = a.a.x() == a.b.x() && (a.a.x() == x_1 || a.a.x() == x_2);
    EXPECT_EQ(b.glass, on_facade) << i;
    panes += b.glass ? 1 : 0;
  }
  EXPECT_GE(panes, 4u);  // each facade is at least two panes beside its door
  // 3 m outside building 1's door, towards the facade 30 degrees off its normal (west is -x).
  const Vector2 origin = opaque.doors[0].center + Vector2(3.0, 0.0);
  const double angle = std::numbers::pi - 30.0 * std::numbers::pi / 180.0;
  const Vector2 direction(std::cos(angle), std::sin(angle));
  const double to_facade = 3.0 / std::cos(30.0 * std::numbers::pi / 180.0);
  const auto stops = cast_lidar_ray(opaque.world, origin, direction, 30.0);
  const auto through = cast_lidar_ray(glazed.world, origin, direction, 30.0);
  ASSERT_TRUE(stops.has_value());
  EXPECT_NEAR(stops->range_m, to_facade, 1e-9);
  EXPECT_TRUE(!through.has_value() || through->range_m > to_facade + 0.1);
}

TEST(OutdoorStretch, ALongBlindPathBetweenTwoBuildingsDrivenBothWays) {
  const Scenario scenario = *make_scenario("outdoor-stretch");
  const SimulationResult& r = simulated("outdoor-stretch");
  const auto& segments = r.mission->segments;
  std::vector<std::string> regions;
  for (const auto& s : segments) regions.push_back(s.region);
  EXPECT_EQ(regions, (std::vector<std::string>{"building-1", "path", "building-2", "path", "building-1"}));
  ASSERT_EQ(r.world.doors.size(), 2u);
  EXPECT_GE((r.world.doors[0].center - r.world.doors[1].center).norm(), 120.0);
  EXPECT_GE(segments[1].path_length_m, 120.0);
  EXPECT_GE(segments[3].path_length_m, 120.0);
  // Farther than the LiDAR's range from both buildings, nearly every scan has few returns.
  const double range = scenario.lidar.max_range_m;
  std::size_t middle = 0;
  std::size_t few = 0;
  for (std::size_t k = 0; k < r.scans.size(); ++k) {
    const double x = scan_position(r, k).x();
    if (x < r.world.doors[0].center.x() + range || x > r.world.doors[1].center.x() - range) continue;
    ++middle;
    few += returns(r.scans[k], range) < 10 ? 1 : 0;
  }
  ASSERT_GT(middle, 1000u);
  EXPECT_GT(static_cast<double>(few) / static_cast<double>(middle), 0.85) << few << " of " << middle;
  // Building 1 is mapped, left for minutes, and revisited.
  ASSERT_TRUE(r.mission->absence.has_value());
  EXPECT_EQ(r.mission->absence->region, "building-1");
  EXPECT_GT(r.mission->absence->duration_s, 300.0);
  std::size_t revisiting = 0;
  for (const auto& v : r.mission->revisits) {
    revisiting += v.later >= segments[4].first_scan && v.earlier <= segments[0].last_scan ? 1 : 0;
  }
  EXPECT_GT(revisiting, 200u);
}

TEST(Kidnapping, TheGroundTruthJumpsAndTheOdometryDoesNot) {
  const Scenario scenario = *make_scenario("kidnapping");
  const SimulationResult& r = simulated("kidnapping");
  ASSERT_EQ(r.carried_samples.size(), 1u);
  const std::size_t jump = r.carried_samples.front();
  for (std::size_t k = 1; k < r.truth.size(); ++k) {
    const core::SE2 truth_step = r.truth[k - 1].T_world_body.inverse() * r.truth[k].T_world_body;
    const core::SE2 odometry_step = r.odometry.poses[k - 1].inverse() * r.odometry.poses[k];
    // At 1 m/s a 10 ms step is 1 cm: the odometry never jumps, the truth jumps once.
    EXPECT_LT(odometry_step.translation().norm(), 0.02) << "sample " << k;
    if (k != jump) {
      ASSERT_LT(truth_step.translation().norm(), 0.02) << "sample " << k;
    } else {
      EXPECT_GT(truth_step.translation().norm(), 3.0);
      EXPECT_GT(std::abs(truth_step.angle()), 0.5) << "put down facing another way";
      EXPECT_EQ(odometry_step.translation().norm(), 0.0) << "the wheels did not turn";
      EXPECT_EQ(odometry_step.angle(), 0.0);
    }
  }
  // Into another room: a wall lies between the two poses.
  const Vector2 from = r.truth[jump - 1].T_world_body.translation();
  const Vector2 to = r.truth[jump].T_world_body.translation();
  bool crosses = false;
  for (const auto& wall : r.world.world.walls) {
    const Vector2 d = to - from;
    const Vector2 e = wall.b - wall.a;
    const double denominator = d.x() * e.y() - d.y() * e.x();
    if (denominator == 0.0) continue;
    const Vector2 w = wall.a - from;
    const double t = (w.x() * e.y() - w.y() * e.x()) / denominator;
    const double u = (w.x() * d.y() - w.y() * d.x()) / denominator;
    crosses = crosses || (t > 0.0 && t < 1.0 && u >= 0.0 && u <= 1.0);
  }
  EXPECT_TRUE(crosses);
  EXPECT_EQ(to, *OfficeFloor(scenario.office).place_center(scenario.kidnap.drop_place));
  // The recorded event is this jump, at the set time.
  ASSERT_TRUE(r.mission->kidnap.has_value());
  const KidnapEvent& event = *r.mission->kidnap;
  EXPECT_EQ(event.first_sample_after, jump);
  EXPECT_LE(event.stamp_before.seconds(), scenario.kidnap.time_s + 1e-9);
  EXPECT_GT(event.stamp_after.seconds(), scenario.kidnap.time_s);
  EXPECT_EQ(event.T_odom_body_before.translation(), event.T_odom_body_after.translation());
  EXPECT_EQ(event.first_scan_after, event.last_scan_before + 1);
  EXPECT_GE(r.scan_samples[event.first_scan_after], jump);
  EXPECT_LT(r.scan_samples[event.last_scan_before], jump);
  // After the drop the robot drives through places it mapped before being picked up.
  std::size_t revisiting = 0;
  for (const auto& v : r.mission->revisits) {
    revisiting += v.later >= event.first_scan_after && v.earlier <= event.last_scan_before ? 1 : 0;
  }
  EXPECT_GT(revisiting, 100u);
  // The driven path does not count the carry.
  EXPECT_LT(std::abs(r.path_length_m - (path_length(r.truth) - (to - from).norm())), 1e-6);
}

TEST(Kidnapping, FilesRecordTheJumpAndTheLogDoesNotShowIt) {
  const Scenario scenario = *make_scenario("kidnapping");
  const SimulationResult& r = simulated("kidnapping");
  const fs::path dir = fs::temp_directory_path() / ("cairn_test_kidnap_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const auto files = write_outputs(r, scenario, 1, dir.string());
  EXPECT_NE(std::find(files.begin(), files.end(), "kidnap.txt"), files.end());
  EXPECT_NE(std::find(files.begin(), files.end(), "segments.txt"), files.end());
  EXPECT_NE(std::find(files.begin(), files.end(), "revisits.txt"), files.end());
  std::map<std::string, std::vector<double>> values;
  {
    std::ifstream in(dir / "kidnap.txt");
    std::string line;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#') continue;
      std::istringstream fields(line);
      std::string key;
      fields >> key;
      double v = 0.0;
      while (fields >> v) values[key].push_back(v);
    }
  }
  const KidnapEvent& event = *r.mission->kidnap;
  ASSERT_EQ(values["T_world_body_before"].size(), 3u);
  ASSERT_EQ(values["T_world_body_after"].size(), 3u);
  EXPECT_EQ(values["T_world_body_after"][0], event.T_world_body_after.x());
  EXPECT_EQ(values["T_world_body_after"][1], event.T_world_body_after.y());
  EXPECT_EQ(values["T_world_body_before"][0], event.T_world_body_before.x());
  ASSERT_EQ(values["time_before_s"].size(), 1u);
  EXPECT_NEAR(values["time_before_s"][0], event.stamp_before.seconds(), 1e-9);
  EXPECT_EQ(values["first_scan_after"], std::vector<double>{static_cast<double>(event.first_scan_after)});
  EXPECT_EQ(values["T_odom_body_before"], values["T_odom_body_after"]);
  EXPECT_GT(values["jump_m"].at(0), 3.0);
  // FLASER's odometry fields just before and after the jump: a few centimetres apart at most.
  std::vector<std::array<double, 3>> flaser_odometry;
  {
    std::ifstream in(dir / "log.clf");
    std::string line;
    while (std::getline(in, line)) {
      if (!line.starts_with("FLASER ")) continue;
      std::istringstream fields(line.substr(7));
      int n = 0;
      fields >> n;
      double skip = 0.0;
      for (int i = 0; i < n + 3; ++i) fields >> skip;
      std::array<double, 3> odometry{};
      fields >> odometry[0] >> odometry[1] >> odometry[2];
      flaser_odometry.push_back(odometry);
    }
  }
  ASSERT_EQ(flaser_odometry.size(), r.scans.size());
  const auto& before = flaser_odometry[event.last_scan_before];
  const auto& after = flaser_odometry[event.first_scan_after];
  EXPECT_LT(std::hypot(after[0] - before[0], after[1] - before[1]), 0.15);
  std::error_code ignored;
  fs::remove_all(dir, ignored);
}

TEST(Kidnapping, TimeAndPlaceAreParametersAndAreChecked) {
  Scenario scenario = *make_scenario("kidnapping");
  std::string why;
  scenario.kidnap.time_s = 100.0;
  scenario.kidnap.drop_place = "bottom-room-3";
  scenario.kidnap.drop_heading_rad = 1.0;
  ASSERT_TRUE(scenario.is_valid(&why)) << why;
  const SimulationResult r = simulate(scenario, 1);
  EXPECT_NEAR(r.mission->kidnap->stamp_before.seconds(), 100.0, 1e-9);
  EXPECT_EQ(r.mission->kidnap->T_world_body_after.translation(),
            *OfficeFloor(scenario.office).place_center("bottom-room-3"));
  EXPECT_NEAR(r.mission->kidnap->T_world_body_after.angle(), 1.0, 1e-12);

  Scenario late = *make_scenario("kidnapping");
  late.kidnap.time_s = 1000.0;
  EXPECT_FALSE(late.is_valid(&why));
  EXPECT_NE(why.find("kidnap.time_s must be below"), std::string::npos) << why;
  Scenario nowhere = *make_scenario("kidnapping");
  nowhere.kidnap.drop_place = "kitchen";
  EXPECT_FALSE(nowhere.is_valid(&why));
  EXPECT_NE(why.find("kidnap.drop_place must be one of bottom-room-0"), std::string::npos) << why;
  // At 15 s the robot stands in bottom room 1: putting it down there is no kidnapping.
  Scenario same_room = *make_scenario("kidnapping");
  same_room.kidnap.time_s = 15.0;
  same_room.kidnap.drop_place = "bottom-room-1";
  EXPECT_FALSE(same_room.is_valid(&why));
  EXPECT_NE(why.find("at least 3 m apart"), std::string::npos) << why;
}

// kidnap.rings_after adds whole rounds of the ring after the drop; office.furnished adds 20 boxes
// (12 cabinets, a shelf in each of the 8 rooms: 80 walls) and only on the default plan.
TEST(Kidnapping, RingsAfterAndFurnitureAreParametersAndAreChecked) {
  auto path_after_drop = [](const SimulationResult& r) {
    double length = 0.0;
    for (std::size_t k = r.mission->kidnap->first_sample_after + 1; k < r.truth.size(); ++k)
      length += (r.truth[k].T_world_body.translation() - r.truth[k - 1].T_world_body.translation()).norm();
    return length;
  };
  std::string why;
  Scenario once = *make_scenario("kidnapping");
  Scenario twice = once;
  twice.kidnap.rings_after = 2;
  twice.office.furnished = true;
  ASSERT_TRUE(twice.is_valid(&why)) << why;
  const SimulationResult r1 = simulate(once, 1);
  const SimulationResult r2 = simulate(twice, 1);
  // The ring's centre lines are 2 x (25.6 + 8.4) = 68 m round; its corners are rounded.
  const double extra_m = path_after_drop(r2) - path_after_drop(r1);
  EXPECT_GT(extra_m, 60.0);
  EXPECT_LT(extra_m, 68.0);
  EXPECT_EQ(r2.world.world.walls.size(), r1.world.world.walls.size() + 80);

  for (const int rings : {0, 6}) {
    Scenario bad = *make_scenario("kidnapping");
    bad.kidnap.rings_after = rings;
    EXPECT_FALSE(bad.is_valid(&why));
    EXPECT_NE(why.find("kidnap.rings_after must be in [1, 5]"), std::string::npos) << why;
  }
  Scenario wide = *make_scenario("kidnapping");
  wide.office.furnished = true;
  wide.office.width_m = 32.0;
  EXPECT_FALSE(wide.is_valid(&why));
  EXPECT_NE(why.find("office.furnished: the furniture is laid out for the default plan"), std::string::npos) << why;
}

TEST(LongAbsence, TheWestWingIsRevisitedAfterMoreThanFiveMinutesAnd200m) {
  const SimulationResult& r = simulated("long-absence");
  const auto& segments = r.mission->segments;
  std::vector<std::string> regions;
  for (const auto& s : segments) regions.push_back(s.region);
  EXPECT_EQ(regions, (std::vector<std::string>{"west-wing", "connector", "east-wing", "connector", "west-wing"}));
  ASSERT_TRUE(r.mission->absence.has_value());
  const Absence& absence = *r.mission->absence;
  EXPECT_EQ(absence.left_scan, segments[0].last_scan);
  EXPECT_EQ(absence.returned_scan, segments[4].first_scan);
  // Measured directly: from the last west-wing scan before leaving to the first west-wing scan
  // within 1 m of a scan of the first visit.
  const double left_time_s = r.truth[r.scan_samples[segments[0].last_scan]].stamp.seconds();
  std::size_t first_revisit = 0;
  for (std::size_t j = segments[4].first_scan; j < r.scans.size() && first_revisit == 0; ++j) {
    for (std::size_t i = 0; i <= segments[0].last_scan; ++i) {
      if ((scan_position(r, j) - scan_position(r, i)).norm() <= 1.0) {
        first_revisit = j;
        break;
      }
    }
  }
  ASSERT_GT(first_revisit, 0u);
  const double away_s = r.truth[r.scan_samples[first_revisit]].stamp.seconds() - left_time_s;
  double away_m = 0.0;
  for (std::size_t k = r.scan_samples[segments[0].last_scan] + 1; k <= r.scan_samples[first_revisit]; ++k) {
    away_m += (r.truth[k].T_world_body.translation() - r.truth[k - 1].T_world_body.translation()).norm();
  }
  EXPECT_GE(away_s, 300.0);
  EXPECT_GE(away_m, 200.0);
  ASSERT_TRUE(absence.first_revisit.has_value());
  EXPECT_EQ(absence.first_revisit->later, first_revisit);
  EXPECT_GE(absence.first_revisit->time_difference_s, 300.0);
  EXPECT_GE(absence.first_revisit->path_between_m, 200.0);
  EXPECT_NEAR(absence.duration_s, away_s, 1e-9);
  // And the places of the first visit are driven again (the bottom corridor, bottom room 1).
  std::size_t revisiting = 0;
  for (const auto& v : r.mission->revisits) {
    revisiting += v.later >= segments[4].first_scan && v.earlier <= segments[0].last_scan ? 1 : 0;
  }
  EXPECT_GT(revisiting, 200u);
}

TEST(SecondSession, StartsElsewhereInTheSameFrameAndSeesTheSamePlaces) {
  const SimulationResult& first = simulated("building-yard");
  const SimulationResult& second = simulated("second-session");
  // The same world, element for element.
  const World& a = first.world.world;
  const World& b = second.world.world;
  ASSERT_EQ(a.walls.size(), b.walls.size());
  for (std::size_t i = 0; i < a.walls.size(); ++i) {
    EXPECT_EQ(a.walls[i].a, b.walls[i].a);
    EXPECT_EQ(a.walls[i].b, b.walls[i].b);
  }
  ASSERT_EQ(a.circles.size(), b.circles.size());
  for (std::size_t i = 0; i < a.circles.size(); ++i) EXPECT_EQ(a.circles[i].center, b.circles[i].center);
  // Another start pose.
  const core::SE2& start_1 = first.truth.front().T_world_body;
  const core::SE2& start_2 = second.truth.front().T_world_body;
  EXPECT_GT((start_1.translation() - start_2.translation()).norm(), 3.0);
  EXPECT_GT(std::abs(core::wrap_angle(start_1.angle() - start_2.angle())), 0.5);
  ASSERT_TRUE(second.mission->session.has_value());
  EXPECT_EQ(second.mission->session->pairs_with, "building-yard");
  EXPECT_EQ(second.mission->session->T_world_paired_start.translation(), start_1.translation());
  // Its scans hit what the first session's scans hit: endpoints in the world frame, on a 0.25 m
  // grid, the second session's within one cell of the first's.
  auto endpoints = [](const SimulationResult& r, const LidarOptions& lidar) {
    std::vector<Vector2> points;
    for (std::size_t k = 0; k < r.scans.size(); ++k) {
      const core::SE2 T_world_laser = r.truth[r.scan_samples[k]].T_world_body * lidar.T_body_laser();
      for (std::size_t i = 0; i < r.scans[k].size(); ++i) {
        const double range = r.scans[k][i];
        if (range >= lidar.max_range_m) continue;
        const double angle = lidar.angle_min_rad + static_cast<double>(i) * lidar.angle_increment_rad;
        points.push_back(T_world_laser * Vector2(range * std::cos(angle), range * std::sin(angle)));
      }
    }
    return points;
  };
  const LidarOptions lidar = make_scenario("building-yard")->lidar;
  constexpr double kCell = 0.25;
  auto key = [](const Vector2& p, int di, int dj) {
    return std::pair{static_cast<long>(std::floor(p.x() / kCell)) + di, static_cast<long>(std::floor(p.y() / kCell)) + dj};
  };
  std::set<std::pair<long, long>> mapped;
  for (const auto& p : endpoints(first, lidar)) mapped.insert(key(p, 0, 0));
  std::size_t seen = 0;
  std::size_t total = 0;
  for (const auto& p : endpoints(second, lidar)) {
    ++total;
    bool near = false;
    for (int di = -1; di <= 1 && !near; ++di) {
      for (int dj = -1; dj <= 1 && !near; ++dj) near = mapped.count(key(p, di, dj)) > 0;
    }
    seen += near ? 1 : 0;
  }
  ASSERT_GT(total, 100000u);
  EXPECT_GT(static_cast<double>(seen) / static_cast<double>(total), 0.9) << seen << " of " << total;
}

TEST(SecondSession, AParameterChoosesTheStart) {
  Scenario scenario = *make_scenario("second-session");
  auto params = parameters(scenario);
  std::string why;
  for (auto& p : params) {
    if (p.name == "session.start_place") {
      ASSERT_TRUE(p.set("bottom-room-1", &why)) << why;
    } else if (p.name == "session.start_heading_rad") {
      ASSERT_TRUE(p.set("0.5", &why)) << why;
    }
  }
  ASSERT_TRUE(scenario.is_valid(&why)) << why;
  const SimulationResult r = simulate(scenario, 1);
  EXPECT_EQ(r.truth.front().T_world_body.translation(), *OfficeFloor(scenario.office).place_center("bottom-room-1"));
  EXPECT_EQ(r.truth.front().T_world_body.angle(), 0.5);
  EXPECT_GE(r.min_clearance_m, 0.3);
  scenario.session_start.place = "attic";
  EXPECT_FALSE(scenario.is_valid(&why));
  EXPECT_NE(why.find("session.start_place"), std::string::npos) << why;
}

TEST(MissionScenarios, RunsAreModestAndSettingsAreChecked) {
  for (const char* name : {"building-yard", "outdoor-stretch", "kidnapping", "long-absence", "second-session"}) {
    const SimulationResult& r = simulated(name);
    EXPECT_LE(r.duration_s, 600.0) << name;
    EXPECT_LE(r.scans.size(), 8000u) << name;
    EXPECT_GE(r.min_clearance_m, 0.3) << name;
  }
  std::string why;
  Scenario yard = *make_scenario("building-yard");
  yard.trajectory.laps = 2;
  yard.building_yard.door_width_m = 0.8;
  yard.building_yard.features = 99;
  EXPECT_FALSE(yard.is_valid(&why));
  EXPECT_NE(why.find("trajectory.laps must be 1"), std::string::npos) << why;
  EXPECT_NE(why.find("building_yard.door_width_m"), std::string::npos) << why;
  EXPECT_NE(why.find("building_yard.features"), std::string::npos) << why;
  Scenario outdoor = *make_scenario("outdoor-stretch");
  outdoor.outdoor.path_length_m = 10.0;
  outdoor.outdoor.building_2_rooms_per_row = 1;
  EXPECT_FALSE(outdoor.is_valid(&why));
  EXPECT_NE(why.find("outdoor.path_length_m"), std::string::npos) << why;
  EXPECT_NE(why.find("building_2.rooms_per_row"), std::string::npos) << why;
  Scenario wings = *make_scenario("long-absence");
  wings.wings.away_laps = 0;
  wings.wings.connector_width_m = 1.0;
  EXPECT_FALSE(wings.is_valid(&why));
  EXPECT_NE(why.find("long_absence.away_laps"), std::string::npos) << why;
  EXPECT_NE(why.find("long_absence.connector_width_m"), std::string::npos) << why;
}

TEST(MissionScenarios, SameSeedSameFiles) {
  Scenario scenario = *make_scenario("second-session");
  const fs::path base = fs::temp_directory_path() / ("cairn_test_mission_" + std::to_string(::getpid()));
  fs::remove_all(base);
  for (const char* run : {"a", "b"}) {
    fs::create_directories(base / run);
    write_outputs(simulate(scenario, 4), scenario, 4, (base / run).string());
  }
  std::size_t compared = 0;
  for (const auto& entry : fs::directory_iterator(base / "a")) {
    std::ifstream x(entry.path(), std::ios::binary);
    std::ifstream y(base / "b" / entry.path().filename(), std::ios::binary);
    std::ostringstream xs;
    std::ostringstream ys;
    xs << x.rdbuf();
    ys << y.rdbuf();
    EXPECT_EQ(xs.str(), ys.str()) << entry.path().filename();
    ++compared;
  }
  EXPECT_GE(compared, 11u);
  std::error_code ignored;
  fs::remove_all(base, ignored);
}

}  // namespace
}  // namespace cairn::sim
