#include "cairn/core/so2.hpp"

#include <cmath>
#include <numbers>

namespace cairn::core {

namespace detail {
double wrap_angle_out_of_range(double angle_rad) {
  constexpr double kPi = std::numbers::pi;
  double a = std::remainder(angle_rad, 2.0 * kPi);  // in [-pi, pi]
  if (a <= -kPi) a += 2.0 * kPi;
  return a;
}
}  // namespace detail

SO2::SO2(double angle_rad) : theta_(wrap_angle(angle_rad)), c_(std::cos(theta_)), s_(std::sin(theta_)) {}

SO2 SO2::from_matrix(const Matrix2& M) {
  // The rotation closest in Frobenius norm to M has angle atan2(M10 - M01, M00 + M11).
  return SO2(std::atan2(M(1, 0) - M(0, 1), M(0, 0) + M(1, 1)));
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
