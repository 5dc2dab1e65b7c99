#pragma once
/// \file
/// SO(3): rotations in space, stored as a unit quaternion (Eigen order x, y, z, w in memory;
/// constructors take w first as Eigen does).
///
/// Tangent phi in R^3 is the rotation vector (axis * angle). exp is Rodrigues' formula; log
/// returns |phi| in [0, pi] and is computed from the quaternion with atan2, which stays accurate
/// as the angle approaches 0 and pi (Sophus `SO3::logAndTheta`). Left Jacobian
///   Jl(phi) = I + (1 - cos a)/a^2 [phi]x + (a - sin a)/a^3 [phi]x^2,   a = |phi|
/// and its inverse (Barfoot, "State Estimation for Robotics", 2017, eq. 7.77 and 7.79;
/// Chirikjian 2011). Jr(phi) = Jl(-phi).

#include "cairn/core/types.hpp"

namespace cairn::core {

class SO3 {
 public:
  static constexpr int kDoF = 3;
  using Tangent = Vector3;
  using Jacobian = Matrix3;

  /// Identity.
  SO3() = default;
  /// From a quaternion of any non-zero norm: it is normalised. Normalisation is idempotent:
  /// a quaternion whose squared norm is already 1 to within 4 ulp is kept bit for bit, so a
  /// rotation written to a file and read back is identical. Precondition: finite, norm > 0.
  explicit SO3(const Quaternion& q);

  /// Nearest rotation to a 3x3 matrix (via the quaternion of its orthonormal polar factor).
  static SO3 from_matrix(const Matrix3& M);
  /// R = Rz(yaw) * Ry(pitch) * Rx(roll), the convention of TORO and GTSAM's Rot3::RzRyRx.
  static SO3 from_rpy(double roll_rad, double pitch_rad, double yaw_rad);
  /// Inverse of from_rpy; pitch in [-pi/2, pi/2].
  Vector3 to_rpy() const;

  static SO3 exp(const Tangent& phi);
  Tangent log() const;
  /// Rotation angle in [0, pi].
  double angle() const;

  SO3 inverse() const { return SO3(q_.conjugate(), kNoNormalise); }
  SO3 operator*(const SO3& other) const;
  Vector3 operator*(const Vector3& p) const { return q_ * p; }

  const Quaternion& unit_quaternion() const { return q_; }
  Matrix3 matrix() const { return q_.toRotationMatrix(); }

  /// Adj = R.
  Jacobian Adj() const { return matrix(); }

  /// hat(phi) = [phi]x, the skew-symmetric matrix with hat(a) b = a x b.
  static Matrix3 hat(const Tangent& phi);
  static Tangent vee(const Matrix3& Phi);

  static Jacobian left_jacobian(const Tangent& phi);
  /// Precondition: |phi| < 2 pi.
  static Jacobian left_jacobian_inverse(const Tangent& phi);
  static Jacobian right_jacobian(const Tangent& phi) { return left_jacobian(-phi); }
  static Jacobian right_jacobian_inverse(const Tangent& phi) { return left_jacobian_inverse(-phi); }

 private:
  enum NoNormalise { kNoNormalise };
  SO3(const Quaternion& q, NoNormalise) : q_(q) {}

  Quaternion q_ = Quaternion::Identity();
};

}  // namespace cairn::core
