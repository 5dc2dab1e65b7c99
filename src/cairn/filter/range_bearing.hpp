#pragma once
/// \file
/// The 2D range-bearing measurement model, its inverse (landmark initialisation) and the
/// odometry motion model, with analytic Jacobians. Shared by EKF-SLAM (cairn::filter) and the
/// landmark graph (cairn::backend::LandmarkGraph), so both methods linearise the same functions.
///
/// Pose x = (x, y, theta) is T_world_body as a plain vector (translation first, as everywhere in
/// cairn); a landmark is its position p_world = (px, py). With d = p_world - t_world_body,
/// q = |d|^2:
///   h(x, p) = ( sqrt(q), wrap(atan2(d_y, d_x) - theta) )                    range, bearing
///   J_h_pose = [ -d_x/r  -d_y/r   0 ;  d_y/q  -d_x/q  -1 ]
///   J_h_landmark = [ d_x/r  d_y/r ; -d_y/q  d_x/q ]
/// (Thrun, Burgard, Fox, Probabilistic Robotics 2005, Table 10.1; Dissanayake et al.
/// 2001).
///
/// Inverse: p = g(x, z) = t + r (cos(theta + b), sin(theta + b)).
///
/// Odometry: the body moves by u = T_body(k)_body(k+1) = (u_x, u_y, u_theta) measured in the
/// frame of the pose it starts from: x' = f(x, u) = (t + R(theta) u_t, wrap(theta + u_theta))
/// (Smith, Self & Cheeseman 1990, the compounding operator x (+) u).

#include "cairn/core/types.hpp"

namespace cairn::filter {

using Matrix23 = Eigen::Matrix<double, 2, 3>;

/// (x, y, theta) of a pose; theta in (-pi, pi].
using PoseVector = Vector3;

/// Range and bearing of `p_world` seen from `pose`. Optional Jacobians (may be null).
/// Precondition: p_world differs from the pose's position (the Jacobians divide by the range).
Vector2 range_bearing(const PoseVector& pose, const Vector2& p_world, Matrix23* J_z_pose = nullptr,
                            Matrix2* J_z_landmark = nullptr);

/// The landmark position seen at range/bearing `z` from `pose` (the inverse of range_bearing).
Vector2 landmark_from_range_bearing(const PoseVector& pose, const Vector2& z,
                                          Matrix23* J_p_pose = nullptr, Matrix2* J_p_z = nullptr);

/// x (+) u: the pose after moving by `u` (body frame of `pose`).
PoseVector compose(const PoseVector& pose, const PoseVector& u, Matrix3* J_out_pose = nullptr,
                   Matrix3* J_out_u = nullptr);

/// (-x_i) (+) x_j: the motion from pose i to pose j in the frame of i (the inverse of compose).
PoseVector between(const PoseVector& pose_i, const PoseVector& pose_j, Matrix3* J_out_i = nullptr,
                   Matrix3* J_out_j = nullptr);

/// Innovation z_measured - z_predicted with the bearing wrapped into (-pi, pi].
Vector2 innovation(const Vector2& z_measured, const Vector2& z_predicted);

}  // namespace cairn::filter
