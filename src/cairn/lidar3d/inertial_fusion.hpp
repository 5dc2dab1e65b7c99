#pragma once
/// \file
/// LiDAR-inertial fusion for the 3D pipeline, after LIO-SAM (Shan et al., "LIO-SAM: Tightly-coupled
/// Lidar Inertial Odometry via Smoothing and Mapping", IROS 2020, Sec. III-B/C and its
/// imuPreintegration.cpp): a factor graph over the scans' registration instants on cairn's
/// least-squares engine, with
///  * IMU factors and bias random-walk factors between consecutive states (inertial/imu_factors.hpp,
///    Forster et al., T-RO 2017),
///  * one LiDAR odometry factor per registered scan: the registered pose of the LiDAR, whose
///    covariance is small except along a degenerate direction the registration names (there the IMU
///    carries the motion: LIO-SAM switches to a loose noise model when its scan matching is
///    degenerate),
///  * priors on the oldest state of a sliding window of `window_states`; when the window slides, the
///    oldest state is marginalised and the new oldest state's joint marginal over (pose, velocity,
///    bias, and gravity while it is estimated) becomes one prior, correlations kept (LIO-SAM's reset
///    with `marginalCovariance` keeps only the per-variable blocks). Once gravity is held, that
///    prior is conditioned on the held gravity, not marginalised over it.
/// The fused state predicts the next sweep: the IMU is integrated from it over the sweep and gives
/// the odometry its prediction and every point's pose for deskewing (motion_prior.hpp).
///
/// Why a smoother on the engine and not FAST-LIO2's iterated error-state Kalman filter: the engine
/// and the IMU factor already exist and are tested, a window re-linearises the recent IMU factors
/// when a registration corrects the velocity (a filter cannot), and it costs well under a
/// millisecond per scan next to the registration's tens (docs/lidar3d.md, "LiDAR-inertial").
///
/// Gravity is a variable of the window during the first gravity_estimation_s (its direction; the
/// magnitude is held by a factor), so the tilt a start in motion leaves in the initial attitude is
/// corrected once the registrations show the accelerations, where turns make it observable (LIO-SAM
/// instead trusts a 9-axis IMU's orientation; VINS-Mono refines gravity on the 2-sphere).
///
/// Frames: `world` is the odometry's frame, gravity-aligned (z up) as well as the IMU's initialisation
/// could tell (the estimated gravity vector says how well);
/// `body` is the IMU's frame; `T_imu_lidar` places the LiDAR in it.

#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "cairn/core/health.hpp"
#include "cairn/inertial/preintegration.hpp"
#include "cairn/inertial/static_initialization.hpp"
#include "cairn/lidar3d/motion_prior.hpp"
#include "cairn/lidar3d/odometry.hpp"

