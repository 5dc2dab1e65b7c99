#pragma once
/// \file
/// Static initialisation: while the IMU stands still it measures only its gyro bias (the mean
/// angular rate) and gravity (the mean specific force, -R_world_body^T g). From a still window this
/// gives the gyro bias, roll and pitch (yaw is unobservable from gravity alone and set to 0) and the
/// accelerometer bias along gravity (|mean accel| - g; the other two axes are not separable from a
/// tilt). The same as VINS-Mono's and OpenVINS' static initialisers (OpenVINS
/// ov_init/static/StaticInitializer.cpp, which also first checks that the window is still).

#include <string>
#include <vector>

#include "cairn/inertial/imu_types.hpp"

namespace cairn::inertial {

struct StaticInitializationOptions {
  /// Length of the window, seconds from the first sample, > 0.
  double window_s = 2.0;
  /// The window counts as still when the means of its blocks of block_s seconds agree with the
  /// window's mean to within gyro_block_spread_max_rad_s (every gyro axis) and
  /// accel_block_spread_max_mps2 (every accelerometer axis). Block means, not the samples' spread:
  /// a multirotor's spinning rotors or an idling engine shake the IMU (EuRoC's MAV on the ground:
  /// 0.04 rad/s and 0.57 m/s^2 standard deviation over its first 5 s) without moving it, while a
  /// motion changes the mean from block to block. A limit below 4 standard errors of a block mean
  /// (the axis' standard deviation / sqrt(block samples)) is raised to that, so vibration alone never
  /// fails the test. Constant acceleration looks like a tilt and
  /// cannot be told from stillness by the IMU alone. All > 0.
  double block_s = 0.25;
  double gyro_block_spread_max_rad_s = 0.01;
  double accel_block_spread_max_mps2 = 0.1;
  /// Magnitude of gravity, m/s^2 (> 0).
  double gravity_mps2 = kStandardGravity;
  bool is_valid(std::string* why) const;
};

struct StaticInitialization {
  bool ok = false;
  std::string message;  ///< why not, when !ok
  int samples = 0;
  double start_s = 0.0, end_s = 0.0;
  Vector3 gyro_bias_rad_s = Vector3::Zero();
  /// Standard error of the gyro bias (the samples' std / sqrt(n), per axis), rad/s.
  Vector3 gyro_bias_sigma_rad_s = Vector3::Zero();
  Vector3 mean_accel_mps2 = Vector3::Zero();
  Vector3 gyro_std_rad_s = Vector3::Zero();
  Vector3 accel_std_mps2 = Vector3::Zero();
  /// Largest |block mean - window mean| over blocks and axes (the stillness test).
  double gyro_block_spread_rad_s = 0.0;
  double accel_block_spread_mps2 = 0.0;
  /// Roll and pitch from gravity, yaw 0: R_world_body with R * mean_accel / |mean_accel| = +z.
  core::SO3 R_world_body;
  /// |mean accel| - g: the accelerometer bias along gravity, m/s^2.
  double accel_bias_along_gravity_mps2 = 0.0;
  /// Gravity's direction in the body frame, unit (-mean_accel / |mean_accel|).
  Vector3 gravity_direction_body = Vector3::Zero();
};

/// Precondition: options.is_valid(). Samples sorted by stamp. Not ok (with the reason) when there
/// are fewer than 10 samples in the window or the window is not still.
StaticInitialization initialize_static(const std::vector<ImuSample>& samples,
                                       const StaticInitializationOptions& options);

}  // namespace cairn::inertial
