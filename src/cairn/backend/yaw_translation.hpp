#pragma once
/// \file
/// Poses that may only turn about gravity and move: the 4-DoF pose graph of a visual-inertial map
/// (Qin, Li & Shen, "VINS-Mono", T-RO 34(4), 2018, Sec. VIII-B; Campos et al., "ORB-SLAM3", T-RO
/// 2021, Sec. VII-B, OptimizeEssentialGraph4DoF). With an IMU the roll and pitch of every pose
/// are observable (gravity fixes them), so a loop correction may change only yaw and position.
///
///  * YawTranslationManifold: se3_manifold()'s storage (qx, qy, qz, qw, tx, ty, tz), T_world_body,
///    with a 4-vector tangent delta = (dx, dy, dz, dyaw) applied in the world frame:
///      R <- Exp(up dyaw) R,  p <- p + (dx, dy, dz),
///    so R^T up (the gravity direction in the body) never changes.
///  * YawTranslationAdapter: a factor written for se3_manifold() poses (its Jacobians on the right
///    perturbation (rho, phi)) used on poses of this manifold. To first order
///    T exp(rho, phi) = (Exp(up dyaw) R, p + d) when rho = R^T d and phi = R^T up dyaw, so each
///    adapted Jacobian block is the SE(3) one times [[R^T, 0], [0, R^T up]] (6 x 4).

#include <memory>
#include <vector>

#include "cairn/backend/least_squares.hpp"

namespace cairn::backend {

class YawTranslationManifold final : public Manifold {
 public:
  /// `up_world`: the world's up direction (minus gravity), normalised here; must not be zero.
  explicit YawTranslationManifold(const Eigen::Vector3d& up_world);
  int ambient_size() const override { return 7; }
  int tangent_size() const override { return 4; }
  void plus(const double* x, const double* delta, double* x_plus) const override;
  std::string_view name() const override { return "SE(3), yaw about gravity and translation"; }
  /// d(rho, phi) / d(dx, dy, dz, dyaw) at the pose stored in x, row-major 6 x 4.
  Eigen::Matrix<double, 6, 4> se3_tangent_jacobian(const double* x) const;
  const Eigen::Vector3d& up() const { return up_; }

 private:
  Eigen::Vector3d up_;
};

class YawTranslationAdapter final : public Factor {
 public:
  /// `manifolds[b]`: the manifold of variable b when it is a YawTranslationManifold (its Jacobian
  /// block is converted), nullptr when the variable is left as the inner factor has it.
  YawTranslationAdapter(std::unique_ptr<Factor> inner, std::vector<const YawTranslationManifold*> manifolds);
  int residual_size() const override { return inner_->residual_size(); }
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override;

 private:
  std::unique_ptr<Factor> inner_;
  std::vector<const YawTranslationManifold*> manifolds_;
};

}  // namespace cairn::backend
