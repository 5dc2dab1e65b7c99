#pragma once
/// \file
/// SO(2): planar rotations.
///
/// Stored as the angle theta in (-pi, pi] with its cosine and sine cached (like g2o's
/// Rotation2D), so a pose read from a file and written back keeps its angle bit for bit.
/// Products and inverses form the cosine and sine by the angle-sum identities instead of
/// calling sincos (which took 7-10 % of a 2D pose-graph solve); they agree with cos/sin of the
/// stored angle to a few ulps.
/// Lie algebra so(2) = R; exp(theta) is the rotation by theta; Adj = 1; all Jacobians = 1.

#include <numbers>

#include "cairn/core/types.hpp"

namespace cairn::core {

class SE2;

namespace detail {
double wrap_angle_out_of_range(double angle_rad);
}  // namespace detail

/// Wraps an angle into (-pi, pi]. Idempotent: an angle already in range is returned unchanged.
/// (The products and inverses below are inline: out of line they took about a third of a 2D
/// pose-graph linearisation in calls, measured on intel.)
inline double wrap_angle(double angle_rad) {
  constexpr double kPi = std::numbers::pi;
  if (angle_rad > -kPi && angle_rad <= kPi) return angle_rad;  // idempotence: keep every bit
  return detail::wrap_angle_out_of_range(angle_rad);
}

class SO2 {
 public:
  static constexpr int kDoF = 1;
  using Tangent = double;

  /// Identity.
  SO2() = default;
  /// Rotation by `angle_rad` (any real value; wrapped into (-pi, pi]).
  explicit SO2(double angle_rad);

  /// Nearest rotation to a 2x2 matrix (polar projection via atan2 of its columns' average).
  static SO2 from_matrix(const Matrix2& M);

  static SO2 exp(double theta) { return SO2(theta); }
  /// log in (-pi, pi].
  double log() const { return theta_; }

  SO2 inverse() const {
    if (theta_ == std::numbers::pi) return *this;  // pi is its own inverse in (-pi, pi]
    return SO2(-theta_, c_, -s_);
  }
  SO2 operator*(const SO2& other) const {
    const double c = c_ * other.c_ - s_ * other.s_;
    const double s = s_ * other.c_ + c_ * other.s_;
    // One Newton step towards unit norm keeps long products on the circle.
    const double scale = 1.5 - 0.5 * (c * c + s * s);
    return SO2(wrap_angle(theta_ + other.theta_), scale * c, scale * s);
  }
  Vector2 operator*(const Vector2& p) const { return {c_ * p.x() - s_ * p.y(), s_ * p.x() + c_ * p.y()}; }

  double angle() const { return theta_; }
  double cos() const { return c_; }
  double sin() const { return s_; }
  Matrix2 matrix() const;

  /// Adjoint of SO(2) is the scalar 1.
  static double Adj() { return 1.0; }
  /// hat(theta) = [[0, -theta], [theta, 0]].
  static Matrix2 hat(double theta);
  /// Inverse of hat; reads the (1,0) entry.
  static double vee(const Matrix2& Omega);

  /// SO(2) is commutative, so exp(theta + d) = exp(d) exp(theta) = exp(theta) exp(d) exactly:
  /// every Jacobian is 1. Given for a uniform interface with the other groups.
  static double left_jacobian(double /*theta*/) { return 1.0; }
  static double left_jacobian_inverse(double /*theta*/) { return 1.0; }
  static double right_jacobian(double /*theta*/) { return 1.0; }
  static double right_jacobian_inverse(double /*theta*/) { return 1.0; }

 private:
  friend class SE2;
  // From an angle already in (-pi, pi] and its cosine and sine (no trigonometry).
  SO2(double theta, double c, double s) : theta_(theta), c_(c), s_(s) {}

  double theta_ = 0.0;
  double c_ = 1.0;
  double s_ = 0.0;
};

}  // namespace cairn::core
