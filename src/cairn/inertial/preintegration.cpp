#include "cairn/inertial/preintegration.hpp"

#include <algorithm>
#include <cmath>

#include "cairn/core/assert.hpp"

namespace cairn::inertial {

PreintegratedImu::PreintegratedImu(const ImuNoise& noise, const ImuBias& bias_linearisation)
    : noise_(noise), bias_bar_(bias_linearisation) {}

void PreintegratedImu::reset(const ImuBias& bias_linearisation) { *this = PreintegratedImu(noise_, bias_linearisation); }

void PreintegratedImu::integrate(const Vector3& gyro_rad_s, const Vector3& accel_mps2, double dt_s) {
  CAIRN_ASSERT(dt_s > 0.0 && std::isfinite(dt_s), "PreintegratedImu::integrate needs a positive, finite dt");
  const Vector3 omega = gyro_rad_s - bias_bar_.gyro_rad_s;
  const Vector3 accel = accel_mps2 - bias_bar_.accel_mps2;
  const double dt2 = dt_s * dt_s;
  const Vector3 phi_k = omega * dt_s;
  const core::SO3 dR_k = core::SO3::exp(phi_k);
  const Matrix3 Jr_k = core::SO3::right_jacobian(phi_k);
  const Matrix3 R = delta_R_.matrix();  // dR_ik, before this sample
  const Matrix3 R_accel_hat = R * core::SO3::hat(accel);

  // Covariance [F] (62)-(63): Sigma <- A Sigma A^T + B Sigma_gd B^T + C Sigma_ad C^T, with the
  // discrete-time noise Cov(eta_d) = Cov(eta) / dt [F] (48), error order (dphi, dv, dp).
  Matrix9 A = Matrix9::Identity();
  A.block<3, 3>(0, 0) = dR_k.inverse().matrix();
  A.block<3, 3>(3, 0) = -R_accel_hat * dt_s;
  A.block<3, 3>(6, 0) = -0.5 * R_accel_hat * dt2;
  A.block<3, 3>(6, 3) = Matrix3::Identity() * dt_s;
  Eigen::Matrix<double, 9, 3> B = Eigen::Matrix<double, 9, 3>::Zero();
  B.block<3, 3>(0, 0) = Jr_k * dt_s;
  Eigen::Matrix<double, 9, 3> C = Eigen::Matrix<double, 9, 3>::Zero();
  C.block<3, 3>(3, 0) = R * dt_s;
  C.block<3, 3>(6, 0) = 0.5 * R * dt2;
  const double gyro_var = noise_.gyro_noise_density * noise_.gyro_noise_density / dt_s;
  const double accel_var = noise_.accel_noise_density * noise_.accel_noise_density / dt_s;
  covariance_ = A * covariance_ * A.transpose() + gyro_var * B * B.transpose() + accel_var * C * C.transpose();

  // Bias Jacobians [F] Appendix B, each from the previous values (p before v before R).
  J_p_ba_ += J_v_ba_ * dt_s - 0.5 * R * dt2;
  J_p_bg_ += J_v_bg_ * dt_s - 0.5 * R_accel_hat * J_R_bg_ * dt2;
  J_v_ba_ -= R * dt_s;
  J_v_bg_ -= R_accel_hat * J_R_bg_ * dt_s;
  J_R_bg_ = dR_k.inverse().matrix() * J_R_bg_ - Jr_k * dt_s;

  // Increments [F] (33), position first (it uses the previous velocity and rotation).
  delta_p_ += delta_v_ * dt_s + 0.5 * R * accel * dt2;
  delta_v_ += R * accel * dt_s;
  delta_R_ = delta_R_ * dR_k;
  dt_ij_s_ += dt_s;
}

core::SO3 PreintegratedImu::corrected_delta_R(const ImuBias& bias) const {
  return delta_R_ * core::SO3::exp(J_R_bg_ * (bias.gyro_rad_s - bias_bar_.gyro_rad_s));
}

Vector3 PreintegratedImu::corrected_delta_v(const ImuBias& bias) const {
  return delta_v_ + J_v_bg_ * (bias.gyro_rad_s - bias_bar_.gyro_rad_s) +
         J_v_ba_ * (bias.accel_mps2 - bias_bar_.accel_mps2);
}

Vector3 PreintegratedImu::corrected_delta_p(const ImuBias& bias) const {
  return delta_p_ + J_p_bg_ * (bias.gyro_rad_s - bias_bar_.gyro_rad_s) +
         J_p_ba_ * (bias.accel_mps2 - bias_bar_.accel_mps2);
}

NavState PreintegratedImu::predict(const NavState& state_i, const ImuBias& bias, const Vector3& gravity_world) const {
  const core::SO3& R_i = state_i.T_world_body.so3();
  const Vector3& p_i = state_i.T_world_body.translation();
  const double dt = dt_ij_s_;
  NavState state_j;
  const core::SO3 R_j = R_i * corrected_delta_R(bias);
  state_j.v_world_mps = state_i.v_world_mps + gravity_world * dt + (R_i * corrected_delta_v(bias));
  const Vector3 p_j =
      p_i + state_i.v_world_mps * dt + 0.5 * gravity_world * dt * dt + (R_i * corrected_delta_p(bias));
  state_j.T_world_body = core::SE3(R_j, p_j);
  return state_j;
}

bool integrate_interval(const std::vector<ImuSample>& samples, core::Timestamp from, core::Timestamp to,
                        PreintegratedImu& preintegrated) {
  if (!(from < to)) return from == to;  // an empty interval integrates nothing
  const auto after_from = std::upper_bound(samples.begin(), samples.end(), from,
                                           [](core::Timestamp t, const ImuSample& s) { return t < s.stamp; });
  if (after_from == samples.begin() || samples.empty() || samples.back().stamp < to) return false;
  PreintegratedImu result = preintegrated;
  core::Timestamp t = from;
  for (auto k = after_from - 1; t < to; ++k) {
    const core::Timestamp piece_end = std::min(to, (k + 1)->stamp);
    const double dt_s = static_cast<double>(piece_end.nanoseconds() - t.nanoseconds()) * 1e-9;
    if (dt_s > 0.0) result.integrate(k->gyro_rad_s, k->accel_mps2, dt_s);
    t = piece_end;
  }
  preintegrated = std::move(result);
  return true;
}

Matrix9 hold_error_covariance(const std::vector<ImuSample>& samples, core::Timestamp from, core::Timestamp to) {
  Matrix9 covariance = Matrix9::Zero();
  if (!(from < to)) return covariance;
  const auto after_from = std::upper_bound(samples.begin(), samples.end(), from,
                                           [](core::Timestamp t, const ImuSample& s) { return t < s.stamp; });
  if (after_from == samples.begin() || samples.empty() || samples.back().stamp < to) return covariance;
  double sigma_phi = 0.0, sigma_v = 0.0, sigma_p = 0.0;
  core::Timestamp t = from;
  for (auto k = after_from - 1; t < to; ++k) {
    const auto next = k + 1;
    const core::Timestamp piece_end = std::min(to, next->stamp);
    const double tau = static_cast<double>(piece_end.nanoseconds() - t.nanoseconds()) * 1e-9;
    const double dt = static_cast<double>(next->stamp.nanoseconds() - k->stamp.nanoseconds()) * 1e-9;
    if (tau > 0.0 && dt > 0.0) {
      const double missed = 0.5 * tau * tau / dt;
      sigma_p += sigma_v * tau;
      sigma_v += missed * (next->accel_mps2 - k->accel_mps2).norm() + k->accel_mps2.norm() * sigma_phi * tau;
      sigma_phi += missed * (next->gyro_rad_s - k->gyro_rad_s).norm();
    }
    t = piece_end;
  }
  covariance.diagonal() << Vector3::Constant(sigma_phi * sigma_phi), Vector3::Constant(sigma_v * sigma_v), Vector3::Constant(sigma_p * sigma_p);
  return covariance;
}

}  // namespace cairn::inertial
