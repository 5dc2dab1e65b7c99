#include "cairn/core/se2.hpp"

#include <cmath>
#include <numbers>

namespace cairn::core {
namespace {

// Below this |theta| the closed forms lose digits to cancellation; use Taylor series instead.
constexpr double kSmallAngle = 1e-4;

// V(theta) of the exponential map: t = V rho. Returns (a, b) with V = [[a, -b], [b, a]],
// a = sin(theta)/theta, b = (1 - cos(theta))/theta.
void v_coefficients(double theta, double& a, double& b) {
  if (std::abs(theta) < kSmallAngle) {
    const double t2 = theta * theta;
    a = 1.0 - t2 / 6.0;
    b = theta / 2.0 - theta * t2 / 24.0;
  } else {
    a = std::sin(theta) / theta;
    // 1 - cos(theta) = 2 sin^2(theta/2). The left side cancels: just above the switch cos(theta)
    // is 1 - 5e-9, so b kept only ~8 digits, and the Jacobians' q = b / theta multiplies that
    // error by |rho| (J(0,2) was off by ~1e-7 for |rho| = 10). The right side is accurate to a
    // few ulp for every theta.
    const double s = std::sin(0.5 * theta);
    b = 2.0 * s * s / theta;
  }
}

}  // namespace

SE2 SE2::from_matrix(const Matrix3& T) {
  return SE2(SO2::from_matrix(T.topLeftCorner<2, 2>()), T.topRightCorner<2, 1>());
}

SE2 SE2::exp(const Tangent& xi) {
  const double theta = xi.z();
  if (std::abs(theta) < kSmallAngle || theta <= -std::numbers::pi || theta > std::numbers::pi) {
    double a = 0.0;
    double b = 0.0;
    v_coefficients(theta, a, b);
    const Vector2 t(a * xi.x() - b * xi.y(), b * xi.x() + a * xi.y());
    return SE2(SO2(theta), t);
  }
  // One sincos of theta/2 gives everything: sin = 2 s c, cos = 1 - 2 s^2 (no cancellation),
  // a = sin(theta)/theta, b = 2 s^2/theta (v_coefficients' forms).
  const double s = std::sin(0.5 * theta);
  const double c = std::cos(0.5 * theta);
  const double sin_theta = 2.0 * s * c;
  const double a = sin_theta / theta;
  const double b = 2.0 * s * s / theta;
  const Vector2 t(a * xi.x() - b * xi.y(), b * xi.x() + a * xi.y());
  return SE2(SO2(theta, 1.0 - 2.0 * s * s, sin_theta), t);
}

SE2::Tangent SE2::log() const {
  const double theta = R_.angle();
  double a = 0.0;
  double b = 0.0;
  if (std::abs(theta) < kSmallAngle) {
    v_coefficients(theta, a, b);
  } else if (std::abs(theta) < 0.25) {
    // Taylor series to the theta^10 / theta^11 terms (next terms below 4e-18): residual angles
    // are small, and the cached sine, rounded independently of theta, would put a relative
    // error of ~1e-16 / theta into sin(theta)/theta.
    const double t2 = theta * theta;
    a = 1.0 - t2 / 6.0 * (1.0 - t2 / 20.0 * (1.0 - t2 / 42.0 * (1.0 - t2 / 72.0 * (1.0 - t2 / 110.0))));
    b = theta / 2.0 * (1.0 - t2 / 12.0 * (1.0 - t2 / 30.0 * (1.0 - t2 / 56.0 * (1.0 - t2 / 90.0 * (1.0 - t2 / 132.0)))));
  } else {
    // From the cached cosine and sine: sin^2(theta/2) = (1 - c)/2 = s^2 / (2 (1 + c)), the form
    // without cancellation on each side of c = 0.
    const double c = R_.cos();
    const double s = R_.sin();
    const double half_sin2 = c > 0.0 ? s * s / (2.0 * (1.0 + c)) : 0.5 * (1.0 - c);
    a = s / theta;
    b = 2.0 * half_sin2 / theta;
  }
  // V^-1 = 1/(a^2 + b^2) [[a, b], [-b, a]]; a^2 + b^2 > 0 for |theta| <= pi.
  const double inv = 1.0 / (a * a + b * b);
  return {inv * (a * t_.x() + b * t_.y()), inv * (-b * t_.x() + a * t_.y()), theta};
}

Matrix3 SE2::matrix() const {
  Matrix3 T = Matrix3::Identity();
  T.topLeftCorner<2, 2>() = R_.matrix();
  T.topRightCorner<2, 1>() = t_;
  return T;
}

Matrix3 SE2::hat(const Tangent& xi) {
  Matrix3 X = Matrix3::Zero();
  X.topLeftCorner<2, 2>() = SO2::hat(xi.z());
  X(0, 2) = xi.x();
  X(1, 2) = xi.y();
  return X;
}

SE2::Tangent SE2::vee(const Matrix3& Xi) { return {Xi(0, 2), Xi(1, 2), Xi(1, 0)}; }

Matrix3 SE2::left_jacobian(const Tangent& xi) {
  // Sola eq. 164. With a = s/theta, b = (1-c)/theta the third column is
  //   ( (theta rho1 + rho2 - rho2 c - rho1 s) / theta^2,
  //     (-rho1 + theta rho2 + rho1 c - rho2 s) / theta^2 )
  // = ( rho1 (1 - a)/theta + rho2 b/theta,  -rho1 b/theta + rho2 (1 - a)/theta ).
  const double theta = xi.z();
  double a = 0.0;
  double b = 0.0;
  v_coefficients(theta, a, b);
  double p = 0.0;  // (1 - a) / theta = (theta - sin theta) / theta^2
  double q = 0.0;  // b / theta = (1 - cos theta) / theta^2
  if (std::abs(theta) < kSmallAngle) {
    const double t2 = theta * theta;
    p = theta / 6.0 - theta * t2 / 120.0;
    q = 0.5 - t2 / 24.0;
  } else {
    p = (1.0 - a) / theta;
    q = b / theta;
  }
  Matrix3 J = Matrix3::Identity();
  J(0, 0) = a;
  J(0, 1) = -b;
  J(1, 0) = b;
  J(1, 1) = a;
  J(0, 2) = p * xi.x() + q * xi.y();
  J(1, 2) = -q * xi.x() + p * xi.y();
  return J;
}

Matrix3 SE2::right_jacobian(const Tangent& xi) { return left_jacobian(-xi); }

namespace {
// Inverse of [[A, c], [0, 1]] with A = [[a, -b], [b, a]].
Matrix3 invert_upper_block(const Matrix3& J) {
  const double a = J(0, 0);
  const double b = J(1, 0);
  const double inv = 1.0 / (a * a + b * b);
  Matrix2 A_inv;
  A_inv << a * inv, b * inv, -b * inv, a * inv;
  Matrix3 K = Matrix3::Identity();
  K.topLeftCorner<2, 2>() = A_inv;
  K.topRightCorner<2, 1>() = -A_inv * J.topRightCorner<2, 1>();
  return K;
}
}  // namespace

Matrix3 SE2::left_jacobian_inverse(const Tangent& xi) { return invert_upper_block(left_jacobian(xi)); }

Matrix3 SE2::right_jacobian_inverse(const Tangent& xi) {
  return invert_upper_block(right_jacobian(xi));
}

}  // namespace cairn::core
