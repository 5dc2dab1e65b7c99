#pragma once
/// \file
/// `cairn slam3d --mcap FILE`: every processed scan's sensor pose with its health, the global map
/// and the accepted loop closures as an MCAP file Foxglove shows (bag/foxglove_results.hpp),
/// written whole or not at all.

#include <string>

#include "cairn/lidar3d/slam.hpp"
#include "cairn/lidar3d/slam_run.hpp"

namespace cairn::lidar3d {

/// After SlamRun::finish: the poses written are those trajectory.tum holds.
void write_foxglove_mcap(const std::string& path, const LidarSlam& slam, const SlamRun& run);

}  // namespace cairn::lidar3d
