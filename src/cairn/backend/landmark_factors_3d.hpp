#pragma once
/// \file
/// Factors between an SE(3) pose and a 3D point landmark, for visual / 3D landmark SLAM: the
/// residuals and their analytic Jacobians (checked numerically in tests/landmarks). Only the
/// factors exist so far; no 3D landmark solver uses them yet (see docs/landmark-slam.md).
///
/// Pose perturbation: T_world_body <- T_world_body * exp(delta), delta = (rho, phi) translation
/// first (docs/conventions.md), so the landmark in the body frame q = T_world_body^-1 p_world moves
/// by dq = -rho + q x phi:  J_q_pose = [ -I  hat(q) ],  J_q_landmark = R_world_body^T
/// (Barfoot 2017, "State Estimation for Robotics", the point-transformation Jacobian, here with the perturbation on the right of the pose).
///
/// * Point factor: e = q - q_measured (a stereo / RGB-D point in the body frame).
/// * Range-bearing-elevation factor: z = (r, b, el) with r = |q|, b = atan2(q_y, q_x),
///   el = atan2(q_z, sqrt(q_x^2 + q_y^2)); e = h(q) - z, angles wrapped.

#include "cairn/core/se3.hpp"
#include "cairn/core/types.hpp"

namespace cairn::backend {

using Matrix36 = Eigen::Matrix<double, 3, 6>;

/// e = T_world_body^-1 p_world - q_measured.
Vector3 point_residual_3d(const core::SE3& T_world_body, const Vector3& p_world, const Vector3& q_measured,
                          Matrix36* J_e_pose = nullptr, Matrix3* J_e_landmark = nullptr);

/// e = (range, bearing, elevation)(T_world_body^-1 p_world) - z (angles wrapped). Precondition:
/// the landmark is not on the body's z axis through the origin (bearing undefined).
Vector3 range_bearing_elevation_residual_3d(const core::SE3& T_world_body, const Vector3& p_world, const Vector3& z,
                                            Matrix36* J_e_pose = nullptr, Matrix3* J_e_landmark = nullptr);

}  // namespace cairn::backend
