#include "cairn/core/se3.hpp"

#include <cmath>

namespace cairn::core {
namespace {

constexpr double kSmallAngle = 1e-3;

// Q(rho, phi) of Barfoot 2017, eq. 7.86:
//   Q = 1/2 P + c1 (F P + P F + F P F) + c2 (F F P + P F F - 3 F P F)
//       + c3 (F P F F + F F P F),
// with P = [rho]x, F = [phi]x, a = |phi| and
//   c1 = (a - sin a) / a^3, c2 = (a^2 + 2 cos a - 2) / (2 a^4), c3 = (2a - 3 sin a + a cos a) / (2 a^5).
// The Taylor series (c1 = 1/6 - a^2/120, c2 = 1/24 - a^2/720, c3 = 1/120 - a^2/2520) are used
// for small a, where the closed forms cancel.
Matrix3 barfoot_q(const Vector3& rho, const Vector3& phi) {
  const Matrix3 P = SO3::hat(rho);
  const Matrix3 F = SO3::hat(phi);
  const double a2 = phi.squaredNorm();
  const double a = std::sqrt(a2);
  double c1 = 0.0;
  double c2 = 0.0;
  double c3 = 0.0;
  if (a < kSmallAngle) {
    c1 = 1.0 / 6.0 - a2 / 120.0;
    c2 = 1.0 / 24.0 - a2 / 720.0;
    c3 = 1.0 / 120.0 - a2 / 2520.0;
  } else {
    const double s = std::sin(a);
    const double c = std::cos(a);
    c1 = (a - s) / (a2 * a);
    // a^2 + 2 cos a - 2 = a^2 - 4 sin^2(a/2) = (a - 2 sin(a/2)) (a + 2 sin(a/2)). Written with
    // cos a, the rounding of 2 cos a (~2e-16) swamps the a^4/12 it should resolve: c2 had ~2e-3
    // relative error just above the switch (a = 1e-3), i.e. ~1e-10 |rho| in Q. The factored form
    // cancels only at the scale of a and keeps c2 to ~2e-9 there.
    const double two_sin_half = 2.0 * std::sin(0.5 * a);
    c2 = (a - two_sin_half) * (a + two_sin_half) / (2.0 * a2 * a2);
    c3 = (2.0 * a - 3.0 * s + a * c) / (2.0 * a2 * a2 * a);
  }
  const Matrix3 FP = F * P;
  const Matrix3 PF = P * F;
  const Matrix3 FPF = FP * F;
  const Matrix3 FF = F * F;
  return 0.5 * P + c1 * (FP + PF + FPF) + c2 * (FF * P + PF * F - 3.0 * FPF) +
         c3 * (FPF * F + F * FPF);
}

}  // namespace

SE3 SE3::from_matrix(const Matrix4& T) {
  return SE3(SO3::from_matrix(T.topLeftCorner<3, 3>()), T.topRightCorner<3, 1>());
}

SE3 SE3::from_matrix3x4(const Eigen::Matrix<double, 3, 4>& T) {
  return SE3(SO3::from_matrix(T.leftCols<3>()), T.col(3));
}

SE3 SE3::exp(const Tangent& xi) {
  const Vector3 rho = xi.head<3>();
  const Vector3 phi = xi.tail<3>();
  return SE3(SO3::exp(phi), SO3::left_jacobian(phi) * rho);
}

SE3::Tangent SE3::log() const {
  const Vector3 phi = R_.log();
  Tangent xi;
  xi.head<3>() = SO3::left_jacobian_inverse(phi) * t_;
  xi.tail<3>() = phi;
  return xi;
}

SE3::Tangent SE3::log(Jacobian& right_jacobian_inverse_at_log) const {
  const Vector3 phi = R_.log();
  const Matrix3 K = SO3::left_jacobian_inverse(phi);
  const Vector3 rho = K * t_;
  // Jl^-1(-xi) = [[K^T, -K^T Q(-rho, -phi) K^T], [0, K^T]] (left_jacobian_inverse below).
  const Matrix3 K_T = K.transpose();
  Jacobian& J = right_jacobian_inverse_at_log;
  J.setZero();
  J.topLeftCorner<3, 3>() = K_T;
  J.topRightCorner<3, 3>() = -K_T * barfoot_q(-rho, -phi) * K_T;
  J.bottomRightCorner<3, 3>() = K_T;
  Tangent xi;
  xi.head<3>() = rho;
  xi.tail<3>() = phi;
  return xi;
}

SE3 SE3::inverse() const {
  const SO3 R_inv = R_.inverse();
  return SE3(R_inv, -(R_inv * t_));
}

Matrix4 SE3::matrix() const {
  Matrix4 T = Matrix4::Identity();
  T.topLeftCorner<3, 3>() = R_.matrix();
  T.topRightCorner<3, 1>() = t_;
  return T;
}

Eigen::Matrix<double, 3, 4> SE3::matrix3x4() const {
  Eigen::Matrix<double, 3, 4> T;
  T.leftCols<3>() = R_.matrix();
  T.col(3) = t_;
  return T;
}

Matrix6 SE3::Adj() const {
  const Matrix3 R = R_.matrix();
  Matrix6 A = Matrix6::Zero();
  A.topLeftCorner<3, 3>() = R;
  A.topRightCorner<3, 3>() = SO3::hat(t_) * R;
  A.bottomRightCorner<3, 3>() = R;
  return A;
}

Matrix4 SE3::hat(const Tangent& xi) {
  Matrix4 X = Matrix4::Zero();
  X.topLeftCorner<3, 3>() = SO3::hat(xi.tail<3>());
  X.topRightCorner<3, 1>() = xi.head<3>();
  return X;
}

SE3::Tangent SE3::vee(const Matrix4& Xi) {
  Tangent xi;
  xi.head<3>() = Xi.topRightCorner<3, 1>();
  xi.tail<3>() = SO3::vee(Xi.topLeftCorner<3, 3>());
  return xi;
}

Matrix6 SE3::left_jacobian(const Tangent& xi) {
  const Vector3 rho = xi.head<3>();
  const Vector3 phi = xi.tail<3>();
  const Matrix3 J = SO3::left_jacobian(phi);
  Matrix6 Jl = Matrix6::Zero();
  Jl.topLeftCorner<3, 3>() = J;
  Jl.topRightCorner<3, 3>() = barfoot_q(rho, phi);
  Jl.bottomRightCorner<3, 3>() = J;
  return Jl;
}

Matrix6 SE3::left_jacobian_inverse(const Tangent& xi) {
  // Barfoot 2017, eq. 7.95: Jl^-1 = [[J^-1, -J^-1 Q J^-1], [0, J^-1]].
  const Vector3 rho = xi.head<3>();
  const Vector3 phi = xi.tail<3>();
  const Matrix3 J_inv = SO3::left_jacobian_inverse(phi);
  Matrix6 K = Matrix6::Zero();
  K.topLeftCorner<3, 3>() = J_inv;
  K.topRightCorner<3, 3>() = -J_inv * barfoot_q(rho, phi) * J_inv;
  K.bottomRightCorner<3, 3>() = J_inv;
  return K;
}

}  // namespace cairn::core
