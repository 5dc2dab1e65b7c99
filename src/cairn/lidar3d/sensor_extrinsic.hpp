#pragma once
/// \file
/// A sensor's extrinsic from EuRoC's sensor.yaml layout (Burri et al., IJRR 2016; mav0/<sensor>/
/// sensor.yaml): `T_BS`, the sensor in the body frame, as {rows: 4, cols: 4, data: [16 numbers,
/// row-major]}. The simulator writes the LiDAR's this way (lidar0/sensor.yaml, docs/simulation.md
/// "Simulated IMU"); `cairn slam3d --lidar-extrinsic` reads it.

#include <filesystem>

#include "cairn/core/se3.hpp"

namespace cairn::lidar3d {

/// T_BS of the sensor.yaml at `path` (or in the folder `path`). Other keys (sensor_type, comment,
/// rate_hz, noise) are ignored. T_BS must be a rigid transform: last row 0 0 0 1, rotation block
/// orthonormal to 1e-6 with det > 0. Throws io::ParseError naming the file and line for a file
/// that is missing, not YAML, larger than 1 MiB, without T_BS, or with a bad T_BS.
core::SE3 read_sensor_extrinsic(const std::filesystem::path& path);

}  // namespace cairn::lidar3d
