#pragma once
/// \file
/// IMU factors on the least-squares engine (backend/least_squares.hpp), after Forster et al.,
/// T-RO 2017 ([F]) Sec. VI and GTSAM's ImuFactor / CombinedImuFactor:
///
///  * ImuFactor: 9 residuals between (pose_i, velocity_i, pose_j, velocity_j, bias_i) [F] (45):
///      r_R = Log(dR(b)^T R_i^T R_j)
///      r_v = R_i^T (v_j - v_i - g dt) - dv(b)
///      r_p = R_i^T (p_j - p_i - v_i dt - 1/2 g dt^2) - dp(b)
///    whitened by the preintegrated covariance, with the analytic Jacobians of [F] Appendix C.
///  * BiasRandomWalkFactor: 6 residuals b_j - b_i, whitened by the random walk over dt [F] (47).
///  * Priors on a pose, a velocity and a bias, for the first state.
///
/// Variables: a pose is se3_manifold() (T_world_body, delta = (rho, phi), T <- T exp(delta), so
/// R <- R Exp(phi) and p <- p + R rho to first order: [F]'s lifting (21)); a velocity is
/// euclidean_manifold(3) in the world frame; a bias is euclidean_manifold(6), (gyro, accel).

#include <memory>

#include "cairn/backend/least_squares.hpp"
#include "cairn/inertial/preintegration.hpp"

namespace cairn::inertial {

/// A bias as the engine stores it: (gyro xyz, accel xyz).
using BiasValues = Eigen::Matrix<double, 6, 1>;
BiasValues to_values(const ImuBias& bias);
ImuBias bias_from_values(const double* values);

class ImuFactor final : public backend::Factor {
 public:
  /// Gravity held at `gravity_world`.
  ImuFactor(PreintegratedImu preintegrated, const Vector3& gravity_world);
  /// Gravity a variable (euclidean_manifold(3), the world's gravity vector in m/s^2): the sixth
  /// variable of evaluate(), with dr_v/dg = -R_i^T dt and dr_p/dg = -1/2 R_i^T dt^2. Pair it with a
  /// GravityMagnitudeFactor: only its direction is left to the data.
  static ImuFactor with_gravity_variable(PreintegratedImu preintegrated);
  int residual_size() const override { return 9; }
  /// values: pose_i (7), velocity_i (3), pose_j (7), velocity_j (3), bias_i (6) [, gravity (3)].
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override;
  /// The unwhitened residual (r_R, r_v, r_p) at these states, for consistency checks (NEES).
  Vector9 raw_residual(const NavState& state_i, const NavState& state_j, const ImuBias& bias_i) const;
  const PreintegratedImu& preintegrated() const { return preintegrated_; }

 private:
  PreintegratedImu preintegrated_;
  Vector3 gravity_world_;
  bool gravity_variable_ = false;
  Matrix9 sqrt_information_;
};

/// An ImuFactor between two poses of a sensor rigidly mounted on the body (a camera whose poses a
/// bundle adjustment holds): T_world_body = T_world_sensor T_sensor_body. values: T_world_sensor_i
/// (7), velocity_i (3), T_world_sensor_j (7), velocity_j (3), bias_i (6); velocities are the body's.
/// The pose Jacobians are the body's times Adj(T_body_sensor), from
/// T_world_sensor exp(d) T_sensor_body = T_world_body exp(Adj(T_body_sensor) d).
class SensorPoseImuFactor final : public backend::Factor {
 public:
  SensorPoseImuFactor(ImuFactor factor, const core::SE3& T_body_sensor);
  int residual_size() const override { return 9; }
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override;

 private:
  ImuFactor factor_;
  core::SE3 T_sensor_body_;
  Matrix6 adjoint_body_sensor_;
};

/// r = (|g| - g0) / sigma on a gravity variable (euclidean_manifold(3)): keeps the magnitude known
/// while the direction is estimated (gravity refinement as in VINS-Mono's initialisation, Qin et
/// al., T-RO 2018, Sec. V-B-3, on the 2-sphere there; here as a soft constraint).
class GravityMagnitudeFactor final : public backend::Factor {
 public:
  GravityMagnitudeFactor(double magnitude_mps2, double sigma_mps2) : magnitude_(magnitude_mps2), sigma_(sigma_mps2) {}
  int residual_size() const override { return 1; }
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override;

 private:
  double magnitude_;
  double sigma_;
};

class BiasRandomWalkFactor final : public backend::Factor {
 public:
  /// Covariance of b_j - b_i over dt_s: random_walk^2 dt per axis (Kalibr's bias model).
  BiasRandomWalkFactor(const ImuNoise& noise, double dt_s);
  int residual_size() const override { return 6; }
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override;

 private:
  Eigen::Matrix<double, 6, 1> inverse_sigma_;
};

/// A measured pose of a sensor rigidly mounted on the body: r = S Log(Z^-1 T_world_body T_body_sensor)
/// on (rho, phi) (se3_manifold's order), S = Sigma^-1/2, Sigma the measurement's covariance in the
/// sensor frame (right perturbation of Z). With T_body_sensor the identity it is a prior on the
/// body's pose; with a LiDAR's extrinsic it is LIO-SAM's LiDAR odometry factor. The Jacobian is
/// S Jr^-1(r) Adj(T_body_sensor^-1) (T exp(d) X = T X exp(Adj(X^-1) d)).
class PosePriorFactor final : public backend::Factor {
 public:
  PosePriorFactor(const core::SE3& Z_world_sensor, const Matrix6& covariance,
                  const core::SE3& T_body_sensor = core::SE3());
  int residual_size() const override { return 6; }
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override;

 private:
  core::SE3 measured_inverse_;
  core::SE3 T_body_sensor_;
  Matrix6 sqrt_information_;
  Matrix6 adjoint_sensor_body_;
};

/// r = S (x - x_prior) for a Euclidean variable of size N (velocity: 3, bias: 6).
template <int N>
class VectorPriorFactor final : public backend::Factor {
 public:
  using Vector = Eigen::Matrix<double, N, 1>;
  using Matrix = Eigen::Matrix<double, N, N>;
  VectorPriorFactor(const Vector& prior, const Matrix& covariance)
      : prior_(prior), sqrt_information_(backend::square_root_information<N>(covariance.inverse())) {}
  int residual_size() const override { return N; }
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override {
    Eigen::Map<Vector>{residual} = sqrt_information_ * (Eigen::Map<const Vector>(values[0]) - prior_);
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, N, N, Eigen::RowMajor>>{jacobians[0]} = sqrt_information_;
    }
    return true;
  }

 private:
  Vector prior_;
  Matrix sqrt_information_;
};

}  // namespace cairn::inertial
