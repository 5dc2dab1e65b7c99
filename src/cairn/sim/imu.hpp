#pragma once
/// \file
/// A simulated IMU: gyroscope and accelerometer readings from a body's true kinematics with white
/// noise, bias random walks, saturation and a clock offset, plus the exact ground truth (pose,
/// velocity, biases) at every sample. Presets for EuRoC's ADIS16448 and a consumer MEMS.
///
/// Model: Kalibr's IMU noise model (github.com/ethz-asl/kalibr/wiki/IMU-Noise-Model), as in
/// Forster et al., "On-Manifold Preintegration for Real-Time Visual-Inertial Odometry", T-RO 33(1),
/// 2017, eq. 27, with the IMU frame = the body frame and world z up:
///
///   omega_meas(t_k) = omega_body(t_k) + b_g[k] + eta_g[k]
///   a_meas(t_k)     = R_world_body(t_k)^T (a_world(t_k) - g_world) + b_a[k] + eta_a[k]
///   g_world         = (0, 0, -kStandardGravity)
///   eta[k] ~ N(0, sigma_d^2 I),   sigma_d = noise_density * sqrt(rate_hz)    (discrete white noise)
///   b[k+1] = b[k] + sigma_bd n,   sigma_bd = random_walk * sqrt(dt), n ~ N(0, I)  (bias random walk)
///
/// then each axis clipped to +-saturation (when > 0). A body at rest reads a_meas = +g up: the
/// specific force. Sample k is taken at true time t_k = start + k dt and stamped with the IMU's
/// clock, t_k + time_offset_s; the ground truth of sample k is stamped with the true time t_k.

#include <cstdint>
#include <functional>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/inertial/euroc_files.hpp"
#include "cairn/inertial/imu_types.hpp"

namespace cairn::sim {

/// What the simulated IMU is and how it errs. Defaults: the "adis16448" preset.
struct ImuSimulationOptions {
  /// Samples per second, in [1, 10000]; the period is rounded to whole nanoseconds.
  double rate_hz = 200.0;
  /// Continuous-time densities and random walks (Kalibr's units, see inertial::ImuNoise); each
  /// >= 0 here (0 switches that noise off: a noise-free IMU for tests).
  inertial::ImuNoise noise;
  /// Biases at the first sample. When unset, every axis is drawn N(0, sigma^2) with the sigmas
  /// below (the draws happen either way, so the noise that follows does not change).
  std::optional<inertial::ImuBias> initial_bias;
  /// Standard deviation of each axis of the drawn initial gyro bias, rad/s (>= 0).
  double initial_gyro_bias_sigma_rad_s = 0.04;
  /// Standard deviation of each axis of the drawn initial accelerometer bias, m/s^2 (>= 0).
  double initial_accel_bias_sigma_mps2 = 0.1;
  /// Each gyro axis is clipped to [-s, s], rad/s (>= 0; 0 = no clipping).
  double gyro_saturation_rad_s = 1000.0 * std::numbers::pi / 180.0;
  /// Each accelerometer axis is clipped to [-s, s], m/s^2 (>= 0; 0 = no clipping).
  double accel_saturation_mps2 = 18.0 * inertial::kStandardGravity;
  /// The IMU's clock minus true time, seconds, in [-10, 10]: samples are stamped t + offset.
  double time_offset_s = 0.0;
  /// Seed of the noise, the bias walk and the drawn initial biases.
  std::uint64_t seed = 1;

  /// Checks every field; on failure returns false and writes every problem to `why`.
  bool is_valid(std::string* why) const;
  /// The period between samples, nanoseconds (1e9 / rate_hz rounded).
  std::int64_t period_ns() const;
};

/// The preset names: "adis16448" (EuRoC MAV's IMU) and "consumer-mems" (MPU-9250 class); see
/// imu.cpp for the figures and where each comes from.
std::vector<std::string> imu_preset_names();
/// The named preset's noise, initial-bias sigmas, saturations and rate (seed and time offset keep
/// their defaults); nullopt for an unknown name.
std::optional<ImuSimulationOptions> imu_preset(std::string_view name);

/// The body's true motion at one instant. The body frame has x forward and z up.
struct BodyKinematics {
  core::SE3 T_world_body;
  Vector3 v_world_mps = Vector3::Zero();
  Vector3 a_world_mps2 = Vector3::Zero();
  Vector3 omega_body_rad_s = Vector3::Zero();
};

/// The readings and, for each, the true state and biases at the instant it was taken.
struct SimulatedImu {
  std::vector<inertial::ImuSample> samples;        ///< stamped with the IMU's clock
  std::vector<inertial::GroundTruthState> truth;   ///< stamped with true time; truth[k] <-> samples[k]
  inertial::ImuBias initial_bias;                  ///< the biases of sample 0 (given or drawn)
};

/// Samples the IMU at true times start_s + k / rate_hz <= end_s (to the nanosecond) from `truth`
/// (the body's kinematics at a true time, seconds). Precondition: options.is_valid(), start_s <=
/// end_s.
SimulatedImu simulate_imu(const std::function<BodyKinematics(double t_s)>& truth, double start_s, double end_s,
                          const ImuSimulationOptions& options);

}  // namespace cairn::sim
