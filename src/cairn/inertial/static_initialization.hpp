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
  /// The window counts as still when the standard deviation of every gyro axis is below this
  /// (rad/s, > 0) and of every accelerometer axis below accel_std_max_mps2 (m/s^2, > 0). The
  /// defaults leave room for a running engine or rotor vibration (EuRoC's MAV on the ground:
  /// 0.005 rad/s, 0.05 m/s^2 at rest).
  double gyro_std_max_rad_s = 0.02;
  double accel_std_max_mps2 = 0.2;
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
