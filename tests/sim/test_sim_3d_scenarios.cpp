// The 3D LiDAR SLAM test scenarios: street-3d-loops (reverse revisit, moving cars), garage-3d
// (aliasing, no true loop), tunnel-3d (degenerate passage); the PCD scans read back through
// io::read_point_cloud; the azimuth index against brute-force ray casting; sensor presets.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

#include "cairn/io/point_cloud.hpp"
#include "cairn/io/trajectory.hpp"
#include "cairn/sim/random.hpp"
#include "cairn/sim/ray_cast_3d.hpp"
#include "cairn/sim/scenario.hpp"
#include "scratch_directory.hpp"
#include "cairn/sim/street_run.hpp"

namespace cairn::sim {
namespace {

namespace fs = std::filesystem;

using test::bytes_of;
using test::ScratchDirectory;

/// A short garage (5 bays) with a coarse LiDAR: a run in a few tens of milliseconds.
Scenario small_garage() {
  Scenario s = *make_scenario("garage-3d");
  s.garage.length_m = 40.0;
  s.garage.approach_m = 10.0;
  s.lidar3d.columns = 60;
  return s;
}

TEST(Scenarios3D, SameSeedSameBytesOtherSeedOtherScans) {
  const Scenario scenario = small_garage();
  std::string why;
  ASSERT_TRUE(scenario.is_valid(&why)) << why;
  ScratchDirectory dir("sim3d_determinism");
  for (const char* run : {"a", "b"}) {
    fs::create_directories(dir.path / run);
    write_outputs(simulate(scenario, 3), scenario, 3, (dir.path / run).string());
  }
  fs::create_directories(dir.path / "c");
  const auto files = write_outputs(simulate(scenario, 4), scenario, 4, (dir.path / "c").string());
  ASSERT_GT(files.size(), 10u);
  std::size_t scans_differing = 0;
  for (const auto& name : files) {
    EXPECT_EQ(bytes_of(dir.path / "a" / name), bytes_of(dir.path / "b" / name)) << name;
    if (name.starts_with("scans/")) scans_differing += bytes_of(dir.path / "a" / name) != bytes_of(dir.path / "c" / name);
  }
  EXPECT_GT(scans_differing, 0u) << "another seed draws other range noise";
}

TEST(Scenarios3D, PcdScansReadBackWithRingsAndTimesAndPosesAreTheLidarInTheWorld) {
  const Scenario scenario = small_garage();
  const SimulationResult result = simulate(scenario, 1);
  ScratchDirectory dir("sim3d_pcd");
  const auto files = write_outputs(result, scenario, 1, dir.path.string());
  ASSERT_EQ(std::count_if(files.begin(), files.end(), [](const std::string& f) { return f.starts_with("scans/"); }),
            static_cast<std::ptrdiff_t>(result.clouds.size()));
  for (const std::size_t k : {std::size_t{0}, result.clouds.size() / 2}) {
    char name[32];
    std::snprintf(name, sizeof name, "scans/%06zu.pcd", k);
    io::PointCloudReadReport report;
    const io::PointCloud cloud = io::read_point_cloud((dir.path / name).string(), &report);
    EXPECT_EQ(report.format, "pcd binary");
    const auto& truth = result.clouds[k];
    ASSERT_EQ(cloud.size(), truth.size());
    ASSERT_EQ(cloud.ring.size(), truth.size());
    ASSERT_EQ(cloud.time_s.size(), truth.size());
    ASSERT_EQ(cloud.intensity.size(), truth.size());
    for (std::size_t i = 0; i < truth.size(); ++i) {
      ASSERT_EQ(cloud.points[i], truth[i].position.cast<float>()) << i;
      ASSERT_EQ(cloud.ring[i], truth[i].ring) << i;
      ASSERT_EQ(cloud.time_s[i], static_cast<float>(truth[i].time_offset_s)) << i;
    }
    EXPECT_EQ(cloud.ring.front(), 0);  // the first column's lowest ring hits the ground
  }
  // poses.txt: T_world_lidar at the sweep start, times.txt beside it.
  io::Trajectory poses = io::read_kitti((dir.path / "poses.txt").string(), (dir.path / "times.txt").string());
  ASSERT_EQ(poses.poses.size(), result.scan_samples.size());
  for (std::size_t k = 0; k < poses.poses.size(); k += 7) {
    const std::size_t sample = result.scan_samples[k];
    const core::SE3 expected = lidar_pose(result.truth[sample].T_world_body, scenario.lidar3d);
    EXPECT_LT((poses.poses[k].translation() - expected.translation()).norm(), 1e-9);
    EXPECT_EQ(poses.stamps[k], result.truth[sample].stamp);
  }
  EXPECT_NEAR(poses.poses.front().translation().x(), -scenario.garage.approach_m, 1e-9);  // world, not first-pose
}

TEST(Scenarios3D, WritePcdWithoutAttributesReadsBack) {
  io::PointCloud cloud;
  cloud.points = {Eigen::Vector3f(1, 2, 3), Eigen::Vector3f(-4.5F, 0.25F, 1e-3F)};
  std::ostringstream out;
  io::write_pcd(out, cloud, "two points");
  const io::PointCloud back = io::parse_point_cloud("mem.pcd", out.str());
  EXPECT_EQ(back.points, cloud.points);
  EXPECT_TRUE(back.ring.empty());
  EXPECT_TRUE(back.time_s.empty());
  std::ostringstream empty;
  io::write_pcd(empty, io::PointCloud{});
  EXPECT_EQ(io::parse_point_cloud("empty.pcd", empty.str()).size(), 0u);
}

TEST(StreetLoops, ReverseRevisitsAreTrueLoopsAndTheListIsComplete) {
  Scenario scenario = *make_scenario("street-3d-loops");
  scenario.lidar3d.columns = 4;  // the loop list depends on the trajectory only
  std::string why;
  ASSERT_TRUE(scenario.is_valid(&why)) << why;
  const SimulationResult result = simulate(scenario, 1);
  EXPECT_GE(result.min_clearance_m, 1.0);
  std::vector<core::SE3> poses;
  std::vector<double> times;
  for (std::size_t k : result.scan_samples) {
    poses.push_back(lidar_pose(result.truth[k].T_world_body, scenario.lidar3d));
    times.push_back(result.truth[k].stamp.seconds());
  }
  // Brute force over every pair: the list holds exactly the pairs meeting the criterion.
  std::size_t expected = 0;
  for (std::size_t j = 0; j < poses.size(); ++j) {
    for (std::size_t i = 0; i < j; ++i) {
      expected += (poses[j].translation() - poses[i].translation()).norm() <= scenario.loop_truth.max_distance_m &&
                  times[j] - times[i] >= scenario.loop_truth.min_separation_s;
    }
  }
  EXPECT_EQ(result.true_loops.size(), expected);
  std::size_t reverse = 0;
  std::size_t same_direction = 0;
  for (const auto& loop : result.true_loops) {
    ASSERT_LT(loop.earlier, loop.later);
    EXPECT_LE(loop.distance_m, scenario.loop_truth.max_distance_m);
    EXPECT_GE(loop.time_difference_s, scenario.loop_truth.min_separation_s);
    reverse += loop.heading_difference_rad > std::numbers::pi - 0.1;
    same_direction += loop.heading_difference_rad < 0.1;
  }
  // The whole second lap revisits the first in reverse, one lane over (3 m); the first lap's
  // end revisits its start in the same direction.
  EXPECT_GT(reverse, 1000u);
  EXPECT_GT(same_direction, 10u);
  double nearest_reverse = 1e9;
  for (const auto& loop : result.true_loops) {
    if (loop.heading_difference_rad > std::numbers::pi - 0.1) nearest_reverse = std::min(nearest_reverse, loop.distance_m);
  }
  EXPECT_NEAR(nearest_reverse, scenario.street.reverse_lane_offset_m, 0.05);
}

TEST(StreetLoops, MovingCarsAreSeenAndMoveBetweenScans) {
  Scenario scenario = *make_scenario("street-3d-loops");
  scenario.lidar3d.columns = 120;
  scenario.lidar3d.range_sigma_m = 0.0;
  scenario.lidar3d.dropout_probability = 0.0;
  const SimulationResult result = simulate(scenario, 1);
  const auto& cars = result.world_3d.moving_boxes;
  ASSERT_EQ(cars.size(), 6u);
  // A point is on car c when, placed in the world with the pose of its firing time (the nearest
  // 10 ms truth sample: within 3 cm), it lies within 0.1 m of that car's box at that time.
  auto inside = [](const Box& box, const Vector3& p, double margin) {
    return (p.array() >= box.min.array() - margin).all() && (p.array() <= box.max.array() + margin).all();
  };
  const double sample_s = scenario.trajectory.sample_period_s;
  std::size_t scans_seeing_cars = 0;
  std::size_t car_points = 0;
  std::size_t still_there_a_second_later = 0;
  for (std::size_t k = 0; k < result.clouds.size(); ++k) {
    bool seen = false;
    for (const auto& point : result.clouds[k]) {
      const double time = result.truth[result.scan_samples[k]].stamp.seconds() + point.time_offset_s;
      const auto sample = static_cast<std::size_t>(std::llround(time / sample_s));
      const Vector3 world = lidar_pose(result.truth[std::min(sample, result.truth.size() - 1)].T_world_body,
                                       scenario.lidar3d) * point.position;
      for (const auto& car : cars) {
        if (!inside(car.at(time), world, 0.1)) continue;
        seen = true;
        ++car_points;
        still_there_a_second_later += inside(car.at(time + 1.0), world, 0.1);
      }
    }
    scans_seeing_cars += seen;
  }
  EXPECT_GT(scans_seeing_cars, result.clouds.size() / 4);
  EXPECT_GT(car_points, 10000u);
  // At 5 m/s a car leaves the spot it was seen at: few car points (rays at its long sides) stay.
  EXPECT_LT(still_there_a_second_later, car_points / 5);
}

TEST(MovingBox, DrivesAroundItsPathAndTurnsAtCorners) {
  MovingBox car;
  car.path = {{0, 0}, {10, 0}, {10, 10}, {0, 10}};
  car.speed_mps = 2.0;
  car.phase_m = 1.0;
  const Box start = car.at(0.0);  // 1 m along the first edge, length along x
  EXPECT_NEAR(0.5 * (start.min.x() + start.max.x()), 1.0, 1e-12);
  EXPECT_NEAR(start.max.x() - start.min.x(), 4.5, 1e-12);
  EXPECT_NEAR(start.max.y() - start.min.y(), 1.8, 1e-12);
  const Box up = car.at(7.0);  // 15 m: 5 m up the second edge, length along y
  EXPECT_NEAR(0.5 * (up.min.y() + up.max.y()), 5.0, 1e-12);
  EXPECT_NEAR(up.max.y() - up.min.y(), 4.5, 1e-12);
  const Box lap = car.at(20.0);  // one 40 m lap later: where it started
  EXPECT_NEAR((lap.min - start.min).norm(), 0.0, 1e-9);
}

TEST(Garage, NothingIsRevisitedAndPlacesOneBayApartLookTheSame) {
  const Scenario scenario = *make_scenario("garage-3d");
  Scenario light = scenario;
  light.lidar3d.columns = 4;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) EXPECT_TRUE(simulate(light, seed).true_loops.empty());
  const SimulationResult result = simulate(light, 1);
  ASSERT_TRUE(result.passage_scans.has_value());
  EXPECT_TRUE(result.passage_scans->any_inside);
  EXPECT_EQ(result.passage_scans->passage.kind, "garage");

