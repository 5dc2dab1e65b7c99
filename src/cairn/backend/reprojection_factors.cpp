#include "cairn/backend/reprojection_factors.hpp"

#include <Eigen/Core>
#include <cmath>

#include "cairn/core/se3.hpp"
#include "cairn/core/so3.hpp"

namespace cairn::backend {
namespace {

using Matrix3 = Eigen::Matrix3d;
using Vector3 = Eigen::Vector3d;

Matrix3 hat(const Vector3& a) {
  Matrix3 A;
  A << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return A;
}

/// Rodrigues' formula R(w) and the right Jacobian J_r(w), with R(w + d) = R(w) Exp(J_r(w) d)
/// to first order (Barfoot, "State estimation for robotics", eq. 7.77a; Chirikjian 2011).
void rotation_and_right_jacobian(const Vector3& w, Matrix3& R, Matrix3* J_r) {
  const double theta_squared = w.squaredNorm();
  const Matrix3 W = hat(w);
  if (theta_squared < 1e-16) {
    R = Matrix3::Identity() + W;
    if (J_r != nullptr) *J_r = Matrix3::Identity() - 0.5 * W;
    return;
  }
  const double theta = std::sqrt(theta_squared);
  const double s = std::sin(theta);
  const double c = std::cos(theta);
  const Matrix3 W2 = W * W;
  R = Matrix3::Identity() + (s / theta) * W + ((1.0 - c) / theta_squared) * W2;
  if (J_r != nullptr) {
    *J_r = Matrix3::Identity() - ((1.0 - c) / theta_squared) * W + ((theta - s) / (theta_squared * theta)) * W2;
  }
}

}  // namespace

bool BalReprojectionFactor::evaluate(const double* const* values, double* residual, double* const* jacobians) const {
  const double* camera = values[0];
  const Eigen::Map<const Vector3> w(camera);
  const Eigen::Map<const Vector3> t(camera + 3);
  const double f = camera[6];
  const double k1 = camera[7];
  const double k2 = camera[8];
  const Eigen::Map<const Vector3> X(values[1]);
  const bool want_camera = jacobians != nullptr && jacobians[0] != nullptr;
  const bool want_point = jacobians != nullptr && jacobians[1] != nullptr;
  Matrix3 R, J_r;
  rotation_and_right_jacobian(w, R, want_camera ? &J_r : nullptr);
  const Vector3 P = R * X + t;
  // BAL's model divides by P_z whatever its sign; only P_z = 0 leaves it undefined.
  if (P.z() == 0.0) return false;
  const double inverse_z = 1.0 / P.z();
  const double px = -P.x() * inverse_z;
  const double py = -P.y() * inverse_z;
  const double r2 = px * px + py * py;
  const double d = 1.0 + r2 * (k1 + k2 * r2);
  residual[0] = f * d * px - observed_x_;
  residual[1] = f * d * py - observed_y_;
  if (!want_camera && !want_point) return true;
  // d(prediction)/dp = f (d I + 2 (k1 + 2 k2 r2) p p^T);  dp/dP = [[-1/z, 0, x/z^2], [0, -1/z, y/z^2]].
  const double dd = 2.0 * (k1 + 2.0 * k2 * r2);
  Eigen::Matrix2d J_pred_p;
  J_pred_p << f * (d + dd * px * px), f * dd * px * py, f * dd * px * py, f * (d + dd * py * py);
  Eigen::Matrix<double, 2, 3> J_p_P;
  J_p_P << -inverse_z, 0.0, P.x() * inverse_z * inverse_z, 0.0, -inverse_z, P.y() * inverse_z * inverse_z;
  const Eigen::Matrix<double, 2, 3> J_pred_P = J_pred_p * J_p_P;
  if (want_camera) {
    Eigen::Map<Eigen::Matrix<double, 2, 9, Eigen::RowMajor>> J(jacobians[0]);
    // dP/dw = -R [X]x J_r(w); dP/dt = I.
    J.block<2, 3>(0, 0) = J_pred_P * (-R * hat(X) * J_r);
    J.block<2, 3>(0, 3) = J_pred_P;
    J(0, 6) = d * px;
    J(1, 6) = d * py;
    J(0, 7) = f * r2 * px;
    J(1, 7) = f * r2 * py;
    J(0, 8) = f * r2 * r2 * px;
    J(1, 8) = f * r2 * r2 * py;
  }
  if (want_point) {
    Eigen::Map<Eigen::Matrix<double, 2, 3, Eigen::RowMajor>> J(jacobians[1]);
    J = J_pred_P * R;
  }
  return true;
}

namespace {

/// p_camera = T_world_camera^-1 p_world and its Jacobians: d/d(rho, phi) = [-I, [p_camera]x],
/// d/dp_world = R^T (right perturbation T <- T exp(delta), docs/conventions.md).
struct CameraPoint {
  Vector3 p;
  Matrix3 R_camera_world;
};

CameraPoint to_camera(const double* pose, const double* point) {
  const cairn::Quaternion q(pose[3], pose[0], pose[1], pose[2]);
  const Matrix3 R_world_camera = q.normalized().toRotationMatrix();
  const Vector3 t(pose[4], pose[5], pose[6]);
  const Eigen::Map<const Vector3> p_world(point);
  CameraPoint result;
  result.R_camera_world = R_world_camera.transpose();
  result.p = result.R_camera_world * (p_world - t);
  return result;
}

constexpr double kMinDepth = 1e-9;

template <int Rows>
void write_jacobians(const Eigen::Matrix<double, Rows, 3>& J_residual_p, const CameraPoint& camera,
                     double* const* jacobians) {
  if (jacobians == nullptr) return;
  if (jacobians[0] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, Rows, 6, Eigen::RowMajor>> J(jacobians[0]);
    J.template leftCols<3>() = -J_residual_p;
    J.template rightCols<3>() = J_residual_p * hat(camera.p);
  }
  if (jacobians[1] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, Rows, 3, Eigen::RowMajor>> J(jacobians[1]);
    J = J_residual_p * camera.R_camera_world;
  }
}

}  // namespace

bool PinholeReprojectionFactor::evaluate(const double* const* values, double* residual, double* const* jacobians) const {
  const CameraPoint camera = to_camera(values[0], values[1]);
  const Vector3& p = camera.p;
  if (!(p.z() > kMinDepth)) return false;
  const double inverse_z = 1.0 / p.z();
  const PinholeIntrinsics& K = intrinsics_;
  residual[0] = K.fx * p.x() * inverse_z + K.cx - u_;
  residual[1] = K.fy * p.y() * inverse_z + K.cy - v_;
  Eigen::Matrix<double, 2, 3> J_residual_p;
  J_residual_p << K.fx * inverse_z, 0.0, -K.fx * p.x() * inverse_z * inverse_z, 0.0, K.fy * inverse_z,
      -K.fy * p.y() * inverse_z * inverse_z;
  write_jacobians<2>(J_residual_p, camera, jacobians);
  return true;
}

bool StereoReprojectionFactor::evaluate(const double* const* values, double* residual, double* const* jacobians) const {
  const CameraPoint camera = to_camera(values[0], values[1]);
  const Vector3& p = camera.p;
  if (!(p.z() > kMinDepth)) return false;
  const double inverse_z = 1.0 / p.z();
  const PinholeIntrinsics& K = intrinsics_;
  residual[0] = K.fx * p.x() * inverse_z + K.cx - u_left_;
  residual[1] = K.fy * p.y() * inverse_z + K.cy - v_left_;
  residual[2] = K.fx * (p.x() - baseline_m_) * inverse_z + K.cx - u_right_;
  Eigen::Matrix<double, 3, 3> J_residual_p;
  const double z2 = inverse_z * inverse_z;
  J_residual_p << K.fx * inverse_z, 0.0, -K.fx * p.x() * z2, 0.0, K.fy * inverse_z, -K.fy * p.y() * z2,
      K.fx * inverse_z, 0.0, -K.fx * (p.x() - baseline_m_) * z2;
  write_jacobians<3>(J_residual_p, camera, jacobians);
  return true;
}

}  // namespace cairn::backend
