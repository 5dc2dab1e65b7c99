#pragma once
/// \file
/// A simulated LiDAR revolution (sim/lidar_3d.hpp) as the point cloud a scan file would give:
/// sensor-frame points, per-point times from the sweep's start and rings, for the lidar3d tests
/// that feed the simulator's scans to the pipelines.

#include <cstdint>
#include <vector>

#include "cairn/io/point_cloud.hpp"
#include "cairn/sim/lidar_3d.hpp"

namespace cairn::test {

inline io::PointCloud to_point_cloud(const std::vector<sim::LidarPoint>& revolution) {
  io::PointCloud cloud;
  cloud.points.reserve(revolution.size());
  cloud.time_s.reserve(revolution.size());
  cloud.ring.reserve(revolution.size());
  for (const sim::LidarPoint& p : revolution) {
    cloud.points.push_back(p.position.cast<float>());
    cloud.time_s.push_back(static_cast<float>(p.time_offset_s));
    cloud.ring.push_back(static_cast<std::uint16_t>(p.ring));
  }
  return cloud;
}

}  // namespace cairn::test