namespace cairn::lidar3d {

struct InertialFusionOptions {
  inertial::ImuNoise noise;
  /// The LiDAR's pose in the IMU's frame.
  core::SE3 T_imu_lidar;
  /// Magnitude of gravity, m/s^2 (> 0).
  double gravity_mps2 = inertial::kStandardGravity;
  /// States in the sliding window (>= 2).
  int window_states = 10;
  /// The LiDAR odometry factor's standard deviations (> 0): rotation (rad) and translation (m);
  /// along a degenerate translation direction, degenerate_translation_sigma_m. The translation's is
  /// LIO-SAM's (imuPreintegration.cpp, correctionNoise: 0.1 m; 1 for a degenerate match). The
  /// rotation's is the registration's measured accuracy, not LIO-SAM's 0.05 rad: consecutive
  /// scan-to-map registrations differ from the truth by 0.165 deg RMS on real KITTI scans (docs/
  /// lidar3d.md, the dense front end's table) and 0.05-0.1 deg on the simulated tunnel and street,
  /// i.e. 0.002 rad per scan or less. At 0.05 rad the window could tilt the attitude by half a degree
  /// at no cost, and in the tunnel it did: gravity's share then drove the unobserved axis
  /// (docs/lidar3d.md, "LiDAR-inertial").
  double lidar_rotation_sigma_rad = 0.002;
  double lidar_translation_sigma_m = 0.1;
  double degenerate_translation_sigma_m = 10.0;
  /// Standard deviations of the first state's priors: the initial velocity when the IMU was still
  /// at the start (m/s) or moving (then the velocity comes from the first registrations), and the
  /// biases (rad/s, m/s^2).
  double initial_velocity_sigma_still_mps = 0.01;
  double initial_velocity_sigma_moving_mps = 10.0;
  double initial_gyro_bias_sigma_rad_s = 0.01;
  double initial_accel_bias_sigma_mps2 = 0.2;
  /// A registration whose pose differs from the IMU's prediction by more than this squared
  /// Mahalanobis distance (6 dof; 22.46 = chi-square 0.999) contradicts the IMU: `degraded`.
  double contradiction_chi2 = 22.46;
  /// Gravity's direction is a variable of the window for this long after the first scan (seconds,
  /// >= 0), then held: once the window has slid, separate marginal priors on gravity and the
  /// accelerometer bias would drop their strong correlation (on a straight drive only their sum
  /// is observable) and let the velocity drift. ORB-SLAM3 likewise refines gravity during its
  /// inertial initialisation only.
  double gravity_estimation_s = 10.0;
  /// Static initialisation over the IMU's first seconds (window, stillness limits).
  inertial::StaticInitializationOptions initialization;
  /// When the static window overlaps the scans, the LiDAR must agree that the sensor was still: a
  /// registered translation beyond this from the first scan within the window (m, > 0) overrules
  /// the IMU's stillness test (a constant acceleration reads like a tilt to an IMU alone: the
  /// block means agree and only |mean accel| - g, which a bias also explains, shows it).
  double still_lidar_motion_max_m = 0.05;
  bool is_valid(std::string* why) const;
};

/// How the IMU was initialised at the first scan.
struct InertialInitialization {
  bool still = false;     ///< static initialisation succeeded (gyro bias and tilt from a still window)
  std::string message;    ///< why it was not still, when !still
  /// The IMU's test passed but the LiDAR moved during the static window (the tilt is then wrong by
  /// the acceleration's share: gravity's direction is left to the window, as when moving).
  bool overruled_by_lidar = false;
  inertial::StaticInitialization statics;
};

/// The fused state at one scan's registration instant.
struct InertialScanState {
  double time_s = 0.0;
  inertial::NavState state;  ///< T_world_body, v_world_mps (the odometry's world frame)
  inertial::ImuBias bias;
  /// The world's gravity vector as estimated so far, m/s^2 (its magnitude is held at gravity_mps2).
  Vector3 gravity_world = Vector3::Zero();
  core::SE3 T_world_lidar;   ///< the fused LiDAR pose
  /// Squared Mahalanobis distance between the registered pose and the IMU's prediction (6 dof);
  /// -1 when the scan had no registration (the first, or a lost one).
  double imu_lidar_chi2 = -1.0;
  bool contradicts_imu = false;
  bool lidar_used = false;    ///< a LiDAR factor was added (not lost)
  bool degenerate = false;    ///< the registration had a degenerate direction, carried by the IMU
  double solve_s = 0.0;
};

class LidarInertialFusion {
 public:
  /// Throws std::invalid_argument if the options are invalid.
  explicit LidarInertialFusion(const InertialFusionOptions& options);
  ~LidarInertialFusion();
  LidarInertialFusion(const LidarInertialFusion&) = delete;
  LidarInertialFusion& operator=(const LidarInertialFusion&) = delete;

  /// IMU samples in time order (in the body frame, the scans' clock). Out-of-order samples are
  /// refused (std::invalid_argument).
  void add_imu(const inertial::ImuSample& sample);

  /// The LiDAR's poses over [from_s, to_s] (a sweep) predicted by the IMU from the latest state; at
  /// the first call, the IMU is initialised first. nullopt when the IMU does not cover the interval
  /// (the caller then runs without a prior).
  std::optional<MotionPrior> predict_sweep(double from_s, double to_s);

  /// Adds the state at `odometry.registered_time_s` with its LiDAR factor (none when the scan was
  /// lost), solves the window and returns the fused state. `T_odom_lidar` is the registered pose in
  /// the odometry's frame. Precondition: predict_sweep covered this instant.
  InertialScanState fuse(const OdometryScanResult& odometry, const core::SE3& T_odom_lidar);

  bool initialized() const;
  const InertialInitialization& initialization() const;
  const InertialFusionOptions& options() const { return options_; }

 private:
  struct Impl;
  InertialFusionOptions options_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cairn::lidar3d