  // Noise-free scans from the middle of the garage, one bay apart: the same points.
  const World3D world = build_world_3d(scenario).world;
  Lidar3DOptions lidar = scenario.lidar3d;
  lidar.range_sigma_m = 0.0;
  lidar.dropout_probability = 0.0;
  lidar.columns = 180;
  const double middle = 0.5 * scenario.garage.length_m + 0.3;
  auto scan_at = [&](double x) {
    Random random(1);
    return spin_scan(world, 0.0, [&](double) { return core::SE3(Quaternion::Identity(), Vector3(x, 0, 1.8)); },
                     lidar, random);
  };
  const auto a = scan_at(middle);
  const auto b = scan_at(middle + scenario.garage.bay_pitch_m);
  const auto c = scan_at(middle + 0.5 * scenario.garage.bay_pitch_m);
  ASSERT_EQ(a.size(), b.size());
  double worst = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, (a[i].position - b[i].position).norm());
  EXPECT_LT(worst, 1e-6);
  double moved = 0.0;
  for (std::size_t i = 0; i < std::min(a.size(), c.size()); ++i) moved = std::max(moved, (a[i].position - c[i].position).norm());
  EXPECT_GT(moved, 1.0) << "half a bay further the scan differs";
}

TEST(Tunnel, ScansInsideAreListedAndTheSpeedIsConstantThere) {
  Scenario scenario = *make_scenario("tunnel-3d");
  scenario.lidar3d.columns = 4;
  const SimulationResult result = simulate(scenario, 1);
  EXPECT_TRUE(result.true_loops.empty());
  ASSERT_TRUE(result.passage_scans.has_value());
  const PassageScans& p = *result.passage_scans;
  EXPECT_EQ(p.passage.kind, "tunnel");
  EXPECT_EQ(p.passage.axis, Vector2::UnitX());
  EXPECT_EQ(p.passage.length_m, scenario.tunnel.length_m);
  ASSERT_TRUE(p.any_inside);
  ASSERT_TRUE(p.any_blind);  // 150 m tunnel, 60 m range: the middle 30 m see neither portal
  EXPECT_LT(p.first_inside, p.first_blind);
  EXPECT_LT(p.last_blind, p.last_inside);
  for (std::size_t k = 0; k < result.scan_samples.size(); ++k) {
    const auto& sample = result.truth[result.scan_samples[k]];
    const double x = sample.T_world_body.x();
    const bool inside = k >= p.first_inside && k <= p.last_inside;
    EXPECT_EQ(inside, x >= 0.0 && x <= scenario.tunnel.length_m) << k;
    if (inside) {
      EXPECT_NEAR(sample.speed_mps, scenario.trajectory.max_speed_mps, 1e-9) << k;
    }
    EXPECT_NEAR(sample.T_world_body.y(), 0.0, 1e-9);
  }
}

