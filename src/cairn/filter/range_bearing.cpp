#include "cairn/filter/range_bearing.hpp"

#include <cmath>

#include "cairn/core/so2.hpp"

namespace cairn::filter {

Vector2 range_bearing(const PoseVector& pose, const Vector2& p_world, Matrix23* J_z_pose,
                            Matrix2* J_z_landmark) {
  const Vector2 d = p_world - pose.head<2>();
  const double q = d.squaredNorm();
  const double r = std::sqrt(q);
  const Vector2 z(r, core::wrap_angle(std::atan2(d.y(), d.x()) - pose.z()));
  if (J_z_pose != nullptr) {
    *J_z_pose << -d.x() / r, -d.y() / r, 0.0,  //
        d.y() / q, -d.x() / q, -1.0;
  }
  if (J_z_landmark != nullptr) {
    *J_z_landmark << d.x() / r, d.y() / r,  //
        -d.y() / q, d.x() / q;
  }
  return z;
}

Vector2 landmark_from_range_bearing(const PoseVector& pose, const Vector2& z, Matrix23* J_p_pose,
                                          Matrix2* J_p_z) {
  const double angle = pose.z() + z.y();
  const double c = std::cos(angle);
  const double s = std::sin(angle);
  const double r = z.x();
  if (J_p_pose != nullptr) {
    *J_p_pose << 1.0, 0.0, -r * s,  //
        0.0, 1.0, r * c;
  }
  if (J_p_z != nullptr) {
    *J_p_z << c, -r * s,  //
        s, r * c;
  }
  return {pose.x() + r * c, pose.y() + r * s};
}

PoseVector compose(const PoseVector& pose, const PoseVector& u, Matrix3* J_out_pose, Matrix3* J_out_u) {
  const double c = std::cos(pose.z());
  const double s = std::sin(pose.z());
  if (J_out_pose != nullptr) {
    *J_out_pose << 1.0, 0.0, -s * u.x() - c * u.y(),  //
        0.0, 1.0, c * u.x() - s * u.y(),               //
        0.0, 0.0, 1.0;
  }
  if (J_out_u != nullptr) {
    *J_out_u << c, -s, 0.0,  //
        s, c, 0.0,           //
        0.0, 0.0, 1.0;
  }
  return {pose.x() + c * u.x() - s * u.y(), pose.y() + s * u.x() + c * u.y(), core::wrap_angle(pose.z() + u.z())};
}

PoseVector between(const PoseVector& pose_i, const PoseVector& pose_j, Matrix3* J_out_i,
                   Matrix3* J_out_j) {
  const double c = std::cos(pose_i.z());
  const double s = std::sin(pose_i.z());
  const Vector2 d = pose_j.head<2>() - pose_i.head<2>();
  // R_i^T d and its derivative in theta_i (Grisetti et al. 2010, the 2D example's A_ij, B_ij
  // with the measurement left out: the residual subtracts it afterwards).
  const Vector2 local(c * d.x() + s * d.y(), -s * d.x() + c * d.y());
  if (J_out_i != nullptr) {
    *J_out_i << -c, -s, local.y(),  //
        s, -c, -local.x(),          //
        0.0, 0.0, -1.0;
  }
  if (J_out_j != nullptr) {
    *J_out_j << c, s, 0.0,  //
        -s, c, 0.0,         //
        0.0, 0.0, 1.0;
  }
  return {local.x(), local.y(), core::wrap_angle(pose_j.z() - pose_i.z())};
}

Vector2 innovation(const Vector2& z_measured, const Vector2& z_predicted) {
  return {z_measured.x() - z_predicted.x(), core::wrap_angle(z_measured.y() - z_predicted.y())};
}

}  // namespace cairn::filter
