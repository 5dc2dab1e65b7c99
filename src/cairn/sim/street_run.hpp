#pragma once
/// \file
/// The street-3d scenario's sensors and files (used by scenario.cpp): the spinning LiDAR and
/// the camera along the ground truth, and the KITTI-style output.

#include <cstdint>
#include <string>
#include <vector>

#include "cairn/sim/scenario.hpp"

namespace cairn::sim {

/// The 2D footprint of a 3D world (boxes as rectangles, cylinders as circles; landmarks dropped),
/// for pictures and clearance checks.
World footprint(const World3D& world);

/// Fills result.world_3d, result.clouds (one per scan sample) and result.camera_observations.
/// Needs result.truth and result.scan_samples.
void simulate_street_sensors(const Scenario& scenario, std::uint64_t lidar_seed, std::uint64_t camera_seed,
                             SimulationResult& result);

/// Writes the street files into `directory` (creating its sub-folders) and returns their names.
std::vector<std::string> write_street_outputs(const SimulationResult& result, const Scenario& scenario,
                                              const std::string& directory);

}  // namespace cairn::sim
