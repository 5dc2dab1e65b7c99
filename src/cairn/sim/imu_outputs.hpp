#pragma once
/// \file
/// The simulated IMU's files and manifest entry (3D worlds, used by scenario.cpp and manifest.cpp):
///  * `imu0/data.csv`, `imu0/sensor.yaml`: EuRoC's layout (inertial/euroc_files.hpp), stamps on
///    the IMU's clock (true time + imu.time_offset_s), T_BS = T_body_imu = identity;
///  * `state_groundtruth_estimate0/data.csv`: the true pose, velocity and biases at every IMU
///    sample, stamped with true time (the clock of ground_truth.tum, times.txt and the scans);
///  * `lidar0/sensor.yaml`: the LiDAR's extrinsic T_BS = T_body_lidar in EuRoC's sensor.yaml
///    layout (sensor_type lidar), and its rate.
/// The manifest's `imu` object repeats the model, the numbers used, the drawn initial biases and
/// the extrinsics of the IMU, LiDAR and camera.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cairn/sim/scenario.hpp"

namespace cairn::sim {

/// The 16 numbers of a 4x4 row-major matrix: how the manifests write a transform.
std::vector<double> row_major(const core::SE3& T);

/// T_body_lidar of the 3D worlds' LiDAR: mount_height_m straight above the body origin, axes
/// parallel to the body's (sim/street_run.hpp lidar_pose).
core::SE3 T_body_lidar(const Lidar3DOptions& lidar);

/// Writes the IMU files into `directory` (creating imu0/, state_groundtruth_estimate0/ and
/// lidar0/) and returns their names. Precondition: scenario.imu_enabled and result.imu filled.
std::vector<std::string> write_imu_outputs(const SimulationResult& result, const Scenario& scenario,
                                           const std::string& directory);

/// The manifest's `imu` object.
nlohmann::json imu_manifest(const SimulationResult& result, const Scenario& scenario);

}  // namespace cairn::sim