TEST(AzimuthIndex, FindsTheSameFirstHitAsBruteForce) {
  const World3D world = build_world_3d(*make_scenario("street-3d-loops")).world;
  Random random(11);
  std::size_t hits = 0;
  for (int trial = 0; trial < 20; ++trial) {
    const Vector2 center(random.uniform(-5.0, 65.0), random.uniform(-5.0, 45.0));
    const double motion = random.uniform(0.0, 2.0);
    const AzimuthIndex index(world, center, motion);
    for (int ray = 0; ray < 2000; ++ray) {
      const double angle = random.uniform(0.0, 2.0 * std::numbers::pi);
      const double radius = motion * std::sqrt(random.uniform());
      const Vector3 origin(center.x() + radius * std::cos(angle), center.y() + radius * std::sin(angle),
                           random.uniform(0.2, 3.0));
      Vector3 direction(random.gaussian(), random.gaussian(), 0.3 * random.gaussian());
      direction.normalize();
      const auto fast = index.cast(origin, direction, 80.0);
      const auto slow = cast_ray(world, origin, direction, 80.0);
      ASSERT_EQ(fast.has_value(), slow.has_value()) << trial << " " << ray;
      if (slow) {
        ASSERT_EQ(*fast, *slow);
        ++hits;
      }
    }
  }
  EXPECT_GT(hits, 30000u);
}

