#pragma once
/// \file
/// Wheel odometry: ground-truth increments corrupted by scale and yaw biases, slip and Gaussian
/// noise whose variance grows linearly with the motion, then integrated (dead reckoning).
///
/// For each ground-truth step k -> k+1 with true increment T_k^-1 T_{k+1} = (dx, dy, dtheta),
/// travelled distance d = sqrt(dx^2 + dy^2) and turned angle a = |dtheta|, the measured
/// increment is
///
///   g         = (1 + scale_error) * (1 + e_k)                     (e_k: slip excess, below)
///   dx~       = g dx + forward_sigma * sqrt(d) * n1
///   dy~       = g dy + lateral_sigma * sqrt(d) * n2
///   dtheta~   = (1 + yaw_scale_error) dtheta + yaw_bias * d
///               + sqrt(yaw_sigma_per_rad^2 * a + yaw_sigma_per_m^2 * d) * n3
///
/// with n1, n2, n3 independent N(0, 1). Variances add over steps, so the noise after a stretch
/// does not depend on the sampling rate: driving D metres straight gives a forward error of
/// standard deviation forward_sigma * sqrt(D) (a random walk in distance, as in the odometry
/// model of Thrun, Burgard, Fox, "Probabilistic Robotics", 2005, section 5.4, with variances
/// linear instead of quadratic in the motion).
///
/// Slip: when no slip is under way, one starts at step k with probability
/// 1 - exp(-slip_rate_per_s * dt) and lasts slip_duration_s; during it the wheels over-report
/// translation by the factor 1 + e, e ~ U(0, slip_max_excess) drawn once per slip.
///
/// The odometry frame coincides with the world frame at the first sample, so noise-free
/// odometry reproduces the ground truth.

#include <cstdint>
#include <string>
#include <vector>

#include "cairn/core/se2.hpp"
#include "cairn/sim/random.hpp"
#include "cairn/sim/trajectory.hpp"

namespace cairn::sim {

struct OdometryNoise {
  /// Forward and lateral noise, metres per sqrt(metre travelled) (>= 0).
  double forward_sigma_m_per_sqrt_m = 0.02;
  double lateral_sigma_m_per_sqrt_m = 0.005;
  /// Yaw noise per sqrt(radian turned), rad/sqrt(rad), and per sqrt(metre travelled), rad/sqrt(m).
  double yaw_sigma_rad_per_sqrt_rad = 0.02;
  double yaw_sigma_rad_per_sqrt_m = 0.008;
  /// Relative error of the wheel radius (0.01 = wheels report 1 % too much distance).
  double scale_error = 0.01;
  /// Relative error of turned angles (track width error).
  double yaw_scale_error = 0.005;
  /// Yaw drift per metre travelled (unequal wheel radii), rad/m.
  double yaw_bias_rad_per_m = 0.001;
  /// Slip events per second of driving (>= 0), their duration (s) and largest excess (>= 0).
  double slip_rate_per_s = 0.02;
  double slip_duration_s = 0.5;
  double slip_max_excess = 0.2;

  /// All zero: odometry equals the ground truth.
  static OdometryNoise none();
  bool is_valid(std::string* why) const;
};

/// Dead reckoning at every trajectory sample.
struct OdometryTrack {
  /// T_odom_body at each sample (odom frame = world frame at the first sample).
  std::vector<core::SE2> poses;
  /// Measured forward speed (m/s) and yaw rate (rad/s) over the step ending at each sample
  /// (0 at the first sample): what a CARMEN ODOM line calls tv and rv.
  std::vector<double> speed_mps;
  std::vector<double> yaw_rate_rad_s;
  /// Slip events that started, for the manifest.
  std::size_t slip_events = 0;
};

/// The sensor: turns true increments into measured ones (see the file comment), keeping the
/// slip state between steps. Draws exactly five variates per step whatever the settings.
class WheelOdometry {
 public:
  WheelOdometry(const OdometryNoise& noise, std::uint64_t seed) : noise_(noise), random_(seed) {}

  /// Measured increment for the true increment `T_prev_next` taking `dt_s` seconds.
  core::SE2 measure(const core::SE2& T_prev_next, double dt_s);
  std::size_t slip_events() const { return slip_events_; }

 private:
  OdometryNoise noise_;
  Random random_;
  double slip_excess_ = 0.0;
  double slip_left_s_ = 0.0;
  std::size_t slip_events_ = 0;
};

/// Integrates WheelOdometry over the whole trajectory. `carried_samples` (increasing) lists the
/// samples k whose step from k - 1 the wheels did not drive: the robot was picked up and put down
/// elsewhere (kidnapping), so the sensor is handed the identity increment and reports exactly no
/// motion (every noise term scales with the motion), while the ground truth jumps.
OdometryTrack simulate_odometry(const std::vector<TrajectorySample>& truth, const OdometryNoise& noise,
                                std::uint64_t seed, const std::vector<std::size_t>& carried_samples = {});

}  // namespace cairn::sim
