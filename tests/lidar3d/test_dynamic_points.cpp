// Free-space carving of points seen on moving objects (lidar3d/dynamic_points.hpp) in the
// simulated street with cars driving around the block, with exact ground truth: every point is
// placed in the world by the true sensor pose at its own firing time, and it is dynamic when it
// lies on a moving car's box at that time (sim::MovingBox::at, 10 cm of slack). The keyframes are
// every third scan (1.2 m apart at 4 m/s), their points in their own frame at the scan's start,
// one per 0.5 m voxel as the odometry keeps a keyframe's points; the carving sees only those
// keyframes and their poses; the map is every point of those scans. Issue 42 asks for at least
// 90 % of the dynamic points removed and 99 % of the static ones kept. The poses are the true ones
// here: what the carving does, apart from SLAM's error. The options were chosen on this run (seed
// 1, world 5): 92.5 % / 99.89 %; measured with the same options on noise seed 2: 92.5 / 99.89 %;
// on worlds 11 and 12: 92.4 / 99.86 and 92.9 / 99.88 %.

#include <gtest/gtest.h>

#include <cstdio>

#include "cairn/lidar3d/dynamic_points.hpp"
#include "cairn/lidar3d/voxel_hash_map.hpp"
#include "cairn/sim/scenario.hpp"
#include "cairn/sim/street_run.hpp"

namespace cairn::lidar3d {
namespace {

bool on_moving_car(const sim::World3D& world, const Eigen::Vector3d& p, double time_s) {
  for (const sim::MovingBox& car : world.moving_boxes) {
    const sim::Box box = car.at(time_s);
    if ((p.array() >= box.min.array() - 0.1).all() && (p.array() <= box.max.array() + 0.1).all()) return true;
  }
  return false;
}

TEST(DynamicPoints, CarsDrivingByAreRemovedAndTheStreetIsKept) {
  sim::Scenario scenario = *sim::make_scenario("street-3d");
  scenario.street.moving_cars = 6;
  const sim::SimulationResult s = sim::simulate(scenario, 1);
  ASSERT_FALSE(s.world_3d.moving_boxes.empty());
  const double sample_period = s.truth[1].stamp.seconds() - s.truth[0].stamp.seconds();

  std::vector<std::vector<Eigen::Vector3d>> keyframe_points;
  std::vector<KeyframeRays> keyframes;
  std::vector<Eigen::Vector3f> map_points;
  std::vector<bool> truly_dynamic;
  keyframe_points.reserve(s.clouds.size() / 3 + 1);
  for (std::size_t k = 0; k < s.clouds.size(); k += 3) {
    const core::SE3 T_world_kf = sim::lidar_pose(s.truth[s.scan_samples[k]].T_world_body, scenario.lidar3d);
    std::vector<Eigen::Vector3d> points;
    for (const sim::LidarPoint& p : s.clouds[k]) {
      const auto sample = std::min(s.truth.size() - 1, s.scan_samples[k] + static_cast<std::size_t>(std::lround(p.time_offset_s / sample_period)));
      const Eigen::Vector3d world = sim::lidar_pose(s.truth[sample].T_world_body, scenario.lidar3d) * p.position;
      points.push_back(T_world_kf.inverse() * world);
      map_points.push_back(world.cast<float>());
      truly_dynamic.push_back(on_moving_car(s.world_3d, world, s.truth[s.scan_samples[k]].stamp.seconds() + p.time_offset_s));
    }
    // As the odometry keeps a keyframe's points: one per 0.5 m voxel (half its 1 m voxel).
    keyframe_points.push_back(voxel_downsample(points, 0.5));
  }
  for (std::size_t i = 0; i < keyframe_points.size(); ++i) keyframes.push_back({&keyframe_points[i], sim::lidar_pose(s.truth[s.scan_samples[3 * i]].T_world_body, scenario.lidar3d)});

  DynamicPointSummary summary;
  const std::vector<bool> found = find_dynamic_points(map_points, keyframes, DynamicPointOptions{}, &summary);
  std::size_t dynamic = 0, removed_dynamic = 0, static_points = 0, kept_static = 0;
  for (std::size_t i = 0; i < map_points.size(); ++i) {
    if (truly_dynamic[i]) {
      ++dynamic;
      removed_dynamic += found[i] ? 1 : 0;
    } else {
      ++static_points;
      kept_static += found[i] ? 0 : 1;
    }
  }
  const double removed = static_cast<double>(removed_dynamic) / static_cast<double>(dynamic);
  const double kept = static_cast<double>(kept_static) / static_cast<double>(static_points);
  std::printf("%zu keyframes, %zu points (%zu on moving cars): %.1f %% of the dynamic points removed, %.2f %% of the static "
              "kept; %zu rays, %zu ground points exempt, %.2f s\n",
              keyframes.size(), map_points.size(), dynamic, 100.0 * removed, 100.0 * kept, summary.rays,
              summary.ground_exempt, summary.time_s);
  ASSERT_GT(dynamic, 1000u) << "the cars must be seen, or this tests nothing";
  EXPECT_GE(removed, 0.90);
  EXPECT_GE(kept, 0.99);
}

}  // namespace
}  // namespace cairn::lidar3d
