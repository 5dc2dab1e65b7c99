#pragma once
/// \file
/// Sim(3): similarity transforms S = (s R, t), s > 0, acting as S * p = s R p + t; as a matrix
/// [[s R, t], [0, 1]]. Monocular SLAM's loop closures live here: scale is unobservable and
/// drifts, and closing a loop must correct it (Strasdat, Montiel & Davison, "Scale drift-aware
/// large scale monocular SLAM", RSS 2010; ORB-SLAM's essential graph, Optimizer::
/// OptimizeEssentialGraph, is optimised over Sim(3)).
///
/// Tangent vectors xi = (rho (3), phi (3), sigma (1)): translation first as in SE3 and Sophus'
/// Sim3, then the rotation vector, then the log-scale sigma = ln s. (g2o's Sim3 / ORB-SLAM's
/// VertexSim3Expmap order (phi, rho, sigma); permute when comparing with them.)
/// hat(xi) = [[[phi]x + sigma I, rho], [0, 0]], and
///   exp(xi) = (e^sigma exp(phi), W(sigma, phi) rho),  W = sum_k A^k / (k+1)!,  A = [phi]x + sigma I
/// (Strasdat, "Local accuracy and global consistency for efficient visual SLAM", PhD thesis,
/// Imperial College 2012, appendix on Lie groups; Sophus sim_details.hpp, calcW). W is written as
///   W = C I + A' [phi]x + B' [phi]x^2 with
///   C = int_0^1 e^(u sigma) du, A' = int_0^1 e^(u sigma) sin(u a) / a du,
///   B' = int_0^1 e^(u sigma) (1 - cos(u a)) / a^2 du,   a = |phi|
/// (Eade, "Lie groups for computer vision", Sim(3) section), evaluated in closed form away from
/// (sigma, a) = 0 and by their joint power series near it (sim3.cpp), so that no branch loses
/// digits. W^-1, needed by log, is again C' I + A'' [phi]x + B'' [phi]x^2 with coefficients from
/// C, A', B' in closed form (sim3.cpp).
///
/// Jacobians: Jl(xi) = sum_k ad(xi)^k / (k+1)!, Jr(xi) = Jl(-xi). With ad block upper triangular,
///   ad(xi) = [[A, [rho]x, -rho], [0, [phi]x, 0], [0, 0, 0]],
///   Jl(xi) = [[W(sigma, phi), X, Y], [0, Jl_SO3(phi), 0], [0, 0, 1]],
/// the diagonal blocks are the closed forms above; the couplings X (the analogue of SE(3)'s
/// Q of Barfoot 2017, eq. 7.86) and Y = -f2(A) rho, f2(x) = (e^x - 1 - x) / x^2, are summed as
/// their power series, truncated where a bound on the remaining terms (||A|| = |(sigma, |phi|)|,
/// so ||k-th term|| <= k |rho| r^(k-1) / (k+1)!) falls below 1e-17 |rho| (about 30 terms at
/// r = 4; precondition r < 60). Their closed forms are long double integrals of exponentials and
/// trigonometric functions; the series needs no small-angle or small-sigma branches. Against the
/// top-right block of the matrix exponential of [[ad, I], [0, 0]] (|phi| <= 3, |rho| <= 17,
/// error relative to max(1, |Jl|)): 2e-14 for |sigma| <= 5, 5e-14 at |sigma| = 8, 8e-13 at
/// |sigma| = 12 (for sigma < 0 the terms alternate and the sum loses digits slowly). The inverse
/// is by blocks:
///   Jl^-1 = [[W^-1, -W^-1 X Jl_SO3^-1, -W^-1 Y], [0, Jl_SO3^-1, 0], [0, 0, 1]].

#include "cairn/core/se3.hpp"
#include "cairn/core/so3.hpp"

namespace cairn::core {

class Sim3 {
 public:
  static constexpr int kDoF = 7;
  using Tangent = Eigen::Matrix<double, 7, 1>;
  using Jacobian = Eigen::Matrix<double, 7, 7>;

