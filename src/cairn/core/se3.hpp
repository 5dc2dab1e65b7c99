#pragma once
/// \file
/// SE(3): rigid motions T = (R, t), acting as T * p = R p + t.
///
/// Tangent vectors are ordered translation first, xi = (rho, phi), as in Sophus and g2o
/// (GTSAM orders rotation first). exp(xi) = (exp(phi), Jl(phi) rho) where Jl is SO(3)'s left
/// Jacobian. The SE(3) left Jacobian is
///   Jl(xi) = [[Jl(phi), Q(rho, phi)], [0, Jl(phi)]]
/// with Q from Barfoot, "State Estimation for Robotics", 2017, eq. 7.86 (Barfoot & Furgale,
/// T-RO 2014, eq. 102); Jr(xi) = Jl(-xi).

#include "cairn/core/so3.hpp"

namespace cairn::core {

class SE3 {
 public:
  static constexpr int kDoF = 6;
  using Tangent = Vector6;
  using Jacobian = Matrix6;

  /// Identity.
  SE3() = default;
  SE3(const SO3& R, const Vector3& t) : R_(R), t_(t) {}
  /// From a quaternion (normalised, see SO3) and a translation.
  SE3(const Quaternion& q, const Vector3& t) : R_(q), t_(t) {}

  /// From a 4x4 (or the top 3x4 of a) homogeneous matrix; the rotation block is projected onto
  /// SO(3).
  static SE3 from_matrix(const Matrix4& T);
  static SE3 from_matrix3x4(const Eigen::Matrix<double, 3, 4>& T);

  static SE3 exp(const Tangent& xi);
  Tangent log() const;
  /// log() and Jr^-1 at it, sharing SO(3)'s Jl^-1(phi): Jr^-1(xi) = Jl^-1(-xi), and
  /// Jl^-1(-phi) = Jl^-1(phi)^T on SO(3) (Barfoot 2017, eqs. 7.87 and 7.95).
  Tangent log(Jacobian& right_jacobian_inverse_at_log) const;

  SE3 inverse() const;
  SE3 operator*(const SE3& other) const { return SE3(R_ * other.R_, R_ * other.t_ + t_); }
  Vector3 operator*(const Vector3& p) const { return R_ * p + t_; }

  const SO3& so3() const { return R_; }
  const Quaternion& unit_quaternion() const { return R_.unit_quaternion(); }
  Matrix3 rotation_matrix() const { return R_.matrix(); }
  const Vector3& translation() const { return t_; }
  Matrix4 matrix() const;
  Eigen::Matrix<double, 3, 4> matrix3x4() const;

  /// Adj = [[R, [t]x R], [0, R]] so that T * exp(xi) * T^-1 = exp(Adj * xi).
  Jacobian Adj() const;

  static Matrix4 hat(const Tangent& xi);
  static Tangent vee(const Matrix4& Xi);

  static Jacobian left_jacobian(const Tangent& xi);
  /// Precondition: |phi| < 2 pi.
  static Jacobian left_jacobian_inverse(const Tangent& xi);
  static Jacobian right_jacobian(const Tangent& xi) { return left_jacobian(-xi); }
  static Jacobian right_jacobian_inverse(const Tangent& xi) { return left_jacobian_inverse(-xi); }

 private:
  SO3 R_;
  Vector3 t_ = Vector3::Zero();
};

}  // namespace cairn::core
