#pragma once
/// \file
/// A ground vehicle's navigation from an IMU, wheel odometry and GNSS (`GnssInertialOdometry`):
/// a fixed-lag smoother on the least-squares engine over states (pose, velocity, IMU biases) every
/// `state_period_s`, with
///  * IMU and bias random-walk factors between consecutive states (inertial/imu_factors.hpp,
///    Forster et al., T-RO 2017),
///  * one wheel factor per state: the wheels' forward speed (interpolated to the state's time) and
///    the non-holonomic constraint (zero lateral and vertical speed), navigation_factors.hpp,
///  * GNSS fixes as gnss::GnssPositionFactor with the Cauchy kernel, on the state nearest the fix
///    moved along its velocity to the fix's time (navigation_factors.hpp, ShiftedGnssFactor),
///  * priors on the oldest state of a sliding window of `window_states`; when it slides, the
///    factors touching the oldest state are linearised and its block eliminated, and the next
///    state's joint 15 x 15 marginal becomes its prior (the Schur complement, as
///    lidar3d/inertial_fusion.cpp does; docs/navigation.md, "Sliding window").
///
/// Frames: `imu` is the estimated body (the IMU's frame); `vehicle` is the wheel odometry's child
/// frame (x forward, z up; T_imu_vehicle places it); `world` is gravity-aligned (z up). Until yaw
/// is observable the world is the frame the IMU started in (yaw 0) and GNSS factors wait; once the
/// vehicle has driven far enough, gnss::align_world_to_enu fits the dead-reckoned antenna positions
/// to the first fixes (yaw and translation), every state, prior and stored estimate is moved into
/// the ENU frame at the first fix (gnss::LocalFrame::at_first_fix), the oldest prior is loosened by
/// the fit's uncertainty, and from then the world is that ENU frame and the fixes enter as factors.
///
/// Measurements may arrive interleaved from several streams; a state is solved once every stream
/// may be assumed to have delivered its time: when a measurement stamped at least
/// `latency_s` + state_period_s / 2 after it has arrived (or at finish()).

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/core/time.hpp"
#include "cairn/gnss/gnss_factor.hpp"
#include "cairn/gnss/gnss_fix.hpp"
#include "cairn/gnss/gnss_outliers.hpp"
#include "cairn/gnss/gnss_yaw.hpp"
#include "cairn/gnss/local_frame.hpp"
#include "cairn/inertial/imu_types.hpp"
#include "cairn/inertial/static_initialization.hpp"

