#pragma once
/// \file
/// On-manifold IMU preintegration after Forster, Carlone, Dellaert and Scaramuzza, "On-Manifold
/// Preintegration for Real-Time Visual-Inertial Odometry", IEEE T-RO 33(1), 2017 (cited below as
/// [F] with its equation numbers). Between two states i and j the IMU samples are summarised, once,
/// into relative motion increments that do not depend on the states:
///
///   dR_ij = prod_k Exp((w_k - bg) dt)                                              [F] (33)
///   dv_ij = sum_k dR_ik (a_k - ba) dt
///   dp_ij = sum_k dv_ik dt + 1/2 dR_ik (a_k - ba) dt^2
///
/// together with their covariance Sigma_ij over (dphi, dv, dp) [F] (62)-(63) and their Jacobians
/// with respect to the biases [F] Appendix B, so that a new bias estimate corrects them to first
/// order without integrating again [F] (44). predict() turns them into state j from state i with
/// gravity [F] (35); imu_factors.hpp uses them as a factor on the least-squares engine.
///
/// Sample k holds from its stamp to the next one (zero-order hold, as [F] Sec. IV and GTSAM's
/// PreintegratedImuMeasurements::integrateMeasurement with the measurement's dt).

#include <string>
#include <vector>

#include "cairn/core/so3.hpp"
#include "cairn/core/types.hpp"
#include "cairn/inertial/imu_types.hpp"

namespace cairn::inertial {

using Matrix9 = Eigen::Matrix<double, 9, 9>;
using Vector9 = Eigen::Matrix<double, 9, 1>;

/// Preintegrated increments between two states. Build with the bias estimate at state i (the
/// linearisation point of the bias correction), then integrate() every sample between them.
class PreintegratedImu {
 public:
  /// Precondition: noise.is_valid().
  PreintegratedImu(const ImuNoise& noise, const ImuBias& bias_linearisation);

  /// Integrates one reading held for dt_s seconds (dt_s > 0, finite). Updates the increments,
  /// their covariance (white noise only: the bias random walk goes into the bias factor) and the
  /// bias Jacobians [F] Appendix A and B.
  void integrate(const Vector3& gyro_rad_s, const Vector3& accel_mps2, double dt_s);

  /// Back to nothing integrated, with a new bias linearisation point.
  void reset(const ImuBias& bias_linearisation);

  double delta_time_s() const { return dt_ij_s_; }
  const core::SO3& delta_R() const { return delta_R_; }
  const Vector3& delta_v() const { return delta_v_; }
  const Vector3& delta_p() const { return delta_p_; }
  /// Covariance of the increments' errors (dphi, dv, dp) [F] (62), at the linearisation bias.
  const Matrix9& covariance() const { return covariance_; }
  const ImuBias& bias_linearisation() const { return bias_bar_; }
  /// Adds an error the white noise does not model (hold_error_covariance below) to covariance().
  void add_covariance(const Matrix9& extra) { covariance_ += extra; }
  const ImuNoise& noise() const { return noise_; }

  const Matrix3& J_R_bg() const { return J_R_bg_; }
  const Matrix3& J_v_bg() const { return J_v_bg_; }
  const Matrix3& J_v_ba() const { return J_v_ba_; }
  const Matrix3& J_p_bg() const { return J_p_bg_; }
  const Matrix3& J_p_ba() const { return J_p_ba_; }

  /// The increments corrected to first order for `bias` [F] (44):
  ///   dR(b) = dR Exp(J_R_bg dbg), dv(b) = dv + J_v_bg dbg + J_v_ba dba, likewise dp.
  core::SO3 corrected_delta_R(const ImuBias& bias) const;
  Vector3 corrected_delta_v(const ImuBias& bias) const;
  Vector3 corrected_delta_p(const ImuBias& bias) const;

  /// State j from state i with the bias held at `bias` over the interval [F] (35) / (44):
  ///   R_j = R_i dR,  v_j = v_i + g dt + R_i dv,  p_j = p_i + v_i dt + 1/2 g dt^2 + R_i dp.
  NavState predict(const NavState& state_i, const ImuBias& bias, const Vector3& gravity_world) const;

 private:
  ImuNoise noise_;
  ImuBias bias_bar_;
  double dt_ij_s_ = 0.0;
  core::SO3 delta_R_;
  Vector3 delta_v_ = Vector3::Zero();
  Vector3 delta_p_ = Vector3::Zero();
  Matrix9 covariance_ = Matrix9::Zero();
  Matrix3 J_R_bg_ = Matrix3::Zero();
  Matrix3 J_v_bg_ = Matrix3::Zero();
  Matrix3 J_v_ba_ = Matrix3::Zero();
  Matrix3 J_p_bg_ = Matrix3::Zero();
  Matrix3 J_p_ba_ = Matrix3::Zero();
};

/// Integrates the samples over [from, to] into `preintegrated`, each sample held until the next
/// one (zero-order hold) and the first and last pieces cut at `from` and `to`. Returns false, leaving
/// `preintegrated` unchanged, when the samples do not cover the interval: no sample at or before
/// `from`, or none at or after `to`, or to < from (from == to integrates nothing and returns true).
/// Precondition: samples sorted by stamp.
bool integrate_interval(const std::vector<ImuSample>& samples, core::Timestamp from, core::Timestamp to,
                        PreintegratedImu& preintegrated);

/// The zero-order hold's own error over [from, to], as a covariance of (dphi, dv, dp) to add to the
/// white noise's. Holding sample k until k+1 misses, in each piece of length tau, about half the
/// change to the next sample times tau (1/2 |w_k+1 - w_k| tau^2 / dt_k for the rotation, likewise
/// the specific force for the velocity: the error the midpoint rule of VINS-Mono, Qin et al. T-RO
/// 2018 Sec. IV-B, removes at first order). The rotation's error also turns the specific force
/// (|a_k| sigma_phi tau into the velocity), the velocity's moves the position. The pieces' errors
/// add linearly (a steady angular acceleration makes them all of one sign), so the sigmas are
/// sums; the covariance is diagonal. Zero where the readings do not change (and when the samples
/// do not cover the interval). Measured in tests/inertial/test_preintegration.cpp: the hold's
/// error in a fast turn stays within these sigmas where the white noise's are far too small.
Matrix9 hold_error_covariance(const std::vector<ImuSample>& samples, core::Timestamp from, core::Timestamp to);

/// The world's gravity vector for a z-up world: (0, 0, -g).
inline Vector3 gravity_z_up(double g_mps2 = kStandardGravity) { return Vector3(0.0, 0.0, -g_mps2); }

}  // namespace cairn::inertial
