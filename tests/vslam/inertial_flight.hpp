#pragma once
/// \file
/// Issue 40's simulated camera + IMU flight down the synthetic textured corridor
/// (synthetic_world.hpp): a smooth closed-form path, so the simulator's IMU (sim/imu.hpp) sees
/// the motion exactly, shared by the visual-inertial tests.

#include <Eigen/Geometry>
#include <cmath>

#include "cairn/core/se3.hpp"
#include "cairn/sim/imu.hpp"

namespace cairn::test {

inline constexpr double kFlightPi = 3.14159265358979323846;

// The render world has y down (synthetic_world.hpp); the IMU world has z up, x along the corridor
// (+z of the render world), y to its left (-x). R_render_imu's columns are the IMU world's axes.
inline Eigen::Matrix3d R_render_imu() { return (Eigen::Matrix3d() << 0, -1, 0, 0, 0, -1, 1, 0, 0).finished(); }

// The camera on the body (x forward, z up): its z is the body's x, its x the body's -y, its y the
// body's -z; 5 cm ahead of the IMU.
inline core::SE3 T_body_camera() {
  return core::SE3(core::SO3::from_matrix((Eigen::Matrix3d() << 0, 0, 1, -1, 0, 0, 0, -1, 0).finished()), Eigen::Vector3d(0.05, 0.0, 0.0));
}

// The camera in the render world at time t: down the corridor at about 1 m/s, swaying sideways
// and up and down, yawing and pitching a few degrees (all smooth, so the IMU sees it exactly).
// `turn_at_s` >= 0 adds a fast yaw there: a smooth bump of `turn_deg` over `turn_s` seconds
// (peak rate 2 turn_deg / turn_s), turned back over the following turn_s.
inline core::SE3 camera_in_render_world(double t, double turn_at_s = -1.0, double turn_deg = 0.0, double turn_s = 1.0) {
  const Eigen::Vector3d p(0.25 * std::sin(1.3 * t), 0.08 * std::sin(2.1 * t), 0.2 + 0.9 * t + 0.1 * std::sin(0.9 * t));
  double yaw = 10.0 * kFlightPi / 180.0 * std::sin(1.1 * t);
  if (turn_at_s >= 0.0 && t > turn_at_s && t < turn_at_s + 2.0 * turn_s) {
    yaw += turn_deg * kFlightPi / 180.0 * 0.5 * (1.0 - std::cos(kFlightPi * (t - turn_at_s) / turn_s));
  }
  const double pitch = 4.0 * kFlightPi / 180.0 * std::sin(1.7 * t);
  const Eigen::Matrix3d R =
      (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitX())).toRotationMatrix();
  return core::SE3(core::SO3::from_matrix(R), p);
}

// The body's kinematics in the IMU world by central differences of a closed-form camera path
// (h = 1e-4 s: errors ~1e-7 in velocity and ~1e-5 in acceleration, far below the IMU's noise).
template <typename CameraPath>
sim::BodyKinematics kinematics_of(const CameraPath& camera_in_render, double t) {
  const core::SE3 T_imu_render(core::SO3::from_matrix(R_render_imu().transpose()), Eigen::Vector3d::Zero());
  const core::SE3 T_camera_body = T_body_camera().inverse();
  auto body = [&](double s) { return T_imu_render * camera_in_render(s) * T_camera_body; };
  constexpr double h = 1e-4;
  const core::SE3 T = body(t), before = body(t - h), after = body(t + h);
  sim::BodyKinematics k;
  k.T_world_body = T;
  k.v_world_mps = (after.translation() - before.translation()) / (2.0 * h);
  k.a_world_mps2 = (after.translation() - 2.0 * T.translation() + before.translation()) / (h * h);
  k.omega_body_rad_s = (before.so3().inverse() * after.so3()).log() / (2.0 * h);
  return k;
}

}  // namespace cairn::test
