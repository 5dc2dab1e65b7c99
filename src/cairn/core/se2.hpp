#pragma once
/// \file
/// SE(2): planar rigid motions T = (R, t), acting as T * p = R p + t.
///
/// Tangent vectors are ordered translation first, xi = (rho_x, rho_y, theta), as in Sophus and
/// g2o (GTSAM orders rotation first). exp(xi) = (exp(theta), V(theta) rho) with
/// V(theta) = [[s/theta, -(1-c)/theta], [(1-c)/theta, s/theta]]
/// (Sola et al., "A micro Lie theory for state estimation in robotics", 2018, eq. 156).
/// Left/right Jacobians follow Sola eq. 163-164; Jr(xi) = Jl(-xi).

#include "cairn/core/so2.hpp"

namespace cairn::core {

class SE2 {
 public:
  static constexpr int kDoF = 3;
  using Tangent = Vector3;
  using Jacobian = Matrix3;

  /// Identity.
  SE2() = default;
  SE2(const SO2& R, const Vector2& t) : R_(R), t_(t) {}
  /// Pose (x, y, theta) as written in g2o and TORO files.
  SE2(double x, double y, double theta_rad) : R_(theta_rad), t_(x, y) {}

  /// From a 3x3 homogeneous matrix; the rotation block is projected onto SO(2).
  static SE2 from_matrix(const Matrix3& T);

  static SE2 exp(const Tangent& xi);
  Tangent log() const;
  /// log() and Jr^-1 at it (the same interface as SE3's).
  Tangent log(Jacobian& right_jacobian_inverse_at_log) const {
    const Tangent xi = log();
    right_jacobian_inverse_at_log = right_jacobian_inverse(xi);
    return xi;
  }

  SE2 inverse() const {
    const SO2 R_inv = R_.inverse();
    return SE2(R_inv, -(R_inv * t_));
  }
  SE2 operator*(const SE2& other) const { return SE2(R_ * other.R_, R_ * other.t_ + t_); }
  Vector2 operator*(const Vector2& p) const { return R_ * p + t_; }

  const SO2& so2() const { return R_; }
  const Vector2& translation() const { return t_; }
  double x() const { return t_.x(); }
  double y() const { return t_.y(); }
  double angle() const { return R_.angle(); }
  Matrix3 matrix() const;

  /// Adj such that T * exp(xi) * T^-1 = exp(Adj * xi): Sola eq. 159 with translation-first
  /// ordering, [[R, -[1]x t], [0, 1]] with [1]x t = (-t_y, t_x).
  Jacobian Adj() const {
    Jacobian A;
    A << R_.cos(), -R_.sin(), t_.y(), R_.sin(), R_.cos(), -t_.x(), 0.0, 0.0, 1.0;
    return A;
  }

  static Matrix3 hat(const Tangent& xi);
  static Tangent vee(const Matrix3& Xi);

  /// Left Jacobian: exp(xi + d) ~= exp(Jl(xi) d) * exp(xi) for small d.
  static Jacobian left_jacobian(const Tangent& xi);
  static Jacobian left_jacobian_inverse(const Tangent& xi);
  /// Right Jacobian: exp(xi + d) ~= exp(xi) * exp(Jr(xi) d) for small d.
  static Jacobian right_jacobian(const Tangent& xi);
  static Jacobian right_jacobian_inverse(const Tangent& xi);

 private:
  SO2 R_;
  Vector2 t_ = Vector2::Zero();
};

}  // namespace cairn::core
