#include "cairn/core/so3.hpp"

#include <cmath>
#include <limits>

#include <Eigen/LU>
#include <Eigen/SVD>

#include "cairn/core/assert.hpp"

namespace cairn::core {
namespace {
constexpr double kSmallAngle = 1e-4;
constexpr double kEps = std::numeric_limits<double>::epsilon();
}  // namespace

SO3::SO3(const Quaternion& q) : q_(q) {
  const double n2 = q.squaredNorm();
  CAIRN_ASSERT(std::isfinite(n2) && n2 > 0.0, "SO3 needs a finite, non-zero quaternion");
  if (std::abs(n2 - 1.0) > 4.0 * kEps) q_.coeffs() /= std::sqrt(n2);
}

SO3 SO3::from_matrix(const Matrix3& M) {
  // The closest rotation in Frobenius norm is the orthonormal polar factor U V^T (det +1) of M.
  // For det(M) > 0 it is reached by Newton's iteration X <- (g X + X^-T / g) / 2 with the
  // Frobenius-norm scaling g = sqrt(|X^-1| / |X|) (Higham, "Computing the polar decomposition -
  // with applications", SIAM J. Sci. Stat. Comput. 7(4), 1986, eqs. 3.1 and 3.5): quadratic
  // convergence in a few 3x3 inverses, where the SVD took most of the chordal initialisation's
  // projections. Otherwise (det <= 0, or no convergence in 20 steps) from the SVD.
  if (M.determinant() > 0.0) {
    Matrix3 X = M;
    for (int k = 0; k < 20; ++k) {
      const Matrix3 X_inv_T = X.inverse().transpose();
      const double g = std::sqrt(X_inv_T.norm() / X.norm());
      const Matrix3 next = 0.5 * (g * X + X_inv_T / g);
      // Near the polar factor the error squares with each step (the step is about the error):
      // after a step of 1e-9 the new iterate is orthonormal to rounding.
      const double change = (next - X).norm();
      X = next;
      if (change <= 1e-9) return SO3(Quaternion(X));
    }
  }
  Eigen::JacobiSVD<Matrix3> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Matrix3 D = Matrix3::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0) D(2, 2) = -1.0;
  const Matrix3 R = svd.matrixU() * D * svd.matrixV().transpose();
  return SO3(Quaternion(R));
}

SO3 SO3::from_rpy(double roll_rad, double pitch_rad, double yaw_rad) {
  const Quaternion q = Eigen::AngleAxisd(yaw_rad, Vector3::UnitZ()) *
                       Eigen::AngleAxisd(pitch_rad, Vector3::UnitY()) *
                       Eigen::AngleAxisd(roll_rad, Vector3::UnitX());
  return SO3(q);
}

Vector3 SO3::to_rpy() const {
  const Matrix3 R = matrix();
  // R = Rz(y) Ry(p) Rx(r): R20 = -sin p, R21 = cos p sin r, R22 = cos p cos r,
  // R10 = sin y cos p, R00 = cos y cos p.
  const double pitch = std::atan2(-R(2, 0), std::hypot(R(0, 0), R(1, 0)));
  double roll = 0.0;
  double yaw = 0.0;
  if (std::hypot(R(0, 0), R(1, 0)) > 1e-12) {
    roll = std::atan2(R(2, 1), R(2, 2));
    yaw = std::atan2(R(1, 0), R(0, 0));
  } else {  // gimbal lock: only yaw - roll (or yaw + roll) is defined; put it all in yaw
    yaw = std::atan2(-R(0, 1), R(1, 1));
  }
  return {roll, pitch, yaw};
}

SO3 SO3::exp(const Tangent& phi) {
  // q = (cos(a/2), sin(a/2)/a * phi), a = |phi| (Sophus SO3::expAndTheta).
  const double a2 = phi.squaredNorm();
  const double a = std::sqrt(a2);
  double w = 0.0;
  double k = 0.0;  // sin(a/2) / a
  if (a < kSmallAngle) {
    w = 1.0 - a2 / 8.0;
    k = 0.5 - a2 / 48.0;
  } else {
    w = std::cos(0.5 * a);
    k = std::sin(0.5 * a) / a;
  }
  return SO3(Quaternion(w, k * phi.x(), k * phi.y(), k * phi.z()));
}

SO3::Tangent SO3::log() const {
  // Work with the representative with w >= 0 so the angle lands in [0, pi].
  double w = q_.w();
  Vector3 v = q_.vec();
  if (w < 0.0) {
    w = -w;
    v = -v;
  }
  const double vn = v.norm();
  if (vn < kSmallAngle * 0.5) {
    // 2 atan(vn / w) / vn = 2/w (1 - vn^2 / (3 w^2)) + O(vn^4)
    const double factor = 2.0 / w - 2.0 / 3.0 * vn * vn / (w * w * w);
    return factor * v;
  }
  return (2.0 * std::atan2(vn, w) / vn) * v;
}

double SO3::angle() const { return 2.0 * std::atan2(q_.vec().norm(), std::abs(q_.w())); }

SO3 SO3::operator*(const SO3& other) const { return SO3(q_ * other.q_); }

Matrix3 SO3::hat(const Tangent& phi) {
  Matrix3 P;
  P << 0.0, -phi.z(), phi.y(), phi.z(), 0.0, -phi.x(), -phi.y(), phi.x(), 0.0;
  return P;
}

SO3::Tangent SO3::vee(const Matrix3& Phi) { return {Phi(2, 1), Phi(0, 2), Phi(1, 0)}; }

Matrix3 SO3::left_jacobian(const Tangent& phi) {
  const double a2 = phi.squaredNorm();
  const double a = std::sqrt(a2);
  const Matrix3 P = hat(phi);
  double c1 = 0.0;  // (1 - cos a) / a^2
  double c2 = 0.0;  // (a - sin a) / a^3
  if (a < kSmallAngle) {
    c1 = 0.5 - a2 / 24.0;
    c2 = 1.0 / 6.0 - a2 / 120.0;
  } else {
    // 1 - cos a = 2 sin^2(a/2), which does not cancel: (1 - cos a) loses ~8 digits near the
    // switch, and SE3::exp multiplies c1 by |phi| |rho|.
    const double s = std::sin(0.5 * a);
    c1 = 2.0 * s * s / a2;
    c2 = (a - std::sin(a)) / (a2 * a);
  }
  return Matrix3::Identity() + c1 * P + c2 * P * P;
}

Matrix3 SO3::left_jacobian_inverse(const Tangent& phi) {
  // Jl^-1 = I - 1/2 [phi]x + (1/a^2 - (1 + cos a) / (2 a sin a)) [phi]x^2
  //       = I - 1/2 [phi]x + (1/a^2 - cot(a/2) / (2a)) [phi]x^2.
  const double a2 = phi.squaredNorm();
  const double a = std::sqrt(a2);
  const Matrix3 P = hat(phi);
  double c = 0.0;
  if (a < kSmallAngle) {
    c = 1.0 / 12.0 + a2 / 720.0;
  } else {
    c = 1.0 / a2 - std::cos(0.5 * a) / (2.0 * a * std::sin(0.5 * a));
  }
  return Matrix3::Identity() - 0.5 * P + c * P * P;
}

}  // namespace cairn::core
