#include "cairn/core/sim3.hpp"

#include <Eigen/LU>
#include <cmath>

#include "cairn/core/assert.hpp"

namespace cairn::core {
namespace {

constexpr double kSmallAngle = 1e-4;
// Below this |(sigma, a)| the coefficients of W come from their joint power series.
constexpr double kSeriesRadius = 1.0;

double sinc(double a) { return a < kSmallAngle ? 1.0 - a * a / 6.0 : std::sin(a) / a; }

// W(sigma, phi) = C I + A [phi]x + B [phi]x^2 (sim3.hpp), a = |phi|:
//   C = int_0^1 e^(u sigma) du,  A = int_0^1 e^(u sigma) sin(u a) / a du,
//   B = int_0^1 e^(u sigma) (1 - cos(u a)) / a^2 du.
// With z = sigma + i a and f(z) = (e^z - 1) / z = int_0^1 e^(u z) du:
//   C = f(sigma), A = Im f(z) / a, B = (f(sigma) - Re f(z)) / a^2
// (Eade, "Lie groups for computer vision"; Sophus sim_details.hpp calcW has the same closed
// forms, with cruder limits).
struct WCoefficients {
  double C = 1.0;
  double A = 0.5;
  double B = 1.0 / 6.0;
};

WCoefficients w_coefficients(double sigma, double a) {
  WCoefficients w;
  const double a2 = a * a;
  const double r2 = sigma * sigma + a2;
  if (r2 < kSeriesRadius * kSeriesRadius) {
    // f(z) = sum_n z^n / (n+1)!. Write z^n = p_n + i a q_n and sigma^n - p_n = a^2 w_n; then
    //   p_{n+1} = sigma p_n - a^2 q_n,  q_{n+1} = p_n + sigma q_n,  w_{n+1} = sigma w_n + q_n,
    // and C = sum sigma^n / (n+1)!, A = sum q_n / (n+1)!, B = sum w_n / (n+1)!: polynomials in
    // sigma and a^2 with no division, so nothing cancels as sigma and a go to 0. |z| < 1: the
    // terms are below n^2 / (n+1)! < 1e-18 after n = 22.
    double p = 1.0, q = 0.0, wn = 0.0, sigma_n = 1.0;
    double inverse_factorial = 1.0;  // 1 / (n+1)!
    w.C = w.A = w.B = 0.0;
    for (int n = 0; n <= 24; ++n) {
      w.C += sigma_n * inverse_factorial;
      w.A += q * inverse_factorial;
      w.B += wn * inverse_factorial;
      const double p_next = sigma * p - a2 * q;
      const double q_next = p + sigma * q;
      wn = sigma * wn + q;
      p = p_next;
      q = q_next;
      sigma_n *= sigma;
      inverse_factorial /= static_cast<double>(n + 2);
    }
    return w;
  }
  // |z| >= 1: closed forms, arranged so that only the removable singularities at a = 0 (when
  // |sigma| >= 1) and sigma = 0 (when a >= 1) remain, and those are resolved by sinc and by
  // choosing the form by which of |sigma| and a is larger.
  const double s = std::exp(sigma);
  const double em1 = std::expm1(sigma);  // s - 1 without cancellation
  const double cos_a = std::cos(a);
  const double sin_half = std::sin(0.5 * a);
  const double one_minus_cos = 2.0 * sin_half * sin_half;
  w.C = sigma == 0.0 ? 1.0 : em1 / sigma;
  // Im f(z) = (s sigma sin a + (1 - s cos a) a) / r^2, divided by a; 1 - s cos a written as
  // (1 - cos a) - (s - 1) cos a.
  w.A = (s * sigma * sinc(a) + one_minus_cos - em1 * cos_a) / r2;
  if (std::abs(sigma) >= a) {
    // (f(sigma) - Re f(z)) / a^2 = (sigma^2 s (1 - cos a) / a^2 + (s - 1) - sigma s sin a / a)
    //                              / (sigma r^2)   (|sigma| >= 1/sqrt 2 here)
    const double h = sinc(0.5 * a);  // (1 - cos a) / a^2 = h^2 / 2
    w.B = (sigma * sigma * s * 0.5 * h * h + em1 - sigma * s * sinc(a)) / (sigma * r2);
  } else {
    // a > 1/sqrt 2: divide by a^2 directly.
    const double re_f = ((em1 * cos_a - one_minus_cos) * sigma + s * a * std::sin(a)) / r2;
    w.B = (w.C - re_f) / a2;
  }
  return w;
}

// W^-1 = C' I + A' [phi]x + B' [phi]x^2. W acts as C on phi and as f(z), f(conj z) on the plane
// orthogonal to it (where [phi]x has eigenvalues +-i a), so W^-1 acts as 1/C and 1/f(z):
//   C' = 1 / C,  A' = Im(1/f(z)) / a = -A / D,  B' = (1/C - Re(1/f(z))) / a^2
//      = (A^2 - C B + B^2 a^2) / (C D),  D = |f(z)|^2 = (C - B a^2)^2 + A^2 a^2,
// with no division by a.
WCoefficients w_inverse_coefficients(double sigma, double a) {
  const WCoefficients w = w_coefficients(sigma, a);
  const double a2 = a * a;
  const double re_f = w.C - w.B * a2;
  const double D = re_f * re_f + w.A * w.A * a2;
  WCoefficients inv;
  inv.C = 1.0 / w.C;
  inv.A = -w.A / D;
  inv.B = (w.A * w.A - w.C * w.B + w.B * w.B * a2) / (w.C * D);
  return inv;
}

Matrix3 from_coefficients(const WCoefficients& w, const Vector3& phi) {
  const Matrix3 P = SO3::hat(phi);
  return w.C * Matrix3::Identity() + w.A * P + w.B * P * P;
}

// The couplings of Jl(xi) = [[W, X, Y], [0, Jl_SO3, 0], [0, 0, 1]] (sim3.hpp): with
// ad^k = [[A^k, X_k, Y_k], [0, Phi^k, 0], [0, 0, 0]] for k >= 1,
//   X_1 = [rho]x, X_{k+1} = A X_k + [rho]x Phi^k,  Y_1 = -rho, Y_{k+1} = A Y_k,
//   X = sum_{k>=1} X_k / (k+1)!,  Y = sum_{k>=1} Y_k / (k+1)!.
// ||A||_2 = r = |(sigma, |phi|)| (A is normal) and ||Phi||_2 <= r, so ||X_k|| <= k |rho| r^(k-1)
// and ||Y_k|| <= |rho| r^(k-1). Once k >= 2r the bounds fall at least geometrically by 2, and
// the sum stops when r^(k-1) / k! < 1e-17: the rest of the series is below 2e-17 |rho|.
void jacobian_couplings(const Vector3& rho, const Vector3& phi, double sigma, Matrix3& X, Vector3& Y) {
  const Matrix3 Phi = SO3::hat(phi);
  const Matrix3 A = Phi + sigma * Matrix3::Identity();
  const Matrix3 P = SO3::hat(rho);
  const double r = std::sqrt(sigma * sigma + phi.squaredNorm());
  CAIRN_ASSERT(r < 60.0, "Sim3 Jacobians: |(sigma, phi)| must be below 60");
  Matrix3 X_k = P;
  Vector3 Y_k = -rho;
  Matrix3 Phi_k = Phi;
  double inverse_factorial = 0.5;  // 1 / (k+1)!
  double bound = 1.0;              // r^(k-1) / k!
  X = 0.5 * P;
  Y = -0.5 * rho;
  for (int k = 1; k < 200; ++k) {
    if (k >= 2.0 * r && bound < 1e-17) break;
    X_k = (A * X_k + P * Phi_k).eval();
    Y_k = (A * Y_k).eval();
    Phi_k = (Phi_k * Phi).eval();
    inverse_factorial /= static_cast<double>(k + 2);
    bound *= r / static_cast<double>(k + 1);
    X += inverse_factorial * X_k;
    Y += inverse_factorial * Y_k;
  }
}

}  // namespace

Sim3::Sim3(const SO3& R, const Vector3& t, double scale) : R_(R), t_(t), scale_(scale) {
  CAIRN_ASSERT(std::isfinite(scale) && scale > 0.0, "Sim3 needs a finite scale > 0");
  sigma_ = std::log(scale);
}

Sim3 Sim3::from_matrix(const Matrix4& S) {
  const Matrix3 sR = S.topLeftCorner<3, 3>();
  const double det = sR.determinant();
  CAIRN_ASSERT(det > 0.0, "Sim3::from_matrix needs det(s R) > 0");
  const double scale = std::cbrt(det);
  return Sim3(SO3::from_matrix(sR / scale), S.topRightCorner<3, 1>(), scale);
}

Matrix3 Sim3::W(double sigma, const Vector3& phi) {
  return from_coefficients(w_coefficients(sigma, phi.norm()), phi);
}

Matrix3 Sim3::W_inverse(double sigma, const Vector3& phi) {
  return from_coefficients(w_inverse_coefficients(sigma, phi.norm()), phi);
}

Sim3 Sim3::exp(const Tangent& xi) {
  const Vector3 rho = xi.head<3>();
  const Vector3 phi = xi.segment<3>(3);
  const double sigma = xi(6);
  return Sim3(SO3::exp(phi), W(sigma, phi) * rho, sigma, std::exp(sigma), kUnchecked);
}

Sim3::Tangent Sim3::log() const {
  const Vector3 phi = R_.log();
  const double sigma = sigma_;
  Tangent xi;
  xi.head<3>() = W_inverse(sigma, phi) * t_;
  xi.segment<3>(3) = phi;
  xi(6) = sigma;
  return xi;
}

Sim3::Tangent Sim3::log(Jacobian& right_jacobian_inverse_at_log) const {
  const Tangent xi = log();
  right_jacobian_inverse_at_log = right_jacobian_inverse(xi);
  return xi;
}

Sim3 Sim3::inverse() const {
  const SO3 R_inv = R_.inverse();
  const double s_inv = 1.0 / scale_;
  return Sim3(R_inv, -s_inv * (R_inv * t_), -sigma_, s_inv, kUnchecked);
}

Matrix4 Sim3::matrix() const {
  Matrix4 S = Matrix4::Identity();
  S.topLeftCorner<3, 3>() = scale_ * R_.matrix();
  S.topRightCorner<3, 1>() = t_;
  return S;
}

Sim3::Jacobian Sim3::Adj() const {
  const Matrix3 R = R_.matrix();
  Jacobian A = Jacobian::Zero();
  A.topLeftCorner<3, 3>() = scale_ * R;
  A.block<3, 3>(0, 3) = SO3::hat(t_) * R;
  A.block<3, 1>(0, 6) = -t_;
  A.block<3, 3>(3, 3) = R;
  A(6, 6) = 1.0;
  return A;
}

Matrix4 Sim3::hat(const Tangent& xi) {
  Matrix4 X = Matrix4::Zero();
  X.topLeftCorner<3, 3>() = SO3::hat(xi.segment<3>(3)) + xi(6) * Matrix3::Identity();
  X.topRightCorner<3, 1>() = xi.head<3>();
  return X;
}

Sim3::Tangent Sim3::vee(const Matrix4& Xi) {
  Tangent xi;
  xi.head<3>() = Xi.topRightCorner<3, 1>();
  const Matrix3 M = Xi.topLeftCorner<3, 3>();
  xi.segment<3>(3) = SO3::vee(0.5 * (M - M.transpose()));
  xi(6) = M.trace() / 3.0;
  return xi;
}

Sim3::Jacobian Sim3::ad(const Tangent& xi) {
  const Vector3 rho = xi.head<3>();
  const Matrix3 Phi = SO3::hat(xi.segment<3>(3));
  Jacobian a = Jacobian::Zero();
  a.topLeftCorner<3, 3>() = Phi + xi(6) * Matrix3::Identity();
  a.block<3, 3>(0, 3) = SO3::hat(rho);
  a.block<3, 1>(0, 6) = -rho;
  a.block<3, 3>(3, 3) = Phi;
  return a;
}

Sim3::Jacobian Sim3::left_jacobian(const Tangent& xi) {
  const Vector3 rho = xi.head<3>();
  const Vector3 phi = xi.segment<3>(3);
  const double sigma = xi(6);
  Matrix3 X;
  Vector3 Y;
  jacobian_couplings(rho, phi, sigma, X, Y);
  Jacobian J = Jacobian::Zero();
  J.topLeftCorner<3, 3>() = W(sigma, phi);
  J.block<3, 3>(0, 3) = X;
  J.block<3, 1>(0, 6) = Y;
  J.block<3, 3>(3, 3) = SO3::left_jacobian(phi);
  J(6, 6) = 1.0;
  return J;
}

Sim3::Jacobian Sim3::left_jacobian_inverse(const Tangent& xi) {
  const Vector3 rho = xi.head<3>();
  const Vector3 phi = xi.segment<3>(3);
  const double sigma = xi(6);
  Matrix3 X;
  Vector3 Y;
  jacobian_couplings(rho, phi, sigma, X, Y);
  const Matrix3 W_inv = W_inverse(sigma, phi);
  const Matrix3 J_inv = SO3::left_jacobian_inverse(phi);
  Jacobian K = Jacobian::Zero();
  K.topLeftCorner<3, 3>() = W_inv;
  K.block<3, 3>(0, 3) = -W_inv * X * J_inv;
  K.block<3, 1>(0, 6) = -W_inv * Y;
  K.block<3, 3>(3, 3) = J_inv;
  K(6, 6) = 1.0;
  return K;
}

}  // namespace cairn::core
