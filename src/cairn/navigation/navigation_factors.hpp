#pragma once
/// \file
/// The two factors a ground vehicle's navigation adds to the IMU's (inertial/imu_factors.hpp), on
/// the least-squares engine, over the IMU's state (pose T_world_imu as se3_manifold(), velocity of
/// the IMU in the world as euclidean_manifold(3)):
///
///  * `WheelVelocityFactor`: the vehicle's velocity in its own frame (x forward, y left, z up, the
///    wheel odometry's child frame) is (v_wheel, 0, 0): forward speed from the wheels, zero lateral
///    and vertical speed: the non-holonomic constraint of a wheeled vehicle that neither slides
///    sideways nor leaves the ground (Dissanayake, Sukkarieh, Nebot, Durrant-Whyte, "The aiding of
///    a low-cost strapdown inertial measurement unit using vehicle model constraints for land
///    vehicle applications", IEEE T-RA 17(5), 2001, Sec. III; Shin, "Estimation techniques for
///    low-cost inertial navigation", PhD thesis, Calgary 2005, Sec. 5.2). With the vehicle at
///    t_iv in the IMU frame and R_iv its rotation, the vehicle origin moves at
///      v_vehicle = R_iv^T (R_wi^T v_w + omega_i x t_iv)
///    (a rigid body: v_B = v_A + omega x r_AB), omega_i the IMU's angular rate (gyro minus bias, held
///    known). Residual r = S (v_vehicle - (v_wheel, 0, 0)), S = diag(1/sigma). With u = R_wi^T v_w
///    and the engine's update R <- R Exp(phi), v <- v + dv:
///      dr/dphi = S R_iv^T [u]x,   dr/drho = 0,   dr/dv = S R_iv^T R_wi^T
///    (Exp(phi)^T u ~ u - phi x u = u + [u]x phi).
///  * `ShiftedGnssFactor`: a GNSS fix taken dt seconds after a state (|dt| at most half the state
///    period) as gnss::GnssPositionFactor on the state's pose moved along its velocity,
///    t' = t_wi + v_w dt (rotation unchanged over dt: the lever arm's change omega dt x l is below
///    1 mm for the lever arms and rates of a ground vehicle at dt <= 0.05 s). Its Jacobians are
///    GnssPositionFactor's at the moved pose, and dr/dv = (dr/drho) R_wi^T dt (t' moves by R rho).

#include <memory>

#include "cairn/backend/least_squares.hpp"
#include "cairn/core/se3.hpp"
#include "cairn/core/types.hpp"
#include "cairn/gnss/gnss_factor.hpp"

namespace cairn::navigation {

class WheelVelocityFactor final : public backend::Factor {
 public:
  /// `sigma_mps`: forward, lateral, vertical standard deviations (> 0). `omega_imu_rad_s`: the
  /// IMU's angular rate at the state, bias removed. `T_imu_vehicle`: the vehicle frame in the IMU's.
  WheelVelocityFactor(double forward_speed_mps, const Vector3& sigma_mps, const Vector3& omega_imu_rad_s,
                      const core::SE3& T_imu_vehicle);
  int residual_size() const override { return 3; }
  /// values: pose (7), velocity (3); jacobians 3 x 6 and 3 x 3, row-major.
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override;
  /// The vehicle frame's velocity in itself at this state (forward, lateral, vertical), m/s.
  Vector3 vehicle_velocity(const core::SE3& T_world_imu, const Vector3& v_world_mps) const;

 private:
  Vector3 measured_;
  Vector3 inverse_sigma_;
  Vector3 omega_cross_t_imu_;  ///< omega_i x t_iv, m/s
  Matrix3 R_vehicle_imu_;
};

class ShiftedGnssFactor final : public backend::Factor {
 public:
  /// The fix's factor and the fix's time minus the state's, seconds.
  ShiftedGnssFactor(std::unique_ptr<gnss::GnssPositionFactor> fix, double dt_s);
  int residual_size() const override { return 3; }
  /// values: pose (7), velocity (3); jacobians 3 x 6 and 3 x 3, row-major.
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override;
  /// The state's pose moved to the fix's time.
  core::SE3 pose_at_fix(const core::SE3& T_world_imu, const Vector3& v_world_mps) const;
  const gnss::GnssPositionFactor& fix() const { return *fix_; }
  double dt_s() const { return dt_s_; }

 private:
  std::unique_ptr<gnss::GnssPositionFactor> fix_;
  double dt_s_;
};

}  // namespace cairn::navigation
