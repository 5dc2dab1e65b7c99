#include "cairn/navigation/navigation_factors.hpp"

#include <array>
#include <utility>

#include "cairn/core/so3.hpp"

namespace cairn::navigation {

using RowMajor36 = Eigen::Matrix<double, 3, 6, Eigen::RowMajor>;
using RowMajor33 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;

WheelVelocityFactor::WheelVelocityFactor(double forward_speed_mps, const Vector3& sigma_mps,
                                         const Vector3& omega_imu_rad_s, const core::SE3& T_imu_vehicle)
    : measured_(forward_speed_mps, 0.0, 0.0),
      inverse_sigma_(sigma_mps.cwiseInverse()),
      omega_cross_t_imu_(omega_imu_rad_s.cross(T_imu_vehicle.translation())),
      R_vehicle_imu_(T_imu_vehicle.so3().matrix().transpose()) {}

Vector3 WheelVelocityFactor::vehicle_velocity(const core::SE3& T_world_imu, const Vector3& v_world_mps) const {
  return R_vehicle_imu_ * (T_world_imu.so3().inverse() * v_world_mps + omega_cross_t_imu_);
}

bool WheelVelocityFactor::evaluate(const double* const* values, double* residual, double* const* jacobians) const {
  const core::SE3 T_world_imu = backend::se3_from_values(values[0]);
  const Eigen::Map<const Vector3> v_world(values[1]);
  const Vector3 u = T_world_imu.so3().inverse() * v_world;
  Eigen::Map<Vector3>{residual} = inverse_sigma_.asDiagonal() * (R_vehicle_imu_ * (u + omega_cross_t_imu_) - measured_);
  if (jacobians == nullptr) return true;
  const Matrix3 S_R = inverse_sigma_.asDiagonal() * R_vehicle_imu_;
  if (jacobians[0] != nullptr) {
    Eigen::Map<RowMajor36> J(jacobians[0]);
    J.leftCols<3>().setZero();
    J.rightCols<3>() = S_R * core::SO3::hat(u);
  }
  if (jacobians[1] != nullptr) Eigen::Map<RowMajor33>{jacobians[1]} = S_R * T_world_imu.so3().inverse().matrix();
  return true;
}

ShiftedGnssFactor::ShiftedGnssFactor(std::unique_ptr<gnss::GnssPositionFactor> fix, double dt_s)
    : fix_(std::move(fix)), dt_s_(dt_s) {}

core::SE3 ShiftedGnssFactor::pose_at_fix(const core::SE3& T_world_imu, const Vector3& v_world_mps) const {
  return core::SE3(T_world_imu.so3(), T_world_imu.translation() + v_world_mps * dt_s_);
}

bool ShiftedGnssFactor::evaluate(const double* const* values, double* residual, double* const* jacobians) const {
  const core::SE3 T_world_imu = backend::se3_from_values(values[0]);
  std::array<double, 7> shifted{};
  backend::se3_to_values(pose_at_fix(T_world_imu, Eigen::Map<const Vector3>(values[1])), shifted.data());
  const double* shifted_values[1] = {shifted.data()};
  RowMajor36 J_pose;
  double* pose_jacobian[1] = {J_pose.data()};
  const bool need = jacobians != nullptr && (jacobians[0] != nullptr || jacobians[1] != nullptr);
  if (!fix_->evaluate(shifted_values, residual, need ? pose_jacobian : nullptr)) return false;
  if (!need) return true;
  if (jacobians[0] != nullptr) Eigen::Map<RowMajor36>{jacobians[0]} = J_pose;
  if (jacobians[1] != nullptr) {
    Eigen::Map<RowMajor33>{jacobians[1]} = J_pose.leftCols<3>() * T_world_imu.so3().inverse().matrix() * dt_s_;
  }
  return true;
}

}  // namespace cairn::navigation
