// Voxel-hash map, subsampling and point-to-point registration (lidar3d/registration.hpp) on
// synthetic geometry with known answers and on a real scan pair with its reference pose.

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <fstream>
#include <random>
#include <set>
#include <sstream>

#include "cairn/io/point_cloud.hpp"
#include "cairn/lidar3d/registration.hpp"
#include "cairn/lidar3d/voxel_hash_map.hpp"
#include "test_data.hpp"

namespace cairn::lidar3d {
namespace {

std::vector<Eigen::Vector3d> to_double(const io::PointCloud& cloud) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(cloud.size());
  for (const Eigen::Vector3f& p : cloud.points) out.push_back(p.cast<double>());
  return out;
}

std::vector<Eigen::Vector3d> transform(const core::SE3& T, std::vector<Eigen::Vector3d> points) {
  for (Eigen::Vector3d& p : points) p = T * p;
  return points;
}

// Points on the faces of an axis-aligned box, every `step` metres; `open_ends` leaves out the two
// faces normal to x (a straight tunnel along x).
std::vector<Eigen::Vector3d> box_surface(const Eigen::Vector3d& half, double step, bool open_ends) {
  std::vector<Eigen::Vector3d> points;
  for (double a = -half.x(); a <= half.x(); a += step) {
    for (double b = -half.y(); b <= half.y(); b += step) {
      points.emplace_back(a, b, -half.z());
      points.emplace_back(a, b, half.z());
    }
    for (double c = -half.z(); c <= half.z(); c += step) {
      points.emplace_back(a, -half.y(), c);
      points.emplace_back(a, half.y(), c);
    }
  }
  if (!open_ends) {
    for (double b = -half.y(); b <= half.y(); b += step) {
      for (double c = -half.z(); c <= half.z(); c += step) {
        points.emplace_back(-half.x(), b, c);
        points.emplace_back(half.x(), b, c);
      }
    }
  }
  return points;
}

TEST(VoxelDownsample, KeepsTheFirstPointOfEachVoxelInInputOrder) {
  const std::vector<Eigen::Vector3d> points = {{0.1, 0.1, 0.1}, {0.9, 0.2, 0.3}, {1.2, 0.1, 0.1},
                                               {-0.1, 0.1, 0.1}, {1.9, 0.9, 0.9}, {0.5, 0.5, 0.5}};
  const std::vector<Eigen::Vector3d> out = voxel_downsample(points, 1.0);
  // Voxels: (0,0,0) (0,0,0) (1,0,0) (-1,0,0) (1,0,0) (0,0,0).
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[0], points[0]);
  EXPECT_EQ(out[1], points[2]);
  EXPECT_EQ(out[2], points[3]);
}

// The first point of each voxel in input order, by std::set of floor triples: the reference for
// the packed open-addressing table, near the origin, around the packing's limits (2^20 voxels)
// and far beyond them (the node-based path).
TEST(VoxelDownsample, MatchesASetOfFloorTriplesNearAndFarFromTheOrigin) {
  std::mt19937 rng(7);
  for (const double centre : {0.0, 262143.0, -262144.5, 3.0e6, -2.0e8}) {
    std::uniform_real_distribution<double> u(-40.0, 40.0);
    std::vector<Eigen::Vector3d> points;
    for (int i = 0; i < 20000; ++i) points.emplace_back(centre + u(rng), u(rng), 0.1 * u(rng));
    for (const double voxel : {0.25, 1.0}) {
      std::set<std::array<double, 3>> seen;
      std::vector<Eigen::Vector3d> expected;
      for (const Eigen::Vector3d& p : points) {
        if (seen.insert({std::floor(p.x() / voxel), std::floor(p.y() / voxel), std::floor(p.z() / voxel)}).second) expected.push_back(p);
      }
      const std::vector<Eigen::Vector3d> out = voxel_downsample(points, voxel);
      ASSERT_EQ(out.size(), expected.size()) << "centre " << centre << " voxel " << voxel;
      for (std::size_t i = 0; i < out.size(); ++i) ASSERT_EQ(out[i], expected[i]) << "centre " << centre << " voxel " << voxel << " point " << i;
    }
  }
}

TEST(VoxelHashMap, NearestMatchesBruteForceWithinOneVoxel) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coordinate(-5.0, 5.0);
  std::vector<Eigen::Vector3d> stored;
  for (int i = 0; i < 2000; ++i) stored.emplace_back(coordinate(rng), coordinate(rng), coordinate(rng));
  VoxelHashMap map(VoxelHashMapOptions{1.0, 1000});
  map.add_points(stored);
  EXPECT_EQ(map.num_points(), stored.size());
  int checked = 0;
  for (int i = 0; i < 500; ++i) {
    const Eigen::Vector3d q(coordinate(rng), coordinate(rng), coordinate(rng));
    double best = 1e300;
    for (const Eigen::Vector3d& p : stored) best = std::min(best, (p - q).squaredNorm());
    Eigen::Vector3d found;
    double d2 = 0.0;
    const bool ok = map.nearest(q, &found, &d2);
    if (best <= 1.0) {  // within one voxel edge: the 27 voxels around q must contain it
      ASSERT_TRUE(ok);
      EXPECT_DOUBLE_EQ(d2, best);
      ++checked;
    }
  }
  EXPECT_GT(checked, 400);
}

TEST(VoxelHashMap, CapsPointsPerVoxelAndDropsFarVoxels) {
  VoxelHashMap map(VoxelHashMapOptions{1.0, 3});
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 10; ++i) points.emplace_back(0.05 * i, 0.5, 0.5);
  points.emplace_back(50.5, 0.5, 0.5);
  map.add_points(points);
  EXPECT_EQ(map.num_voxels(), 2u);
  EXPECT_EQ(map.num_points(), 4u);
  map.remove_far_from(Eigen::Vector3d::Zero(), 10.0);
  EXPECT_EQ(map.num_voxels(), 1u);
  EXPECT_EQ(map.num_points(), 3u);
}

