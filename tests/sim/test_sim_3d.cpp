// The 3D part: exact ray casts against the ground, boxes and cylinders (hand-computed values),
// the spinning LiDAR's per-point timing (points de-skewed with the true poses land exactly on
// the surfaces; without de-skewing they do not), the pinhole camera's projection, and the
// street-3d scenario's files.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <cstring>

#include "cairn/sim/camera.hpp"
#include "cairn/sim/lidar_3d.hpp"
#include "cairn/sim/ray_cast_3d.hpp"
#include "cairn/sim/scenario.hpp"

namespace cairn::sim {
namespace {

namespace fs = std::filesystem;

TEST(RayCast3D, Ground) {
  EXPECT_EQ(intersect_ground(Vector3(0, 0, 2), Vector3(0, 0, -1)).value_or(-1), 2.0);
  const Vector3 down45(std::sqrt(0.5), 0, -std::sqrt(0.5));
  EXPECT_NEAR(intersect_ground(Vector3(0, 0, 2), down45).value_or(-1), 2.0 * std::numbers::sqrt2, 1e-14);
  EXPECT_FALSE(intersect_ground(Vector3(0, 0, 2), Vector3(0, 0, 1)));
  EXPECT_FALSE(intersect_ground(Vector3(0, 0, 2), Vector3(1, 0, 0)));
}

TEST(RayCast3D, Box) {
  const Box box{Vector3(2, -1, 0), Vector3(3, 1, 2)};
  const Vector3 east(1, 0, 0);
  EXPECT_EQ(intersect(Vector3(0, 0, 1), east, box).value_or(-1), 2.0);
  EXPECT_EQ(intersect(Vector3(2.5, 0, 1), east, box).value_or(-1), 0.5);  // from inside: the far face
  EXPECT_FALSE(intersect(Vector3(0, 0, 2.5), east, box));                  // passes above
  EXPECT_FALSE(intersect(Vector3(4, 0, 1), east, box));                    // box behind
  EXPECT_FALSE(intersect(Vector3(0, 2, 1), east, box));                    // parallel, beside
  // Down onto the top face from (2.5, 0, 10): 8 m.
  EXPECT_EQ(intersect(Vector3(2.5, 0, 10), Vector3(0, 0, -1), box).value_or(-1), 8.0);
}

TEST(RayCast3D, VerticalCylinder) {
  const Cylinder pole{{5, 0}, 1.0, 0.0, 3.0};
  const Vector3 east(1, 0, 0);
  EXPECT_EQ(intersect(Vector3(0, 0, 1), east, pole).value_or(-1), 4.0);   // side
  EXPECT_FALSE(intersect(Vector3(0, 0, 4), east, pole));                  // above the top
  EXPECT_EQ(intersect(Vector3(5, 0, 10), Vector3(0, 0, -1), pole).value_or(-1), 7.0);  // top cap
  EXPECT_EQ(intersect(Vector3(5, 0, 1), east, pole).value_or(-1), 1.0);   // from inside
  // Oblique 3-4-5 in the plane: from the origin towards (3, 4), centre (3, 4) radius 1: 4.
  const Cylinder tree{{3, 4}, 1.0, 0.0, 10.0};
  EXPECT_NEAR(intersect(Vector3(0, 0, 5), Vector3(0.6, 0.8, 0), tree).value_or(-1), 4.0, 1e-15);
}

TEST(RayCast3D, WorldNearestAndCull) {
  World3D world;
  world.boxes.push_back({Vector3(10, -1, 0), Vector3(11, 1, 5)});
  world.cylinders.push_back({{4, 0}, 0.5, 0.0, 1.0});
  const Vector3 east(1, 0, 0);
  EXPECT_EQ(cast_ray(world, Vector3(0, 0, 0.5), east, 100).value_or(-1), 3.5);
  EXPECT_EQ(cast_ray(world, Vector3(0, 0, 2), east, 100).value_or(-1), 10.0);
  EXPECT_FALSE(cast_ray(world, Vector3(0, 0, 2), east, 9.0));
  EXPECT_EQ(nearby(world, Vector2(0, 0), 5.0).boxes.size(), 0u);
  EXPECT_EQ(nearby(world, Vector2(0, 0), 5.0).cylinders.size(), 1u);
}

/// A room [-10, 10]^2 with ground and walls 20 m high: from 1.8 m no ray of a +-15 degree
/// sensor escapes over them.
World3D room() {
  World3D world;
  world.ground = true;
  world.boxes.push_back({Vector3(-11, -11, 0), Vector3(-10, 11, 20)});
  world.boxes.push_back({Vector3(10, -11, 0), Vector3(11, 11, 20)});
  world.boxes.push_back({Vector3(-11, -11, 0), Vector3(11, -10, 20)});
  world.boxes.push_back({Vector3(-11, 10, 0), Vector3(11, 11, 20)});
  return world;
}

/// Distance from a world point to the room's nearest surface.
double surface_distance(const Vector3& p) {
  return std::min({std::abs(p.z()), std::abs(p.x() - 10), std::abs(p.x() + 10), std::abs(p.y() - 10),
                   std::abs(p.y() + 10)});
}

TEST(SpinningLidar, PointsDeskewedWithTheTruePosesLieOnTheSurfaces) {
  Lidar3DOptions options;
  options.range_sigma_m = 0.0;
  options.dropout_probability = 0.0;
  options.columns = 180;
  const double speed = 5.0;  // m/s along x: 0.5 m per revolution
  const auto T_world_lidar_at = [&](double t) { return core::SE3(Quaternion::Identity(), Vector3(speed * t, 0, 1.8)); };
  Random random(1);
  const auto points = spin_scan(room(), 0.0, T_world_lidar_at, options, random);
  ASSERT_EQ(points.size(), static_cast<std::size_t>(options.rings * options.columns));  // a closed room: every ray hits
  double worst_deskewed = 0.0;
  double worst_rigid = 0.0;
  double last_time = 0.0;
  for (const auto& p : points) {
    EXPECT_GE(p.time_offset_s, last_time);
    last_time = p.time_offset_s;
    EXPECT_LT(p.time_offset_s, options.period_s);
    worst_deskewed = std::max(worst_deskewed, surface_distance(T_world_lidar_at(p.time_offset_s) * p.position));
    worst_rigid = std::max(worst_rigid, surface_distance(T_world_lidar_at(0.0) * p.position));
  }
  EXPECT_LT(worst_deskewed, 1e-9);
  EXPECT_GT(worst_rigid, 0.3);  // treating the scan as taken at one instant misplaces points
  EXPECT_EQ(points.front().time_offset_s, 0.0);
}

TEST(SpinningLidar, GroundRingsAtTheClosedFormRange) {
  // Stationary at height h: a ring at elevation e < 0 hits the ground at range h / sin(-e),
  // provided that is within max range (the -1 degree ring reaches it only at 103 m).
  Lidar3DOptions options;
  options.range_sigma_m = 0.0;
  options.dropout_probability = 0.0;
  options.columns = 8;
  World3D ground_only;
  const auto at = [](double) { return core::SE3(Quaternion::Identity(), Vector3(0, 0, 1.8)); };
  Random random(2);
  const auto points = spin_scan(ground_only, 0.0, at, options, random);
  ASSERT_FALSE(points.empty());
  for (const auto& p : points) {
    const double elevation = options.elevation(p.ring);
    ASSERT_LT(elevation, 0.0);  // rays at or above the horizon never hit the ground
    EXPECT_NEAR(p.position.norm(), 1.8 / std::sin(-elevation), 1e-12);
  }
  // Rings -15, -13, ..., -3 degrees: seven reach the ground within 60 m.
  EXPECT_EQ(points.size(), 7u * 8u);
}

TEST(SpinningLidar, RangeNoiseHasTheStatedSigma) {
  Lidar3DOptions options;
  options.range_sigma_m = 0.05;
  options.dropout_probability = 0.1;
  options.columns = 360;
  const auto at = [](double) { return core::SE3(Quaternion::Identity(), Vector3(0, 0, 1.8)); };
  Random random(3);
  std::vector<double> errors;
  std::size_t rays = 0;
  for (int scan = 0; scan < 20; ++scan) {
    for (const auto& p : spin_scan(room(), 0.0, at, options, random)) {
      // The exact range along this point's direction, from the same room without noise.
      const Vector3 direction = p.position.normalized();
      const auto exact = cast_ray(room(), Vector3(0, 0, 1.8), direction, options.max_range_m);
      ASSERT_TRUE(exact.has_value());
      errors.push_back(p.position.norm() - *exact);
    }
    rays += static_cast<std::size_t>(options.rings * options.columns);
  }
  const double n = static_cast<double>(errors.size());
  double mean = 0.0;
  for (double e : errors) mean += e;
  mean /= n;
  double variance = 0.0;
  for (double e : errors) variance += (e - mean) * (e - mean);
  variance /= n - 1;
  EXPECT_NEAR(mean, 0.0, 5.0 * 0.05 / std::sqrt(n));
  EXPECT_NEAR(variance, 0.05 * 0.05, 5.0 * 0.05 * 0.05 * std::sqrt(2.0 / (n - 1)));
  const double kept = n / static_cast<double>(rays);
  EXPECT_NEAR(kept, 0.9, 5.0 * std::sqrt(0.09 / static_cast<double>(rays)));
}

TEST(Camera, ProjectsExactlyAndRespectsOcclusionAndFieldOfView) {
  CameraOptions options;
  options.pixel_sigma = 0.0;
  World3D world;
  world.ground = false;
  world.landmarks.push_back({0, Vector3(10, 0, 1.5)});    // on the optical axis
  world.landmarks.push_back({1, Vector3(10, -1, 1.5)});   // 1 m right (camera x)
  world.landmarks.push_back({2, Vector3(10, 0, 2.5)});    // 1 m up (camera -y)
  world.landmarks.push_back({3, Vector3(-10, 0, 1.5)});   // behind
  world.landmarks.push_back({4, Vector3(20, 5, 1.5)});    // behind the box below
  world.landmarks.push_back({5, Vector3(10, 20, 1.5)});   // outside the image
  world.boxes.push_back({Vector3(15, 3, 0), Vector3(16, 6, 3)});
  const core::SE3 T_world_camera = core::SE3() * options.T_body_camera();  // body at the origin
  Random random(4);
  const auto seen = observe_with_camera(world, T_world_camera, core::Timestamp(), options, random);
  ASSERT_EQ(seen.size(), 3u);
  EXPECT_EQ(seen[0].landmark_id, 0);
  EXPECT_NEAR(seen[0].u_px, 320.0, 1e-9);
  EXPECT_NEAR(seen[0].v_px, 240.0, 1e-9);
  EXPECT_EQ(seen[1].landmark_id, 1);
  EXPECT_NEAR(seen[1].u_px, 320.0 + 500.0 * 1.0 / 10.0, 1e-9);
  EXPECT_EQ(seen[2].landmark_id, 2);
  EXPECT_NEAR(seen[2].v_px, 240.0 - 500.0 * 1.0 / 10.0, 1e-9);
}

TEST(Street3D, RunWritesKittiStyleFilesDeterministically) {
  Scenario scenario = *make_scenario("street-3d");
  scenario.street.loop_width_m = 40.0;
  scenario.street.loop_depth_m = 30.0;
  scenario.lidar3d.columns = 90;
  std::string why;
  ASSERT_TRUE(scenario.is_valid(&why)) << why;
  const fs::path base = fs::temp_directory_path() / ("cairn_test_sim3d_" + std::to_string(::getpid()));
  const SimulationResult result = simulate(scenario, 5);
  const auto files = write_outputs(result, scenario, 5, (base / "a").string());
  fs::create_directories(base / "b");
  write_outputs(simulate(scenario, 5), scenario, 5, (base / "b").string());
  ASSERT_FALSE(result.clouds.empty());
  EXPECT_GE(result.min_clearance_m, 2.0);
  EXPECT_FALSE(result.camera_observations.empty());
  auto bytes = [](const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream out;
    out << in.rdbuf();
    return out.str();
  };
  for (const auto& name : files) EXPECT_EQ(bytes(base / "a" / name), bytes(base / "b" / name)) << name;
  // velodyne/000003.bin holds the cloud as float32 x y z 0, in order.
  const std::string cloud = bytes(base / "a" / "velodyne/000003.bin");
  ASSERT_EQ(cloud.size(), 16 * result.clouds[3].size());
  for (std::size_t i = 0; i < result.clouds[3].size(); i += 17) {
    float xyzi[4];
    std::memcpy(xyzi, cloud.data() + 16 * i, sizeof xyzi);
    EXPECT_EQ(xyzi[0], static_cast<float>(result.clouds[3][i].position.x()));
    EXPECT_EQ(xyzi[2], static_cast<float>(result.clouds[3][i].position.z()));
    EXPECT_EQ(xyzi[3], 0.0F);
  }
  EXPECT_EQ(bytes(base / "a" / "velodyne_times/000003.bin").size(), 4 * result.clouds[3].size());
  std::error_code ignored;
  fs::remove_all(base, ignored);
}

}  // namespace
}  // namespace cairn::sim
