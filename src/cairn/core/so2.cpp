#include "cairn/core/so2.hpp"

#include <cmath>
#include <numbers>

namespace cairn::core {

double wrap_angle(double angle_rad) {
  constexpr double kPi = std::numbers::pi;
  if (angle_rad > -kPi && angle_rad <= kPi) return angle_rad;  // idempotence: keep every bit
  double a = std::remainder(angle_rad, 2.0 * kPi);             // in [-pi, pi]
  if (a <= -kPi) a += 2.0 * kPi;
  return a;
}

SO2::SO2(double angle_rad) : theta_(wrap_angle(angle_rad)), c_(std::cos(theta_)), s_(std::sin(theta_)) {}

SO2 SO2::from_matrix(const Matrix2& M) {
  // The rotation closest in Frobenius norm to M has angle atan2(M10 - M01, M00 + M11).
  return SO2(std::atan2(M(1, 0) - M(0, 1), M(0, 0) + M(1, 1)));
}

SO2 SO2::inverse() const {
  if (theta_ == std::numbers::pi) return *this;  // pi is its own inverse in (-pi, pi]
  return SO2(-theta_, c_, -s_);
}

SO2 SO2::operator*(const SO2& other) const {
  const double c = c_ * other.c_ - s_ * other.s_;
  const double s = s_ * other.c_ + c_ * other.s_;
  // One Newton step towards unit norm keeps long products on the circle.
  const double scale = 1.5 - 0.5 * (c * c + s * s);
  return SO2(wrap_angle(theta_ + other.theta_), scale * c, scale * s);
}

Matrix2 SO2::matrix() const {
  Matrix2 R;
  R << c_, -s_, s_, c_;
  return R;
}

Matrix2 SO2::hat(double theta) {
  Matrix2 W;
  W << 0.0, -theta, theta, 0.0;
  return W;
}

double SO2::vee(const Matrix2& Omega) { return Omega(1, 0); }

}  // namespace cairn::core
