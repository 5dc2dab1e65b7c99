#pragma once
/// \file
/// Inertial-only initialisation from up-to-scale visual poses while moving, after Campos,
/// Montiel, Gomez Rodriguez & Tardos, "Inertial-only optimization for visual-inertial
/// initialization", ICRA 2020 ([C]), the initialisation of ORB-SLAM3 (T-RO 2021, Sec. V-B):
/// the visual poses of the first seconds of keyframes are taken as they are (up to a scale when
/// they come from one camera), and one MAP estimate finds what the IMU needs: gravity's direction,
/// the scale, every keyframe's velocity and the biases (one pair for the window, with a prior),
/// [C] eq. (5)-(8). Here on the least-squares engine:
///
///  * each keyframe's body pose is a variable held to its visual pose by a ScaledPoseFactor
///    (rotation as seen; position s p + R t_camera_body: the scale s multiplies the camera's
///    path, not the metric lever arm), stiff (pose_sigma_*), so the poses act as [C]'s fixed ones;
///  * an ImuFactor (imu_factors.hpp) between consecutive keyframes, all on the same bias
///    variable, with gravity's direction a 2-DoF variable (GravityDirectionImuFactor; |g| known),
///    and [C]'s bias prior (VectorPriorFactor); solved, then preintegrated again at the estimated
///    biases and solved again (ORB-SLAM3 re-preintegrates after its initialisation), at most
///    relinearisations times or until the biases move by less than 1e-6;
///  * the scale as log s (a Euclidean variable: s stays positive), held at 0 for stereo / RGB-D.
///
/// Start: biases zero, s = 1, velocities from finite differences of the positions, gravity from
/// the mean of the rotated velocity increments ([C] Sec. IV-A: -sum R_i dv_ij, normalised).
/// Frames: T_world_camera in the visual world; gravity is returned in that world.

#include <string>
#include <vector>

#include "cairn/backend/least_squares.hpp"
#include "cairn/core/se3.hpp"
#include "cairn/core/time.hpp"
#include "cairn/inertial/imu_factors.hpp"
#include "cairn/inertial/imu_types.hpp"
#include "cairn/inertial/preintegration_check.hpp"

namespace cairn::inertial {

/// r = (Log(Zr^T R) / sigma_rad, (p - (e^l p_cam + o)) / sigma_m) on a pose (se3_manifold(),
/// T_world_body) and a log-scale l (euclidean_manifold(1)): the body pose a visual pose implies,
/// Zr = R_world_camera R_camera_body, o = R_world_camera t_camera_body, p_cam the camera's
/// position up to scale. Jacobians: rotation Jr^-1(r_R) / sigma_rad; position R / sigma_m w.r.t.
/// the pose's rho; -e^l p_cam / sigma_m w.r.t. l.
class ScaledPoseFactor final : public backend::Factor {
 public:
  ScaledPoseFactor(const core::SE3& T_world_camera, const core::SE3& T_camera_body, double sigma_m, double sigma_rad);
  int residual_size() const override { return 6; }
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override;

 private:
  core::SO3 R_world_body_;
  Vector3 p_camera_;
  Vector3 offset_;
  double inv_sigma_m_, inv_sigma_rad_;
};

/// Gravity's direction as a rotation R_world_gravity (stored as a quaternion qx qy qz qw) with a
/// 2-DoF retraction R <- R Exp((d_x, d_y, 0)): the world's gravity is R (0, 0, -g), and a turn about
/// the gravity axis changes nothing ([C] Sec. IV-A; ORB-SLAM3's GDirection vertex).
class GravityDirectionManifold final : public backend::Manifold {
 public:
  int ambient_size() const override { return 4; }
  int tangent_size() const override { return 2; }
  void plus(const double* x, const double* delta, double* x_plus) const override;
  std::string_view name() const override { return "gravity direction"; }
};
const backend::Manifold& gravity_direction_manifold();

/// ImuFactor (imu_factors.hpp) with the world's gravity R_world_gravity (0, 0, -g) on a
/// gravity_direction_manifold() variable: values (pose_i, v_i, pose_j, v_j, bias_i, R_world_gravity).
class GravityDirectionImuFactor final : public backend::Factor {
 public:
  GravityDirectionImuFactor(const PreintegratedImu& preintegrated, double gravity_mps2);
  int residual_size() const override { return 9; }
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override;

