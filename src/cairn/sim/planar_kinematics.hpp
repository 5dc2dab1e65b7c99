#pragma once
/// \file
/// The kinematics of a sampled planar ground truth at any instant: pose, velocity, acceleration
/// and angular rate of the body, lifted to 3D, for the simulated IMU (sim/imu.hpp).
///
/// The 3D worlds drive a planar robot (sim/trajectory.hpp). Body frame: x forward, y left, z up,
/// its origin on the ground (z = 0) at the ground-truth body pose T_world_body; the LiDAR is
/// mount_height_m above it (sim/street_run.hpp lidar_pose: T_body_lidar = (I, (0, 0, h))) and the
/// camera as CameraOptions::T_body_camera says. The IMU frame is the body frame.
///
/// Between samples k and k+1 (period h, s = (t - t_k) / h in [0, 1]) position and heading are
/// quintic Hermite polynomials matching, at both ends, the samples' poses, their first
/// derivatives (which the trajectory generator gives exactly: velocity = speed (cos theta,
/// sin theta), heading rate = yaw rate) and second derivatives estimated at the sample:
///
///   p(t)     = H0(s) p_k + h H1(s) v_k + h^2 H2(s) a_k + h^2 H3(s) a_k+1 + h H4(s) v_k+1 + H5(s) p_k+1
///   theta(t) = the same with theta_k, w_k, alpha_k, alpha_k+1, w_k+1, theta_k + wrap(theta_k+1 - theta_k)
///   H0 = 1 - 10s^3 + 15s^4 - 6s^5    H1 = s - 6s^3 + 8s^4 - 3s^5    H2 = (s^2 - 3s^3 + 3s^4 - s^5) / 2
///   H3 = (s^3 - 2s^4 + s^5) / 2      H4 = -4s^3 + 7s^4 - 3s^5        H5 = 10s^3 - 15s^4 + 6s^5
///   a_k = dv/dt forward + speed_k w_k left,  dv/dt and alpha_k = dw/dt by central differences of the
///   samples' speeds and yaw rates (one-sided at the ends)
///
/// Velocity, acceleration and yaw rate are the exact time derivatives of these, so integrating
/// the acceleration and the yaw rate from a sample reproduces the next sample's pose (tested with
/// an independent integrator), and acceleration and yaw rate are continuous in time: where the
/// generator's acceleration steps (speed-profile switches, curvature steps at arc ends) the
/// step is spread over the neighbouring sample periods, as a real vehicle's finite jerk would
/// (a discontinuity would make any sampled-IMU integrator err by about dt |jump| / 6 per step).
/// At sample times the pose and velocity are the samples' own. Before the first sample and after
/// the last the body rests at the end pose. A jump in the truth (a kidnapping's carry) is not
/// motion: do not feed one.

#include <vector>

#include "cairn/sim/imu.hpp"
#include "cairn/sim/trajectory.hpp"

namespace cairn::sim {

class PlanarKinematics {
 public:
  /// `samples`: stamps strictly increasing (>= 2 samples).
  explicit PlanarKinematics(std::vector<TrajectorySample> samples);
  /// The body's kinematics at true time t_s (seconds, the samples' clock).
  BodyKinematics operator()(double t_s) const;

 private:
  /// d value / dt at sample k by a central difference (one-sided at the ends).
  double rate_of_change(std::size_t k, double (*value)(const TrajectorySample&)) const;
  /// World acceleration and yaw acceleration estimated at sample k (see the file comment).
  Vector2 acceleration_at(std::size_t k) const;
  double yaw_acceleration_at(std::size_t k) const;

  std::vector<TrajectorySample> samples_;
};

}  // namespace cairn::sim
