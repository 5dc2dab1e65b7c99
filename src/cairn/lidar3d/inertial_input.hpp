#pragma once
/// \file
/// The IMU of a `cairn slam3d --imu` run, from what the user names: the samples (EuRoC's imu0
/// folder or data.csv, a plain IMU CSV, or sensor_msgs/Imu from a bag: inertial/imu_csv.hpp), the
/// noise (an EuRoC/Kalibr sensor.yaml: inertial/euroc_files.hpp), the LiDAR's pose in the IMU frame
/// (a sensor.yaml's T_BS: inertial/euroc_files.hpp read_euroc_T_BS) and a constant time offset, each with its default
/// found beside the IMU's files and a note saying which was taken; and the fusion's options
/// (lidar_inertial_slam.hpp) they give.
///
/// Frames: the fusion's body is the IMU (samples stay in the IMU's frame, so the accelerometer's
/// lever arm is not neglected), and T_imu_lidar = T_body_imu^-1 T_body_lidar from the two T_BS
/// (EuRoC's: each sensor in the same body frame). Without an IMU sensor.yaml, T_body_imu = I.

#include <filesystem>
#include <string>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/inertial/imu_input.hpp"
#include "cairn/inertial/imu_source.hpp"
#include "cairn/inertial/imu_types.hpp"
#include "cairn/lidar3d/inertial_fusion.hpp"
#include "cairn/lidar3d/slam.hpp"

namespace cairn::lidar3d {

/// Where the IMU is and what is known about it (the flags of `cairn slam3d`).
struct InertialInputRequest {
  /// --imu or the scans' bag with --imu-topic, --imu-calibration, --imu-time-offset
  /// (inertial/imu_source.hpp).
  inertial::ImuSourceRequest imu;
  /// --lidar-extrinsic: a sensor.yaml whose T_BS is the LiDAR in the body frame. Empty:
  /// lidar0/sensor.yaml beside the IMU's folder (in its parent) when there is one, else the identity.
  std::filesystem::path lidar_extrinsic;
};

/// The IMU as read, with what was assumed.
struct InertialInput {
  std::string source;         ///< the IMU's file, folder or bag as read; "BAG topic T" for a topic
  std::string calibration_file;      ///< empty: ADIS16448 defaults
  std::string lidar_extrinsic_file;  ///< empty: identity
  /// IMU frame, stamps on the scans' clock (time_offset_s added), strictly increasing.
  std::vector<inertial::ImuSample> samples;
  /// Rates, gaps, saturation and statistics of the samples as recorded (inertial::check_imu_data).
  inertial::ImuDataReport checks;
  inertial::ImuNoise noise;
  core::SE3 T_body_imu;    ///< the IMU sensor.yaml's T_BS
  core::SE3 T_body_lidar;  ///< the LiDAR sensor.yaml's T_BS
  double time_offset_s = 0.0;
  /// Defaults taken and readers' warnings, one sentence each, for the terminal and the report.
  std::vector<std::string> notes;

  core::SE3 T_imu_lidar() const { return T_body_imu.inverse() * T_body_lidar; }
};

/// Reads the IMU of `request`. Throws io::ParseError (file and line, or bag, topic and message)
/// for bad data or calibration files, std::invalid_argument for a bad time offset or a request
/// naming no IMU.
InertialInput read_inertial_input(const InertialInputRequest& request);

/// The fusion's options: `configured` (the `imu` section of the configuration) with the input's
/// noise and T_imu_lidar, and its gravity_mps2 also the static initialisation's.
InertialFusionOptions inertial_fusion_options(const InertialFusionOptions& configured, const InertialInput& input);

/// What running with an IMU changes in LidarSlam's options: degenerate directions are solved from
/// the prediction (registration.remap_degenerate_directions), since the IMU's prediction carries
/// them (the LOAM front end always remaps; the dense one only when asked, as its own constant-
/// velocity prediction would not). Returns whether it was off before.
bool prepare_for_inertial(LidarSlamOptions& options);

}  // namespace cairn::lidar3d
