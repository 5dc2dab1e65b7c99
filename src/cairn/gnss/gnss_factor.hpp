#pragma once
/// \file
/// The GNSS position factor on the least-squares engine (`GnssPositionFactor`): one fix pulls
/// the antenna of one pose variable T_world_body (backend::se3_manifold) towards the fix's
/// position in the local ENU frame, weighted by the receiver's covariance, and its options
/// (`GnssFactorOptions`: lever arm, the world-to-ENU transform, default sigmas, robust kernel).
///
/// Residual (whitened, 3 values):
///
///     e = T_enu_world * (t_world_body + R_world_body * l_body) - p_enu_antenna
///     r = S e,   S^T S = Sigma^-1   (S = Lambda^-1/2 V^T from Sigma = V Lambda V^T)
///
/// with l_body the lever arm (the antenna in the body frame). For the engine's update
/// T <- T exp(delta), delta = (rho, phi) (t' = t + R rho, R' = R exp(phi) to first order):
///
///     dr/drho = S R_enu_world R_world_body
///     dr/dphi = -S R_enu_world R_world_body [l_body]x
///
/// (R exp(phi) l ~= R (l + phi x l) = R l - R [l]x phi; Barfoot, "State Estimation for
/// Robotics", 2017, eq. 7.185's first-order perturbation of a rotated point.)
///
/// Frames: the engine's world is the pipeline's world; T_enu_world maps it into the ENU frame of
/// the fixes and is held fixed (identity when the pipeline's world is the ENU frame itself; from
/// gnss_yaw.hpp's alignment when the world is an odometry frame). Estimating it jointly would need
/// a second variable; cairn aligns once by motion (gnss_yaw.hpp) instead.
///
/// Robust kernel (GnssFactorOptions::loss, passed to add_factor): Cauchy is recommended for
/// GNSS. Its influence rho'(s) = 1 / (1 + s / c^2) falls towards zero with the residual, so a
/// 10-50 m jump or a multipath excursion of many sigmas pulls almost nothing (weight 0.003 at
/// 50 sigma with c = 2.8), whereas Huber's influence stays constant beyond c: every outlier
/// still drags the trajectory with a fixed force, and a run of multipath fixes biases it. The
/// price of Cauchy is a non-convex cost, harmless here because odometry (or the IMU) gives an
/// initial guess far better than the outliers' size. The scale c = 2.7955 = sqrt(chi2_3^-1(0.95))
/// keeps 95 % of good fixes in the near-quadratic zone.

#include <memory>
#include <string>

#include "cairn/backend/least_squares.hpp"
#include "cairn/core/se3.hpp"
#include "cairn/core/types.hpp"
#include "cairn/gnss/gnss_fix.hpp"
#include "cairn/gnss/local_frame.hpp"

namespace cairn::gnss {

struct GnssFactorOptions {
  /// The antenna's position in the body frame, metres (any finite vector).
  Vector3 lever_arm_body_m = Vector3::Zero();
  /// The pipeline's world in the fixes' ENU frame; identity = the world is the ENU frame.
  core::SE3 T_enu_world;
  /// Sigmas used when a fix has no covariance (covariance_known false), metres, > 0. Defaults: a
  /// consumer receiver without augmentation (horizontal ~2.5 m, vertical about twice that).
  double default_sigma_horizontal_m = 2.5;
  double default_sigma_vertical_m = 5.0;
  /// Floor on the standard deviation along each principal axis of a fix's covariance, metres,
  /// > 0: a receiver reporting a zero or tiny variance would otherwise give an infinite or
  /// absurd weight. 0.01 m is below RTK's centimetre level.
  double min_sigma_m = 0.01;
  /// The robust kernel for add_factor, scale in sigmas (see the file comment: Cauchy, c = 2.7955).
  backend::FactorLoss loss = {backend::RobustKernel::kCauchy, 2.7955};
  bool is_valid(std::string* why) const;
};

/// The covariance the factor uses for `fix`, m^2 in ENU: the receiver's when known, else the
/// default sigmas; principal sigmas floored at min_sigma_m.
Matrix3 factor_covariance_enu(const GnssFix& fix, const GnssFactorOptions& options);

class GnssPositionFactor final : public backend::Factor {
 public:
  /// `covariance_enu_m2` symmetric positive definite (factor_covariance_enu gives one).
  GnssPositionFactor(const Vector3& p_enu_antenna_m, const Matrix3& covariance_enu_m2, const Vector3& lever_arm_body_m,
                     const core::SE3& T_enu_world = core::SE3());

  int residual_size() const override { return 3; }
  /// values[0]: T_world_body in se3_manifold's storage; jacobians[0]: 3 x 6 row-major.
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override;

  /// e (metres, ENU) and r = S e at a pose, for checks after a solve.
  Vector3 error_enu_m(const core::SE3& T_world_body) const;
  Vector3 whitened_residual(const core::SE3& T_world_body) const { return S_ * error_enu_m(T_world_body); }
  /// e^T Sigma^-1 e: chi-square with 3 degrees of freedom for a correct fix at the true pose.
  double squared_mahalanobis(const core::SE3& T_world_body) const { return whitened_residual(T_world_body).squaredNorm(); }
  const Matrix3& square_root_information() const { return S_; }
  const Vector3& p_enu_antenna_m() const { return p_enu_antenna_m_; }

 private:
  Vector3 p_enu_antenna_m_;
  Matrix3 S_;
  Vector3 lever_arm_body_m_;
  core::SE3 T_enu_world_;
};

/// The factor of `fix` (its position through `frame`, its covariance by factor_covariance_enu).
std::unique_ptr<GnssPositionFactor> make_gnss_factor(const GnssFix& fix, const LocalFrame& frame,
                                                     const GnssFactorOptions& options);

}  // namespace cairn::gnss
