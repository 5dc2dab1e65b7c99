#pragma once
/// \file
/// The 3D scenarios' sensors and files (used by scenario.cpp): the spinning LiDAR and the camera
/// along the ground truth, and the KITTI-style or PCD output.

#include <cstdint>
#include <string>
#include <vector>

#include "cairn/sim/scenario.hpp"

namespace cairn::sim {

/// The 2D footprint of a 3D world (boxes as rectangles, cylinders as circles; landmarks, moving
/// boxes and boxes entirely above 2.2 m, such as ceilings, beams and lintels the vehicle drives
/// under, dropped), for pictures and clearance checks.
World footprint(const World3D& world);

/// T_world_lidar: the body pose lifted to 3D with the LiDAR mount_height_m above it.
core::SE3 lidar_pose(const core::SE2& T_world_body, const Lidar3DOptions& lidar);

/// Fills result.world_3d, result.clouds (one per scan sample) and result.camera_observations.
/// Needs result.truth and result.scan_samples.
void simulate_street_sensors(const Scenario& scenario, std::uint64_t lidar_seed, std::uint64_t camera_seed,
                             SimulationResult& result);

/// Writes the 3D files into `directory` (creating its sub-folders) and returns their names.
std::vector<std::string> write_street_outputs(const SimulationResult& result, const Scenario& scenario,
                                              const std::string& directory);

}  // namespace cairn::sim
