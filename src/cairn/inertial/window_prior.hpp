#pragma once
/// \file
/// What a sliding-window smoother keeps of the state it drops: the next state's joint marginal
/// covariance over (pose, velocity, bias[, gravity]) given the factors that touched the dropped one
/// (`joint_marginal_covariance` over a problem holding only those), used as one Gaussian prior on the
/// window's new oldest state (`StatePriorFactor`). Keeping the blocks together keeps the
/// correlations the window built up, above all between the accelerometer bias and gravity (on a
/// straight drive only their sum is observable); LIO-SAM's reset with marginalCovariance keeps one
/// block per variable. Used by lidar3d/inertial_fusion.cpp and navigation/gnss_inertial_odometry.cpp.

#include <array>
#include <vector>

#include "cairn/backend/least_squares.hpp"
#include "cairn/core/se3.hpp"
#include "cairn/inertial/imu_factors.hpp"

namespace cairn::inertial {

/// A window state's values as the engine's variables store them: the pose (se3_manifold's 7
/// numbers), the world-frame velocity and the biases (gyro, accel).
struct StateValues {
  std::array<double, 7> pose{};
  Vector3 velocity = Vector3::Zero();
  BiasValues bias = BiasValues::Zero();

  NavState nav() const { return {backend::se3_from_values(pose.data()), velocity}; }
  void set(const NavState& s) {
    backend::se3_to_values(s.T_world_body, pose.data());
    velocity = s.v_world_mps;
  }
};

/// r = S (Log(P^-1 T), v - v0, b - b0[, g - g0]), S^T S the inverse of the 15 x 15 (18 x 18 with
/// gravity) covariance (eigenvalues floored at 1e-18). Variables: pose (se3_manifold), velocity (3),
/// bias (6)[, gravity (3)]; the pose Jacobian is S Jr^-1(Log(P^-1 T)).
class StatePriorFactor final : public backend::Factor {
 public:
  /// `gravity` null: no gravity block (covariance 15 x 15); otherwise its mean (covariance 18 x 18).
  StatePriorFactor(const core::SE3& pose, const Vector3& velocity, const BiasValues& bias, const Vector3* gravity,
                   const Eigen::MatrixXd& covariance);
  int residual_size() const override { return with_gravity_ ? 18 : 15; }
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override;

 private:
  core::SE3 pose_;
  Vector3 velocity_;
  BiasValues bias_;
  bool with_gravity_;
  Vector3 gravity_;
  Eigen::MatrixXd sqrt_information_;
};

/// The block of (J^T W J)^-1 over every free variable for `variables` (in their order), J whitened
/// and robust-reweighted at the current values (a dense inverse: a window has a few hundred
/// unknowns). Constant variables get zero rows and columns.
Eigen::MatrixXd joint_marginal_covariance(const backend::LeastSquaresProblem& problem, const std::vector<int>& variables);

}  // namespace cairn::inertial