  /// Identity.
  Sim3() = default;
  /// S = (scale R, t). Precondition: scale finite and > 0.
  Sim3(const SO3& R, const Vector3& t, double scale);
  /// From a quaternion (normalised, see SO3), a translation and a scale > 0.
  Sim3(const Quaternion& q, const Vector3& t, double scale) : Sim3(SO3(q), t, scale) {}
  /// S = (scale R, t) from T = (R, t): the rigid pose with a scale. scale 1 embeds SE(3).
  explicit Sim3(const SE3& T, double scale = 1.0) : Sim3(T.so3(), T.translation(), scale) {}

  /// From a 4x4 matrix [[s R, t], [0, 1]]: s = det(top-left)^(1/3), R its projection onto SO(3)
  /// after dividing by s. Precondition: det(top-left) > 0.
  static Sim3 from_matrix(const Matrix4& S);

  static Sim3 exp(const Tangent& xi);
  Tangent log() const;
  /// log() and Jr^-1 at it (right_jacobian_inverse(log())).
  Tangent log(Jacobian& right_jacobian_inverse_at_log) const;

  Sim3 inverse() const;
  Sim3 operator*(const Sim3& other) const {
    return Sim3(R_ * other.R_, scale_ * (R_ * other.t_) + t_, sigma_ + other.sigma_, scale_ * other.scale_,
                kUnchecked);
  }
  Vector3 operator*(const Vector3& p) const { return scale_ * (R_ * p) + t_; }

  double scale() const { return scale_; }
  /// sigma = ln(scale), kept alongside the scale so that log(exp(xi)) returns a tiny sigma to
  /// full relative accuracy (the scale 1 + 1e-13 alone would round it to 3 digits).
  double log_scale() const { return sigma_; }
  const SO3& so3() const { return R_; }
  const Quaternion& unit_quaternion() const { return R_.unit_quaternion(); }
  Matrix3 rotation_matrix() const { return R_.matrix(); }
  const Vector3& translation() const { return t_; }
  /// [[s R, t], [0, 1]].
  Matrix4 matrix() const;
  /// The rigid part (R, t), the scale dropped. For S_world_body this is T_world_body: the body's
  /// origin is at t with orientation R, s being the scale of its local map. (ORB-SLAM's
  /// camera-from-world S_cw converts as (R, t / s) = S_cw^-1.to_se3().inverse().)
  SE3 to_se3() const { return SE3(R_, t_); }

  /// Adj = [[s R, [t]x R, -t], [0, R, 0], [0, 0, 1]] so that S * exp(xi) * S^-1 = exp(Adj * xi)
  /// (Sophus Sim3::Adj).
  Jacobian Adj() const;

  /// hat(xi) = [[[phi]x + sigma I, rho], [0, 0]].
  static Matrix4 hat(const Tangent& xi);
  /// Inverse of hat: sigma from the trace of the top-left block, phi from its skew part.
  static Tangent vee(const Matrix4& Xi);
  /// ad(xi) with hat(ad(xi) eta) = hat(xi) hat(eta) - hat(eta) hat(xi).
  static Jacobian ad(const Tangent& xi);

  /// W(sigma, phi) = sum_k A^k / (k+1)!, t = W rho in exp; and its inverse (precondition
  /// |phi| < 2 pi: W is singular exactly at sigma = 0, |phi| = 2 pi k, k >= 1).
  static Matrix3 W(double sigma, const Vector3& phi);
  static Matrix3 W_inverse(double sigma, const Vector3& phi);

  /// Precondition (all four Jacobians): |(sigma, |phi|)| < 60, the range of the coupling series.
  static Jacobian left_jacobian(const Tangent& xi);
  /// Precondition: also |phi| < 2 pi.
  static Jacobian left_jacobian_inverse(const Tangent& xi);
  static Jacobian right_jacobian(const Tangent& xi) { return left_jacobian(-xi); }
  static Jacobian right_jacobian_inverse(const Tangent& xi) { return left_jacobian_inverse(-xi); }

 private:
  enum Unchecked { kUnchecked };
  Sim3(const SO3& R, const Vector3& t, double log_scale, double scale, Unchecked)
      : R_(R), t_(t), sigma_(log_scale), scale_(scale) {}

  SO3 R_;
  Vector3 t_ = Vector3::Zero();
  double sigma_ = 0.0;  // ln(scale_)
  double scale_ = 1.0;
};

}  // namespace cairn::core
