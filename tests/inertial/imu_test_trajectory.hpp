#pragma once
/// A closed-form 3D trajectory for the IMU tests, independent of the code under test:
///   R(t) = Rz(alpha t) Ry(beta sin(gamma t)),  p(t) = (a sin(f t), b (1 - cos(f t)), c t^2 / 2),
/// with omega_body = Ry^T (alpha e_z) + beta gamma cos(gamma t) e_y (from R^T dR/dt for a product of
/// rotations about fixed axes) and the specific force R^T (p'' - g), g = (0, 0, -9.80665).

#include <cmath>
#include <random>
#include <vector>

#include "cairn/core/so3.hpp"
#include "cairn/inertial/imu_types.hpp"

namespace cairn::inertial::test {

struct AnalyticTrajectory {
  double alpha = 1.0, beta = 0.3, gamma = 2.0;  // rad/s, rad, rad/s
  double a = 2.0, b = 1.0, f = 0.8, c = 0.5;     // m, m, rad/s, m/s^2

  Matrix3 R(double t) const {
    return (Eigen::AngleAxisd(alpha * t, Vector3::UnitZ()) * Eigen::AngleAxisd(beta * std::sin(gamma * t), Vector3::UnitY()))
        .toRotationMatrix();
  }
  Vector3 p(double t) const { return {a * std::sin(f * t), b * (1.0 - std::cos(f * t)), 0.5 * c * t * t}; }
  Vector3 v(double t) const { return {a * f * std::cos(f * t), b * f * std::sin(f * t), c * t}; }
  Vector3 acceleration(double t) const { return {-a * f * f * std::sin(f * t), b * f * f * std::cos(f * t), c}; }
  Vector3 omega_body(double t) const {
    const Matrix3 Ry = Eigen::AngleAxisd(beta * std::sin(gamma * t), Vector3::UnitY()).toRotationMatrix();
    return Ry.transpose() * (alpha * Vector3::UnitZ()) + beta * gamma * std::cos(gamma * t) * Vector3::UnitY();
  }
  Vector3 specific_force(double t) const {
    return R(t).transpose() * (acceleration(t) - Vector3(0.0, 0.0, -kStandardGravity));
  }
  NavState state(double t) const { return {core::SE3(core::SO3::from_matrix(R(t)), p(t)), v(t)}; }
};

/// Noise-free samples every dt over [t0, t1) (the reading at the start of each piece).
inline std::vector<ImuSample> sample_imu(const AnalyticTrajectory& truth, double t0, double t1, double dt,
                                         const ImuBias& bias = {}) {
  std::vector<ImuSample> samples;
  const int n = static_cast<int>(std::llround((t1 - t0) / dt));
  for (int k = 0; k <= n; ++k) {
    const double t = t0 + k * dt;
    samples.push_back({core::Timestamp::from_seconds(t), truth.omega_body(t) + bias.gyro_rad_s,
                       truth.specific_force(t) + bias.accel_mps2});
  }
  return samples;
}

}  // namespace cairn::inertial::test
