#pragma once
/// \file
/// The lidar3d configuration as YAML: every key of LidarSlamOptions (with its LidarOdometryOptions,
/// RegistrationOptions, LoamFeatureOptions and ScanContextOptions) and of the LiDAR-inertial fusion
/// (InertialFusionOptions, section `imu`) under a section, each with what it means (`cairn slam3d
/// --print-config` prints them with their values). Files may set any subset; unknown keys and
/// wrong types are errors naming the file and line. report.json's "options" is
/// configuration().json of the options in effect (without the `imu` section when the run had no IMU).
///
///   odometry:
///     voxel_size_m: 0.5
///   loop_closure:
///     min_fitness: 0.7

#include <nlohmann/json.hpp>
#include <string>

#include "cairn/io/parameters.hpp"
#include "cairn/lidar3d/inertial_fusion.hpp"
#include "cairn/lidar3d/slam.hpp"

namespace cairn::lidar3d {

/// What the configuration describes: LidarSlam's options and the fusion's, used when a run has an
/// IMU (lidar_inertial_slam.hpp). The fusion's `noise` and `T_imu_lidar` are not keys: they come
/// from the IMU's and the LiDAR's sensor.yaml (inertial_input.hpp); `imu.gravity_mps2` sets both
/// `gravity_mps2` and `initialization.gravity_mps2` (inertial_fusion_options).
struct SlamConfiguration {
  LidarSlamOptions slam;
  InertialFusionOptions imu;
  /// Both checked, every problem at once (the fusion's prefixed "imu: ").
  bool is_valid(std::string* why) const;
};

/// The keys: pointers into `options`, each with its section, name and meaning. Enums are words:
/// odometry.front_end (to_string(FrontEnd)), odometry.deskew (to_string(DeskewMode)),
/// registration.metric (point-to-plane, point-to-point); scan_context.lateral_offsets_m is
/// "-4 -2 2 4" (slam_scan_context_options) or "none".
io::Parameters parameters(SlamConfiguration& options);
/// set / load / yaml (--print-config) / json (report.json's "options") over parameters().
const io::Configuration<SlamConfiguration>& configuration();

}  // namespace cairn::lidar3d