TEST(Lidar3DModel, PresetFirstThenOverridesAndUnknownNamesRefused) {
  Scenario scenario = *make_scenario("street-3d-loops");
  auto params = parameters(scenario);
  auto find = [&](const std::string& name) -> Parameter& {
    for (auto& p : params) {
      if (p.name == name) return p;
    }
    throw std::runtime_error("no parameter " + name);
  };
  std::string why;
  ASSERT_TRUE(find("lidar3d.model").set("hdl64", &why)) << why;
  EXPECT_EQ(scenario.lidar3d.rings, 64);
  EXPECT_EQ(scenario.lidar3d.columns, 2000);
  EXPECT_NEAR(scenario.lidar3d.elevation_min_rad * 180.0 / std::numbers::pi, -24.8, 1e-12);
  EXPECT_EQ(scenario.lidar3d.max_range_m, 120.0);
  ASSERT_TRUE(find("lidar3d.columns").set("500", &why));
  EXPECT_EQ(scenario.lidar3d.columns, 500);
  EXPECT_FALSE(find("lidar3d.model").set("os1", &why));
  EXPECT_NE(why.find("vlp16, hdl64"), std::string::npos) << why;
  EXPECT_FALSE(find("lidar3d.format").set("las", &why));
  ASSERT_TRUE(find("lidar3d.model").set("vlp16", &why));
  EXPECT_EQ(scenario.lidar3d.rings, 16);
  EXPECT_EQ(scenario.lidar3d.columns, 360);
  EXPECT_TRUE(scenario.is_valid(&why)) << why;
}

}  // namespace
}  // namespace cairn::sim
