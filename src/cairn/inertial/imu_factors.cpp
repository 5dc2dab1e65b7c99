#include "cairn/inertial/imu_factors.hpp"

#include <cmath>
#include <utility>

namespace cairn::inertial {
namespace {

using RowMajor9x6 = Eigen::Matrix<double, 9, 6, Eigen::RowMajor>;
using RowMajor9x3 = Eigen::Matrix<double, 9, 3, Eigen::RowMajor>;

/// The residual's pieces shared by the value and the Jacobians.
struct ImuResidualTerms {
  Matrix3 R_i_T;           ///< R_i^T
  Vector3 v_term;          ///< R_i^T (v_j - v_i - g dt)
  Vector3 p_term;          ///< R_i^T (p_j - p_i - v_i dt - 1/2 g dt^2)
  Vector3 r_R;             ///< Log(dR(b)^T R_i^T R_j)
  Vector9 residual;        ///< (r_R, r_v, r_p), unwhitened
};

ImuResidualTerms residual_terms(const PreintegratedImu& pim, const Vector3& g, const NavState& s_i,
                                const NavState& s_j, const ImuBias& bias) {
  const double dt = pim.delta_time_s();
  const core::SO3& R_i = s_i.T_world_body.so3();
  const core::SO3& R_j = s_j.T_world_body.so3();
  ImuResidualTerms terms;
  terms.R_i_T = R_i.inverse().matrix();
  terms.v_term = terms.R_i_T * (s_j.v_world_mps - s_i.v_world_mps - g * dt);
  terms.p_term = terms.R_i_T * (s_j.T_world_body.translation() - s_i.T_world_body.translation() -
                                s_i.v_world_mps * dt - 0.5 * g * dt * dt);
  terms.r_R = (pim.corrected_delta_R(bias).inverse() * R_i.inverse() * R_j).log();
  terms.residual << terms.r_R, terms.v_term - pim.corrected_delta_v(bias), terms.p_term - pim.corrected_delta_p(bias);
  return terms;
}

NavState nav_state(const double* pose, const double* velocity) {
  return NavState{backend::se3_from_values(pose), Eigen::Map<const Vector3>(velocity)};
}

}  // namespace

BiasValues to_values(const ImuBias& bias) {
  BiasValues values;
  values << bias.gyro_rad_s, bias.accel_mps2;
  return values;
}

ImuBias bias_from_values(const double* values) {
  return ImuBias{Vector3(values[0], values[1], values[2]), Vector3(values[3], values[4], values[5])};
}

ImuFactor::ImuFactor(PreintegratedImu preintegrated, const Vector3& gravity_world)
    : preintegrated_(std::move(preintegrated)),
      gravity_world_(gravity_world),
      sqrt_information_(backend::square_root_information<9>(preintegrated_.covariance().inverse())) {}

ImuFactor ImuFactor::with_gravity_variable(PreintegratedImu preintegrated) {
  ImuFactor factor(std::move(preintegrated), Vector3::Zero());
  factor.gravity_variable_ = true;
  return factor;
}

SensorPoseImuFactor::SensorPoseImuFactor(ImuFactor factor, const core::SE3& T_body_sensor)
    : factor_(std::move(factor)), T_sensor_body_(T_body_sensor.inverse()), adjoint_body_sensor_(T_body_sensor.Adj()) {}

bool SensorPoseImuFactor::evaluate(const double* const* values, double* residual, double* const* jacobians) const {
  double pose_i[7], pose_j[7];
  backend::se3_to_values(backend::se3_from_values(values[0]) * T_sensor_body_, pose_i);
  backend::se3_to_values(backend::se3_from_values(values[2]) * T_sensor_body_, pose_j);
  const double* body_values[5] = {pose_i, values[1], pose_j, values[3], values[4]};
  if (!factor_.evaluate(body_values, residual, jacobians)) return false;
  if (jacobians == nullptr) return true;
  for (const int pose : {0, 2}) {
    if (jacobians[pose] == nullptr) continue;
    Eigen::Map<RowMajor9x6> J{jacobians[pose]};
    J = (J * adjoint_body_sensor_).eval();
  }
  return true;
}

bool GravityMagnitudeFactor::evaluate(const double* const* values, double* residual, double* const* jacobians) const {
  const Eigen::Map<const Vector3> g(values[0]);
  const double norm = g.norm();
  if (!(norm > 0.0)) return false;
  residual[0] = (norm - magnitude_) / sigma_;
  if (jacobians != nullptr && jacobians[0] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, 1, 3>>{jacobians[0]} = g.transpose() / (norm * sigma_);
  }
  return true;
}

Vector9 ImuFactor::raw_residual(const NavState& state_i, const NavState& state_j, const ImuBias& bias_i) const {
  return residual_terms(preintegrated_, gravity_world_, state_i, state_j, bias_i).residual;
}

bool ImuFactor::evaluate(const double* const* values, double* residual, double* const* jacobians) const {
  const NavState s_i = nav_state(values[0], values[1]);
  const NavState s_j = nav_state(values[2], values[3]);
  const ImuBias bias = bias_from_values(values[4]);
  const Vector3 gravity = gravity_variable_ ? Vector3(Eigen::Map<const Vector3>(values[5])) : gravity_world_;
  const ImuResidualTerms t = residual_terms(preintegrated_, gravity, s_i, s_j, bias);
  if (!t.residual.allFinite()) return false;
  Eigen::Map<Vector9>{residual} = sqrt_information_ * t.residual;
  if (jacobians == nullptr) return true;

  const PreintegratedImu& pim = preintegrated_;
  const double dt = pim.delta_time_s();
  const Matrix3 Jr_inv = core::SO3::right_jacobian_inverse(t.r_R);
  const Matrix3 R_j_T_R_i = s_j.T_world_body.so3().inverse().matrix() * s_i.T_world_body.so3().matrix();
  // [F] Appendix C; pose columns are (rho, phi).
  if (jacobians[0] != nullptr) {
    Eigen::Matrix<double, 9, 6> J = Eigen::Matrix<double, 9, 6>::Zero();
    J.block<3, 3>(0, 3) = -Jr_inv * R_j_T_R_i;
    J.block<3, 3>(3, 3) = core::SO3::hat(t.v_term);
    J.block<3, 3>(6, 0) = -Matrix3::Identity();
    J.block<3, 3>(6, 3) = core::SO3::hat(t.p_term);
    Eigen::Map<RowMajor9x6>{jacobians[0]} = sqrt_information_ * J;
  }
  if (jacobians[1] != nullptr) {
    Eigen::Matrix<double, 9, 3> J = Eigen::Matrix<double, 9, 3>::Zero();
    J.block<3, 3>(3, 0) = -t.R_i_T;
    J.block<3, 3>(6, 0) = -t.R_i_T * dt;
    Eigen::Map<RowMajor9x3>{jacobians[1]} = sqrt_information_ * J;
  }
  if (jacobians[2] != nullptr) {
    Eigen::Matrix<double, 9, 6> J = Eigen::Matrix<double, 9, 6>::Zero();
    J.block<3, 3>(0, 3) = Jr_inv;
    J.block<3, 3>(6, 0) = R_j_T_R_i.transpose();  // R_i^T R_j
    Eigen::Map<RowMajor9x6>{jacobians[2]} = sqrt_information_ * J;
  }
  if (jacobians[3] != nullptr) {
    Eigen::Matrix<double, 9, 3> J = Eigen::Matrix<double, 9, 3>::Zero();
    J.block<3, 3>(3, 0) = t.R_i_T;
    Eigen::Map<RowMajor9x3>{jacobians[3]} = sqrt_information_ * J;
  }
  if (jacobians[4] != nullptr) {
    const Vector3 d_bg = bias.gyro_rad_s - pim.bias_linearisation().gyro_rad_s;
    const Vector3 phi_b = pim.J_R_bg() * d_bg;
    Eigen::Matrix<double, 9, 6> J = Eigen::Matrix<double, 9, 6>::Zero();
    J.block<3, 3>(0, 0) =
        -Jr_inv * core::SO3::exp(t.r_R).inverse().matrix() * core::SO3::right_jacobian(phi_b) * pim.J_R_bg();
    J.block<3, 3>(3, 0) = -pim.J_v_bg();
    J.block<3, 3>(3, 3) = -pim.J_v_ba();
    J.block<3, 3>(6, 0) = -pim.J_p_bg();
    J.block<3, 3>(6, 3) = -pim.J_p_ba();
    Eigen::Map<RowMajor9x6>{jacobians[4]} = sqrt_information_ * J;
  }
  if (gravity_variable_ && jacobians[5] != nullptr) {
    Eigen::Matrix<double, 9, 3> J = Eigen::Matrix<double, 9, 3>::Zero();
    J.block<3, 3>(3, 0) = -t.R_i_T * dt;
    J.block<3, 3>(6, 0) = -0.5 * t.R_i_T * dt * dt;
    Eigen::Map<RowMajor9x3>{jacobians[5]} = sqrt_information_ * J;
  }
  return true;
}

BiasRandomWalkFactor::BiasRandomWalkFactor(const ImuNoise& noise, double dt_s) {
  const double root_dt = std::sqrt(dt_s);
  inverse_sigma_ << Vector3::Constant(1.0 / (noise.gyro_random_walk * root_dt)),
      Vector3::Constant(1.0 / (noise.accel_random_walk * root_dt));
}

bool BiasRandomWalkFactor::evaluate(const double* const* values, double* residual, double* const* jacobians) const {
  using Vector6Map = Eigen::Map<const Eigen::Matrix<double, 6, 1>>;
  Eigen::Map<Eigen::Matrix<double, 6, 1>>{residual} =
      inverse_sigma_.cwiseProduct(Vector6Map(values[1]) - Vector6Map(values[0]));
  if (jacobians == nullptr) return true;
  using RowMajor6 = Eigen::Matrix<double, 6, 6, Eigen::RowMajor>;
  if (jacobians[0] != nullptr) Eigen::Map<RowMajor6>{jacobians[0]} = -inverse_sigma_.asDiagonal().toDenseMatrix();
  if (jacobians[1] != nullptr) Eigen::Map<RowMajor6>{jacobians[1]} = inverse_sigma_.asDiagonal().toDenseMatrix();
  return true;
}

PosePriorFactor::PosePriorFactor(const core::SE3& Z_world_sensor, const Matrix6& covariance,
                                 const core::SE3& T_body_sensor)
    : measured_inverse_(Z_world_sensor.inverse()),
      T_body_sensor_(T_body_sensor),
      sqrt_information_(backend::square_root_information<6>(covariance.inverse())),
      adjoint_sensor_body_(T_body_sensor.inverse().Adj()) {}

bool PosePriorFactor::evaluate(const double* const* values, double* residual, double* const* jacobians) const {
  Matrix6 Jr_inv;
  const Vector6 error = (measured_inverse_ * backend::se3_from_values(values[0]) * T_body_sensor_).log(Jr_inv);
  Eigen::Map<Vector6>{residual} = sqrt_information_ * error;
  if (jacobians != nullptr && jacobians[0] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>{jacobians[0]} =
        sqrt_information_ * Jr_inv * adjoint_sensor_body_;
  }
  return true;
}

}  // namespace cairn::inertial