namespace cairn::navigation {

/// One wheel-odometry reading: the vehicle's forward speed (nav_msgs/Odometry twist.linear.x in
/// its child frame) and, when known, its variance (twist_covariance[0]).
struct WheelSpeed {
  core::Timestamp stamp;
  double forward_speed_mps = 0.0;
  double variance_m2_s2 = 0.0;  ///< 0 = unknown (the option's default sigma is used)
};

/// The vertical variance of a fix whose altitude is not used (use_gnss_altitude false), m^2.
inline constexpr double kUnusedVerticalVariance = 1e8;

struct GnssInertialOdometryOptions {
  /// The IMU's noise densities and random walks (inertial::ImuNoise; defaults EuRoC's ADIS16448).
  inertial::ImuNoise noise;
  /// The vehicle frame (the wheel odometry's child frame) in the IMU frame.
  core::SE3 T_imu_vehicle;
  /// The GNSS factor: lever arm (the antenna in the IMU frame), default sigmas, floor, kernel
  /// (Cauchy, c = 2.7955). Its T_enu_world is not used: the estimator sets the world to ENU.
  gnss::GnssFactorOptions gnss;
  /// Whether the fixes' altitude is used. false: their vertical variance is replaced by
  /// kUnusedVerticalVariance (horizontal fixes only): a consumer receiver's altitude can wander by
  /// tens of metres on level ground (robot_localization's test1.bag: +7 to -22 m), and a ground
  /// vehicle's estimator that follows it tilts its attitude to descend and corrupts the biases.
  bool use_gnss_altitude = true;
  /// The per-fix gate of the report (chi-square(3) at 0.999) and the dropout gap (2 s).
  gnss::GnssOutlierOptions outliers;
  /// When yaw counts as observable (default: 10 m RMS spread of the path) and the trimmed fit.
  gnss::YawAlignmentOptions yaw;
  /// Magnitude of gravity, m/s^2, > 0.
  double gravity_mps2 = inertial::kStandardGravity;
  /// Time between states, seconds, in [0.01, 1]. 0.1 s (10 Hz): a wheel odometry's usual rate,
  /// and a GNSS fix is then at most 0.05 s from a state.
  double state_period_s = 0.1;
  /// States in the sliding window, >= 3. 10 states = 1 s at 10 Hz: 1-5 fixes of a 1-5 Hz receiver.
  int window_states = 10;
  /// Wheel speed sigma when a reading has no variance, and the floor on any reading's, m/s (> 0).
  /// 0.05 m/s: 5 % at 1 m/s, a skid-steer platform's slip on grass; the floor 0.01 m/s.
  double wheel_speed_sigma_mps = 0.05;
  double min_wheel_speed_sigma_mps = 0.01;
  /// Sigma of the non-holonomic constraint (lateral and vertical speed of the vehicle frame), m/s
  /// (> 0). 0.05 m/s leaves room for side slip in turns and suspension travel.
  double nonholonomic_sigma_mps = 0.05;
  /// A wheel reading is interpolated to a state's time only between readings at most this far apart,
  /// seconds (> 0); otherwise the state has no wheel factor.
  double max_wheel_gap_s = 0.5;
  /// How late a measurement may arrive after a later one of another stream, seconds (>= 0).
  double latency_s = 0.2;
  /// Sigmas of the first state's priors: velocity (m/s), gyro bias (rad/s), accelerometer bias
  /// (m/s^2), attitude roll/pitch (rad), all > 0. The pose's position and yaw are the world's
  /// gauge (tight); the velocity is loose (the wheels give it).
  double initial_velocity_sigma_mps = 1.0;
  double initial_gyro_bias_sigma_rad_s = 0.02;
  double initial_accel_bias_sigma_mps2 = 0.2;
  double initial_tilt_sigma_rad = 0.05;
  /// Static initialisation over the IMU's first seconds (else the tilt comes from the mean
  /// specific force and the gyro bias prior is zero).
  inertial::StaticInitializationOptions initialization;
  /// Levenberg-Marquardt iterations per solve, >= 1.
  int max_iterations = 10;
  bool is_valid(std::string* why) const;
};

/// One estimated state (its final estimate, when it left the window).
struct NavigationState {
  double time_s = 0.0;
  inertial::NavState state;  ///< T_world_imu, v_world_mps (world = ENU once aligned)
  /// The IMU's prediction of this state from the previous one's estimate when that was the newest
  /// (a filter's prediction: no measurement at or after this state's time), in the same world.
  inertial::NavState predicted;
  inertial::ImuBias bias;
  bool wheel_used = false;
  int gnss_fixes = 0;  ///< fixes whose factor sits on this state
};

/// One fix, judged against the final estimate of its state.
struct GnssFixResult {
  double time_s = 0.0;
  Vector3 p_enu_m = Vector3::Zero();     ///< the fix's antenna position
  Vector3 error_enu_m = Vector3::Zero(); ///< estimated antenna minus fix
  double squared_mahalanobis = 0.0;
  bool used = false;      ///< a factor was added (false: before the yaw alignment, or late)
  bool outlier = false;   ///< squared_mahalanobis above the gate: rejected
};

enum class NavigationStatus {
  kOk,
  kNoImu,           ///< no IMU sample: nothing estimated
  kNotAligned,      ///< GNSS never aligned (too little motion, or no fixes): world is the IMU's start frame
};

struct NavigationSummary {
  NavigationStatus status = NavigationStatus::kNoImu;
  std::string message;
  std::size_t states = 0;
  std::size_t imu_samples = 0;
  std::size_t wheel_readings = 0;
  std::size_t states_without_wheel = 0;
  std::size_t fixes_received = 0;
  std::size_t fixes_used = 0;
  std::size_t fixes_late = 0;         ///< arrived after their state was solved: dropped
  std::size_t outliers = 0;
  double gate_squared_mahalanobis = 0.0;
  std::vector<gnss::GnssDropout> dropouts;
  bool still_start = false;           ///< static initialisation succeeded
  gnss::YawAlignment alignment;       ///< the fit that started the GNSS factors
  double alignment_time_s = 0.0;
  std::optional<gnss::GeodeticPosition> enu_origin;  ///< the first fix
  double solve_s = 0.0;               ///< total time in the solves and marginals
  double max_step_s = 0.0;            ///< slowest state
  bool ok() const { return status == NavigationStatus::kOk; }
};

class GnssInertialOdometry {
 public:
  /// Throws std::invalid_argument when the options are not valid.
  explicit GnssInertialOdometry(const GnssInertialOdometryOptions& options);
  ~GnssInertialOdometry();
  GnssInertialOdometry(const GnssInertialOdometry&) = delete;
  GnssInertialOdometry& operator=(const GnssInertialOdometry&) = delete;

  /// Per-stream stamps must increase strictly (std::invalid_argument otherwise).
  void add_imu(const inertial::ImuSample& sample);
  void add_wheel_odometry(const WheelSpeed& reading);
  void add_gnss(const gnss::GnssFix& fix);
  /// Solves every state the IMU covers; the window's states become final.
  void finish();

  /// Final estimates so far (all of them after finish()).
  const std::vector<NavigationState>& states() const;
  const std::vector<GnssFixResult>& fix_results() const;
  NavigationSummary summary() const;
  const GnssInertialOdometryOptions& options() const { return options_; }

 private:
  struct Impl;
  GnssInertialOdometryOptions options_;
  std::unique_ptr<Impl> impl_;
};

/// Feeds the three streams in time order (at equal stamps IMU, then wheels, then GNSS) and finishes.
void run_in_time_order(GnssInertialOdometry& odometry, const std::vector<inertial::ImuSample>& imu,
                       const std::vector<WheelSpeed>& wheels, const std::vector<gnss::GnssFix>& fixes);

}  // namespace cairn::navigation
