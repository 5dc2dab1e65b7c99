#include "cairn/gnss/gnss_factor.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>

#include "cairn/core/problems.hpp"
#include "cairn/core/so3.hpp"

namespace cairn::gnss {

bool GnssFactorOptions::is_valid(std::string* why) const {
  core::Problems problems;
  if (!lever_arm_body_m.allFinite()) problems.add("lever_arm_body_m must be finite");
  if (!T_enu_world.translation().allFinite()) problems.add("T_enu_world must be finite");
  if (!(std::isfinite(default_sigma_horizontal_m) && default_sigma_horizontal_m > 0.0)) {
    problems.add("default_sigma_horizontal_m must be finite and > 0");
  }
  if (!(std::isfinite(default_sigma_vertical_m) && default_sigma_vertical_m > 0.0)) {
    problems.add("default_sigma_vertical_m must be finite and > 0");
  }
  if (!(std::isfinite(min_sigma_m) && min_sigma_m > 0.0)) problems.add("min_sigma_m must be finite and > 0");
  if (!(std::isfinite(loss.scale) && loss.scale > 0.0)) problems.add("loss.scale must be finite and > 0");
  return problems.report(why);
}

Matrix3 factor_covariance_enu(const GnssFix& fix, const GnssFactorOptions& options) {
  Matrix3 covariance = Matrix3::Zero();
  if (fix.covariance_known && fix.covariance_enu_m2.allFinite()) {
    covariance = 0.5 * (fix.covariance_enu_m2 + fix.covariance_enu_m2.transpose());
  } else {
    const double h2 = options.default_sigma_horizontal_m * options.default_sigma_horizontal_m;
    covariance.diagonal() << h2, h2, options.default_sigma_vertical_m * options.default_sigma_vertical_m;
  }
  const Eigen::SelfAdjointEigenSolver<Matrix3> eigen(covariance);
  const Vector3 floored = eigen.eigenvalues().cwiseMax(options.min_sigma_m * options.min_sigma_m);
  return eigen.eigenvectors() * floored.asDiagonal() * eigen.eigenvectors().transpose();
}

GnssPositionFactor::GnssPositionFactor(const Vector3& p_enu_antenna_m, const Matrix3& covariance_enu_m2,
                                       const Vector3& lever_arm_body_m, const core::SE3& T_enu_world)
    : p_enu_antenna_m_(p_enu_antenna_m), lever_arm_body_m_(lever_arm_body_m), T_enu_world_(T_enu_world) {
  // Sigma = V Lambda V^T  =>  S = Lambda^-1/2 V^T satisfies S^T S = V Lambda^-1 V^T = Sigma^-1.
  const Eigen::SelfAdjointEigenSolver<Matrix3> eigen(covariance_enu_m2);
  S_ = eigen.eigenvalues().cwiseMax(1e-300).cwiseSqrt().cwiseInverse().asDiagonal() * eigen.eigenvectors().transpose();
}

Vector3 GnssPositionFactor::error_enu_m(const core::SE3& T_world_body) const {
  return T_enu_world_ * (T_world_body * lever_arm_body_m_) - p_enu_antenna_m_;
}

bool GnssPositionFactor::evaluate(const double* const* values, double* residual, double* const* jacobians) const {
  const core::SE3 T_world_body = backend::se3_from_values(values[0]);
  Eigen::Map<Vector3> r(residual);
  r = whitened_residual(T_world_body);
  if (jacobians != nullptr && jacobians[0] != nullptr) {
    const Matrix3 SR = S_ * T_enu_world_.rotation_matrix() * T_world_body.rotation_matrix();
    Eigen::Map<Eigen::Matrix<double, 3, 6, Eigen::RowMajor>> J_residual_pose(jacobians[0]);
    J_residual_pose.leftCols<3>() = SR;
    J_residual_pose.rightCols<3>() = -SR * core::SO3::hat(lever_arm_body_m_);
  }
  return r.allFinite();
}

std::unique_ptr<GnssPositionFactor> make_gnss_factor(const GnssFix& fix, const LocalFrame& frame,
                                                     const GnssFactorOptions& options) {
  return std::make_unique<GnssPositionFactor>(frame.forward(fix), factor_covariance_enu(fix, options),
                                              options.lever_arm_body_m, options.T_enu_world);
}

}  // namespace cairn::gnss
