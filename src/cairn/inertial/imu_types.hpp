#pragma once
/// \file
/// What an IMU measures and how it is described: one sample (`ImuSample`), the sensor's noise
/// model (`ImuNoise`, the continuous-time densities Kalibr and EuRoC's sensor.yaml give), its
/// biases (`ImuBias`) and the body state the IMU moves (`NavState`). Frames (docs/conventions.md):
/// the IMU measures in its own frame `imu`; the body frame of a pipeline is the IMU frame unless
/// an extrinsic `T_body_imu` is given; `world` is gravity-aligned with z up (gravity along -z).

#include <string>

#include "cairn/core/se3.hpp"
#include "cairn/core/time.hpp"
#include "cairn/core/types.hpp"

namespace cairn::inertial {

/// One IMU reading: angular rate and specific force (acceleration minus gravity), both in the
/// IMU's frame, as sensor_msgs/Imu and EuRoC's imu0/data.csv give them.
struct ImuSample {
  core::Timestamp stamp;
  Vector3 gyro_rad_s = Vector3::Zero();
  Vector3 accel_mps2 = Vector3::Zero();
};

/// The IMU's noise model, continuous time (Kalibr's IMU noise model; EuRoC sensor.yaml's keys in
/// brackets). A discrete sample at rate f has white-noise sigma = density * sqrt(f); a bias
/// drifts by random_walk * sqrt(dt) over dt. The defaults are EuRoC's ADIS16448 (V1_01
/// imu0/sensor.yaml).
struct ImuNoise {
  double gyro_noise_density = 1.6968e-04;   ///< rad/s/sqrt(Hz) [gyroscope_noise_density], > 0
  double accel_noise_density = 2.0000e-03;  ///< m/s^2/sqrt(Hz) [accelerometer_noise_density], > 0
  double gyro_random_walk = 1.9393e-05;     ///< rad/s^2/sqrt(Hz) [gyroscope_random_walk], > 0
  double accel_random_walk = 3.0000e-03;    ///< m/s^3/sqrt(Hz) [accelerometer_random_walk], > 0
  bool is_valid(std::string* why) const;
};

/// Gyroscope and accelerometer biases: measured = true + bias + noise.
struct ImuBias {
  Vector3 gyro_rad_s = Vector3::Zero();
  Vector3 accel_mps2 = Vector3::Zero();
};

/// The body's navigation state: pose and velocity in the world frame.
struct NavState {
  core::SE3 T_world_body;
  Vector3 v_world_mps = Vector3::Zero();
};

/// Standard gravity, m/s^2 (the world's gravity vector is (0, 0, -kStandardGravity)).
inline constexpr double kStandardGravity = 9.80665;

}  // namespace cairn::inertial
