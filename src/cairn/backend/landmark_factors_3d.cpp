#include "cairn/backend/landmark_factors_3d.hpp"

#include <cmath>

#include "cairn/core/so2.hpp"
#include "cairn/core/so3.hpp"

namespace cairn::backend {
namespace {

// q = T^-1 p and its Jacobians (see the header).
Vector3 body_point(const core::SE3& T_world_body, const Vector3& p_world, Matrix36* J_q_pose, Matrix3* J_q_landmark) {
  const Matrix3 R_body_world = T_world_body.rotation_matrix().transpose();
  const Vector3 q = R_body_world * (p_world - T_world_body.translation());
  if (J_q_pose != nullptr) {
    J_q_pose->leftCols<3>() = -Matrix3::Identity();
    J_q_pose->rightCols<3>() = core::SO3::hat(q);
  }
  if (J_q_landmark != nullptr) *J_q_landmark = R_body_world;
  return q;
}

}  // namespace

Vector3 point_residual_3d(const core::SE3& T_world_body, const Vector3& p_world, const Vector3& q_measured,
                          Matrix36* J_e_pose, Matrix3* J_e_landmark) {
  return body_point(T_world_body, p_world, J_e_pose, J_e_landmark) - q_measured;
}

Vector3 range_bearing_elevation_residual_3d(const core::SE3& T_world_body, const Vector3& p_world, const Vector3& z,
                                            Matrix36* J_e_pose, Matrix3* J_e_landmark) {
  Matrix36 J_q_pose;
  Matrix3 J_q_landmark;
  const Vector3 q = body_point(T_world_body, p_world, &J_q_pose, &J_q_landmark);
  const double rho2 = q.x() * q.x() + q.y() * q.y();  // squared horizontal distance
  const double rho = std::sqrt(rho2);
  const double r2 = rho2 + q.z() * q.z();
  const double r = std::sqrt(r2);
  // d(r, b, el) / dq.
  Matrix3 J_h_q;
  J_h_q << q.x() / r, q.y() / r, q.z() / r,  //
      -q.y() / rho2, q.x() / rho2, 0.0,      //
      -q.x() * q.z() / (r2 * rho), -q.y() * q.z() / (r2 * rho), rho / r2;
  if (J_e_pose != nullptr) *J_e_pose = J_h_q * J_q_pose;
  if (J_e_landmark != nullptr) *J_e_landmark = J_h_q * J_q_landmark;
  return {r - z.x(), core::wrap_angle(std::atan2(q.y(), q.x()) - z.y()), core::wrap_angle(std::atan2(q.z(), rho) - z.z())};
}

}  // namespace cairn::backend
