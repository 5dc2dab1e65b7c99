// LOAM's features (lidar3d/loam_features.hpp) and the feature registration (register_features) on
// a synthetic spinning scan of a box room with a pole, where edges and planes are known.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "cairn/lidar3d/loam_features.hpp"
#include "cairn/lidar3d/registration.hpp"

namespace cairn::lidar3d {
namespace {

// A 16-ring, 900-column scan from `T_room_sensor` of a room [-10, 10] x [-6, 6] x [-2, 4] (floor,
// ceiling, walls) with a vertical pole of radius 0.15 m at (4, 3).
struct Scan {
  std::vector<Eigen::Vector3d> points;
  std::vector<std::uint16_t> ring;
};

Scan scan_room(const core::SE3& T_room_sensor) {
  Scan scan;
  const Eigen::Matrix3d R = T_room_sensor.rotation_matrix();
  const Eigen::Vector3d o = T_room_sensor.translation();
  for (int r = 0; r < 16; ++r) {
    const double elevation = (-15.0 + 2.0 * r) * std::numbers::pi / 180.0;
    for (int c = 0; c < 900; ++c) {
      const double azimuth = -std::numbers::pi + 2.0 * std::numbers::pi * c / 900.0;
      const Eigen::Vector3d d_sensor(std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth),
                                     std::sin(elevation));
      const Eigen::Vector3d d = R * d_sensor;
      double best = 1e9;
      for (int axis = 0; axis < 3; ++axis) {  // the six faces
        const double lo[] = {-10.0, -6.0, -2.0}, hi[] = {10.0, 6.0, 4.0};
        if (std::abs(d(axis)) < 1e-9) continue;
        for (double bound : {lo[axis], hi[axis]}) {
          const double s = (bound - o(axis)) / d(axis);
          if (s > 0.0 && s < best) best = s;
        }
      }
      // The pole: |(o + s d - c)_xy| = radius.
      const Eigen::Vector2d oc = o.head<2>() - Eigen::Vector2d(4.0, 3.0);
      const Eigen::Vector2d dxy = d.head<2>();
      const double a = dxy.squaredNorm(), b = 2.0 * oc.dot(dxy), cc = oc.squaredNorm() - 0.15 * 0.15;
      const double disc = b * b - 4.0 * a * cc;
      if (a > 1e-12 && disc >= 0.0) {
        const double s = (-b - std::sqrt(disc)) / (2.0 * a);
        if (s > 0.0 && s < best) best = s;
      }
      scan.points.push_back(best * d_sensor);
      scan.ring.push_back(static_cast<std::uint16_t>(r));
    }
  }
  return scan;
}

TEST(LoamFeatures, EdgesOnCornersAndThePoleAndFlatPointsOnWalls) {
  const Scan scan = scan_room(core::SE3(core::SO3(), Eigen::Vector3d(0.5, -0.5, 0.0)));
  const LoamFeatures f = extract_loam_features(scan.points, scan.ring);
  ASSERT_FALSE(f.sharp.empty());
  ASSERT_FALSE(f.flat.empty());
  // Every sharp point is near a vertical corner of the room, the pole, or a floor/ceiling edge.
  const Eigen::Vector3d sensor(0.5, -0.5, 0.0);
  for (const Eigen::Vector3d& p_sensor : f.sharp) {
    const Eigen::Vector3d p = p_sensor + sensor;
    const bool corner = (std::abs(std::abs(p.x()) - 10.0) < 0.6 && std::abs(std::abs(p.y()) - 6.0) < 0.6);
    const bool pole = (p.head<2>() - Eigen::Vector2d(4.0, 3.0)).norm() < 0.6;
    const bool horizontal_edge = (std::abs(p.z() + 2.0) < 0.6 || std::abs(p.z() - 4.0) < 0.6) &&
                                 (std::abs(std::abs(p.x()) - 10.0) < 0.6 || std::abs(std::abs(p.y()) - 6.0) < 0.6);
    EXPECT_TRUE(corner || pole || horizontal_edge) << p.transpose();
  }
  EXPECT_LE(f.sharp.size(), 16u * 6u * 2u);
  EXPECT_LE(f.flat.size(), 16u * 6u * 4u);
  EXPECT_GE(f.less_sharp.size(), f.sharp.size());
  EXPECT_GE(f.less_flat.size(), f.flat.size() / 2);
}

TEST(LoamFeatures, RegistrationRecoversAMotionInTheRoom) {
  // The map: three scans from nearby places, as an odometry would have built it.
  VoxelHashMap edge_map(VoxelHashMapOptions{1.0, 20}), plane_map(VoxelHashMapOptions{1.0, 20});
  for (const Eigen::Vector3d& o : {Eigen::Vector3d(0.0, 0.0, 0.0), Eigen::Vector3d(0.3, 0.2, 0.0), Eigen::Vector3d(-0.3, 0.1, 0.0)}) {
    const Scan scan = scan_room(core::SE3(core::SO3(), o));
    const LoamFeatures f = extract_loam_features(scan.points, scan.ring);
    std::vector<Eigen::Vector3d> edges, planes;
    for (const Eigen::Vector3d& p : f.less_sharp) edges.push_back(p + o);
    for (const Eigen::Vector3d& p : f.less_flat) planes.push_back(p + o);
    edge_map.add_points(edges);
    plane_map.add_points(planes);
  }
  const core::SE3 T_room_sensor(core::SO3::from_rpy(0.0, 0.0, 0.08), Eigen::Vector3d(0.4, -0.25, 0.05));
  const Scan scan = scan_room(T_room_sensor);
  const LoamFeatures f = extract_loam_features(scan.points, scan.ring);
  RegistrationResult r = register_features(edge_map, plane_map, f.sharp, f.flat, core::SE3(), 2.0, 0.6);
  r = register_features(edge_map, plane_map, f.sharp, f.flat, r.T_map_sensor, 0.5, 0.15);
  EXPECT_TRUE(r.converged);
  const core::SE3 error = T_room_sensor.inverse() * r.T_map_sensor;
  EXPECT_LT(error.translation().norm(), 0.05) << error.translation().transpose();
  EXPECT_LT(error.so3().log().norm(), 0.005);
  EXPECT_EQ(r.degenerate_directions, 0);
}

TEST(LoamFeatures, RingsWithTooFewPointsGiveNothingAndMismatchedInputIsEmpty) {
  std::vector<Eigen::Vector3d> points(8, Eigen::Vector3d(5.0, 0.0, 0.0));
  std::vector<std::uint16_t> ring(8, 0);
  EXPECT_TRUE(extract_loam_features(points, ring).sharp.empty());
  ring.pop_back();
  EXPECT_TRUE(extract_loam_features(points, ring).less_flat.empty());
}

}  // namespace
}  // namespace cairn::lidar3d