TEST(Registration, RecoversAKnownMotionInABox) {
  const std::vector<Eigen::Vector3d> world = box_surface({10.0, 6.0, 3.0}, 0.2, /*open_ends=*/false);
  VoxelHashMap map(VoxelHashMapOptions{0.5, 20});
  map.add_points(world);
  const core::SE3 T_world_sensor(core::SO3::from_rpy(0.02, -0.01, 0.1), Eigen::Vector3d(0.4, -0.3, 0.05));
  const std::vector<Eigen::Vector3d> scan = voxel_downsample(transform(T_world_sensor.inverse(), world), 0.4);
  const RegistrationResult r = register_scan(map, scan, core::SE3(), 2.0, 0.3);
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.degenerate_directions, 0);
  EXPECT_GT(r.translation_degeneracy, 0.1);
  const core::SE3 error = T_world_sensor.inverse() * r.T_map_sensor;
  EXPECT_LT(error.translation().norm(), 0.01);
  EXPECT_LT(error.so3().log().norm(), 1e-3);
}

TEST(Registration, ATunnelIsDegenerateAlongItsAxisAndRemappingKeepsThePriorThere) {
  // Walls, floor and ceiling, no ends: sliding along x changes nothing the scan sees.
  const std::vector<Eigen::Vector3d> world = box_surface({40.0, 4.0, 3.0}, 0.2, /*open_ends=*/true);
  VoxelHashMap map(VoxelHashMapOptions{0.5, 20});
  map.add_points(world);
  const core::SE3 T_world_sensor(core::SO3::from_rpy(0.0, 0.0, 0.05), Eigen::Vector3d(0.0, 0.3, 0.1));
  std::vector<Eigen::Vector3d> scan;
  for (const Eigen::Vector3d& p : transform(T_world_sensor.inverse(), world)) {
    if (p.norm() < 25.0) scan.push_back(p);  // the sensor sees 25 m either way, never an end
  }
  scan = voxel_downsample(scan, 0.4);
  // The prior is 0.7 m off along the tunnel and 0.2 m across it.
  const core::SE3 guess(core::SO3(), Eigen::Vector3d(0.7, 0.1, 0.1));
  RegistrationOptions options;
  options.remap_degenerate_directions = true;
  const RegistrationResult r = register_scan(map, scan, guess, 2.0, 0.3, options);
  EXPECT_TRUE(r.converged);
  EXPECT_GE(r.degenerate_directions, 1);
  std::printf("tunnel: translation degeneracy %.3g, 6-DoF eigenvalues %s\n", r.translation_degeneracy,
              (std::ostringstream() << r.eigenvalues.transpose()).str().c_str());
  EXPECT_LT(r.translation_degeneracy, 1e-3);
  EXPECT_EQ(r.degenerate_directions, 1);
  EXPECT_EQ(name_direction(r.weakest_direction, r.T_map_sensor.so3(), r.characteristic_length_m), "x (forward)");
  // Across the tunnel and in yaw the scan decides; along it the prior stays.
  EXPECT_NEAR(r.T_map_sensor.translation().y(), 0.3, 0.01);
  EXPECT_NEAR(r.T_map_sensor.translation().z(), 0.1, 0.01);
  EXPECT_NEAR(r.T_map_sensor.translation().x(), 0.7, 0.02);
}

TEST(Registration, RealScanPairMatchesTheReferencePose) {
  CAIRN_REQUIRE_DATA("lidar3d/small_gicp_pair/source.ply");
  const auto source = to_double(io::read_point_cloud(test::data_path("lidar3d/small_gicp_pair/source.ply").string()));
  const auto target = to_double(io::read_point_cloud(test::data_path("lidar3d/small_gicp_pair/target.ply").string()));
  Eigen::Matrix4d T_ref;
  std::ifstream in(test::data_path("lidar3d/small_gicp_pair/T_target_source.txt"));
  for (int i = 0; i < 16; ++i) in >> T_ref(i / 4, i % 4);
  ASSERT_TRUE(in);
  const core::SE3 T_target_source = core::SE3::from_matrix(T_ref);

  // KISS-ICP's recipe at a 0.5 m map voxel: map from the target at v/2, source at 1.5 v.
  VoxelHashMap map(VoxelHashMapOptions{0.5, 20});
  map.add_points(voxel_downsample(target, 0.25));
  const auto source_points = voxel_downsample(voxel_downsample(source, 0.25), 0.75);
  // From identity, 0.5 m and 0.7 deg away, a 1.5 m correspondence threshold then a 0.3 m one.
  RegistrationResult r = register_scan(map, source_points, core::SE3(), 1.5, 0.5);
  r = register_scan(map, source_points, r.T_map_sensor, 0.3, 0.1);
  EXPECT_TRUE(r.converged);
  const core::SE3 error = T_target_source.inverse() * r.T_map_sensor;
  // The reference is small_gicp's own GICP result, not ground truth. Measured: this ICP ends
  // 5 mm and 0.32 deg (mostly yaw and roll) from it, the same from identity as from the
  // reference itself and at map voxels of 0.25, 0.5 and 1 m with either metric, so the two
  // objectives have their optima that far apart on this sparse pair.
  EXPECT_LT(error.translation().norm(), 0.02) << "translation error " << error.translation().transpose();
  EXPECT_LT(error.so3().log().norm(), 0.5 * M_PI / 180.0);
  EXPECT_GT(static_cast<double>(r.correspondences) / static_cast<double>(r.source_points), 0.6);
}

}  // namespace
}  // namespace cairn::lidar3d