 private:
  ImuFactor inner_;
  double gravity_mps2_;
};

struct InertialInitializationOptions {
  double gravity_mps2 = kStandardGravity;
  /// One camera: the visual poses' unit is arbitrary, the scale is estimated; else held at 1.
  bool estimate_scale = true;
  /// [C]'s bias prior (ORB-SLAM3 priorG 1e2, i.e. 0.1 rad/s); the accelerometer's is as weak
  /// (ORB-SLAM3 holds it near zero for monocular; here the data decide, measured in the tests).
  double gyro_bias_prior_sigma = 0.1;   ///< rad/s
  double accel_bias_prior_sigma = 0.1;  ///< m/s^2
  /// How far the optimisation may move a visual pose (the poses are [C]'s constants).
  double pose_sigma_m = 1e-3;
  double pose_sigma_rad = 1e-4;
  int max_iterations = 50;   ///< per solve
  int relinearisations = 3;  ///< solves, each preintegrating at the last one's biases
  /// Refused below these: the IMU cannot see gravity apart from the accelerometer bias, nor the
  /// scale, without motion ([C] Sec. V: initialisation needs excitation).
  double min_duration_s = 1.0;
  double min_path_length = 0.0;  ///< in the poses' unit (0: no check)
  bool is_valid(std::string* why) const;
};

struct InertialInitialization {
  bool ok = false;
  std::string why;                 ///< when not ok
  Vector3 gravity_world = Vector3::Zero();  ///< m/s^2, the visual world's frame
  double scale = 1.0;              ///< metres per unit of the visual poses
  ImuBias bias;
  std::vector<Vector3> v_world_mps;      ///< per keyframe, metric
  std::vector<core::SE3> T_world_body;   ///< per keyframe, metric (scaled), as optimised
  double initial_cost = 0.0, final_cost = 0.0;
  int iterations = 0;
};

/// The MAP estimate above for keyframes at `stamps` (>= 3, strictly increasing) with visual poses
/// T_world_camera (up to scale when options.estimate_scale), the camera's pose in the body (IMU)
/// frame as T_camera_body (metric), and the IMU samples (sorted, covering every interval).
/// ok false, with `why`, for too short or still input, samples missing, or an estimate that is
/// not finite or has a scale outside (1e-3, 1e3). Throws std::invalid_argument for sizes that
/// differ, stamps out of order or invalid options / noise.
InertialInitialization initialize_inertial(const std::vector<core::Timestamp>& stamps, const std::vector<core::SE3>& T_world_camera,
                                           const core::SE3& T_camera_body, const std::vector<ImuSample>& samples, const ImuNoise& noise,
                                           const InertialInitializationOptions& options = {});

/// The initialisation tried on windows of a recording with ground truth (`cairn imu --groundtruth`):
/// keyframes every keyframe_spacing_s from the ground truth's states (their poses as the visual
/// input, metric: scale held), a window of window_s every every_s; windows in which the body moves
/// less than min_path_m are skipped (nothing to initialise from). Errors against the ground truth:
/// gravity's direction against the world's -z (the ground truth's world must be gravity-aligned,
/// as EuRoC's state file is), the biases against the state's at the window's start.
struct MovingInitializationCheckOptions {
  double window_s = 2.0;
  double every_s = 10.0;
  double keyframe_spacing_s = 0.1;
  double min_path_m = 0.2;
  InertialInitializationOptions initialization;
  bool is_valid(std::string* why) const;
};

struct MovingInitializationWindow {
  double start_s = 0.0;  ///< since the first state
  bool ok = false;
  std::string why;       ///< when not ok
  double gravity_error_deg = 0.0;
  double gyro_bias_error_rad_s = 0.0;
  double accel_bias_error_mps2 = 0.0;
};

struct MovingInitializationCheck {
  std::vector<MovingInitializationWindow> windows;
  int windows_still = 0;  ///< skipped: the body moved less than min_path_m
  ErrorSpread gravity_deg, gyro_bias_rad_s, accel_bias_mps2;  ///< over the windows that initialised
};

/// Precondition: options.is_valid(), noise.is_valid(); samples and states sorted by stamp.
MovingInitializationCheck check_moving_initialization(const std::vector<ImuSample>& samples, const std::vector<GroundTruthState>& states,
                                                      const ImuNoise& noise, const MovingInitializationCheckOptions& options);

}  // namespace cairn::inertial
