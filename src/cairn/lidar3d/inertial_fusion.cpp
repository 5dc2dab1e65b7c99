#include "cairn/lidar3d/inertial_fusion.hpp"

#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "cairn/backend/least_squares.hpp"
#include "cairn/core/problems.hpp"
#include "cairn/core/timer.hpp"

using cairn::core::Clock;
using cairn::core::seconds_since;
#include "cairn/inertial/imu_factors.hpp"
#include "cairn/inertial/window_prior.hpp"

namespace cairn::lidar3d {

bool InertialFusionOptions::is_valid(std::string* why) const {
  core::Problems problems;
  std::string nested;
  if (!noise.is_valid(&nested)) problems.add_all("noise: ", nested);
  nested.clear();
  if (!initialization.is_valid(&nested)) problems.add_all("initialization: ", nested);
  problems.require_positive(gravity_mps2, "gravity_mps2");
  problems.require_positive(lidar_rotation_sigma_rad, "lidar_rotation_sigma_rad");
  problems.require_positive(lidar_translation_sigma_m, "lidar_translation_sigma_m");
  problems.require_positive(degenerate_translation_sigma_m, "degenerate_translation_sigma_m");
  problems.require_positive(initial_velocity_sigma_still_mps, "initial_velocity_sigma_still_mps");
  problems.require_positive(initial_velocity_sigma_moving_mps, "initial_velocity_sigma_moving_mps");
  problems.require_positive(initial_gyro_bias_sigma_rad_s, "initial_gyro_bias_sigma_rad_s");
  problems.require_positive(initial_accel_bias_sigma_mps2, "initial_accel_bias_sigma_mps2");
  problems.require_positive(contradiction_chi2, "contradiction_chi2");
  problems.require_positive(still_lidar_motion_max_m, "still_lidar_motion_max_m");
  if (window_states < 2) problems.add("window_states must be >= 2");
  if (!(std::isfinite(gravity_estimation_s) && gravity_estimation_s >= 0.0)) {
    problems.add("gravity_estimation_s must be finite and >= 0");
  }
  return problems.report(why);
}

namespace {

using inertial::BiasValues;
using inertial::ImuBias;
using inertial::NavState;
using inertial::PreintegratedImu;

/// A LiDAR odometry factor's measurement: the registered LiDAR pose and its covariance (LiDAR frame).
struct LidarMeasurement {
  core::SE3 Z_world_lidar;
  Matrix6 covariance;
};

/// One state of the window, with what links it to the one before.
struct WindowState : inertial::StateValues {
  double time_s = 0.0;
  std::optional<PreintegratedImu> from_previous;
  std::optional<LidarMeasurement> lidar;
};

/// Priors on the oldest state: means and per-variable covariances (LIO-SAM's reset).
struct OldestPriors {
  core::SE3 pose;
  Matrix6 pose_covariance = Matrix6::Identity();
  Vector3 velocity = Vector3::Zero();
  Matrix3 velocity_covariance = Matrix3::Identity();
  BiasValues bias = BiasValues::Zero();
  Eigen::Matrix<double, 6, 6> bias_covariance = Eigen::Matrix<double, 6, 6>::Identity();
  Vector3 gravity = Vector3::Zero();
  Matrix3 gravity_covariance = Matrix3::Identity();
  /// After the window first slid: one joint prior instead of the per-variable ones above (whose
  /// means it shares), over (pose, velocity, bias[, gravity while it is estimated]).
  std::optional<Eigen::MatrixXd> joint_covariance;
  WindowState joint_mean;
};

core::Timestamp stamp_of(double time_s) { return core::Timestamp::from_seconds(time_s); }

}  // namespace

struct LidarInertialFusion::Impl {
  std::vector<inertial::ImuSample> imu;
  bool initialized = false;
  InertialInitialization initialization;
  /// The state the first sweep is predicted from (initialisation), before any scan was fused.
  double start_time_s = 0.0;
  NavState start_state;
  std::deque<WindowState> window;
  OldestPriors priors;
  /// The world's gravity vector, estimated with the window (its magnitude held by a factor) until
  /// gravity_estimation_s after the first scan (first_time_s), then held.
  Vector3 gravity = Vector3::Zero();
  double first_time_s = 0.0;
  bool gravity_held = false;
  /// The static window's end when it overlaps the scans (the IMU started with them), else -inf;
  /// and the first scan's registered LiDAR position, for the LiDAR's stillness check.
  double static_window_end_s = -std::numeric_limits<double>::infinity();
  Vector3 first_lidar_position = Vector3::Zero();
  /// Variable indices of the last solve, per window state (pose, velocity, bias), and gravity's.
  std::vector<std::array<int, 3>> ids;
  int gravity_id = -1;

  void initialize(const InertialFusionOptions& options, double time_s);
  NavState latest_nav(double& time_s, ImuBias& bias) const;
  std::optional<PreintegratedImu> preintegrate(const InertialFusionOptions& o, double from_s, double to_s,
                                               const ImuBias& bias) const;
  void restart_window(const InertialFusionOptions& options, const WindowState& state, bool imu_covered);
  void add_lidar_measurement(const InertialFusionOptions& options, const OdometryScanResult& odometry,
                             const core::SE3& T_odom_lidar, const PreintegratedImu& pim, const NavState& state_k,
                             const NavState& predicted, WindowState& state, InertialScanState& out) const;
  void check_stillness_with_lidar(const InertialFusionOptions& options, const WindowState& state);
  void solve_window(const InertialFusionOptions& options, InertialScanState& out);
  backend::LeastSquaresProblem build_problem(const InertialFusionOptions& options, std::size_t states);
  void slide(const InertialFusionOptions& options);
};

LidarInertialFusion::LidarInertialFusion(const InertialFusionOptions& options)
    : options_(options), impl_(std::make_unique<Impl>()) {
  std::string why;
  if (!options.is_valid(&why)) throw std::invalid_argument("invalid inertial fusion options: " + why);
}

LidarInertialFusion::~LidarInertialFusion() = default;

bool LidarInertialFusion::initialized() const { return impl_->initialized; }
const InertialInitialization& LidarInertialFusion::initialization() const { return impl_->initialization; }

void LidarInertialFusion::add_imu(const inertial::ImuSample& sample) {
  if (!impl_->imu.empty() && !(impl_->imu.back().stamp < sample.stamp)) {
    throw std::invalid_argument("LidarInertialFusion::add_imu: IMU samples must come in strictly increasing time");
  }
  impl_->imu.push_back(sample);
}

// Static initialisation over the IMU before the first sweep (Sec. "Static initialisation" of
// inertial/static_initialization.hpp); when the IMU was moving, the tilt still comes from the mean
// specific force and the velocity is left to the first registrations (a loose prior).
void LidarInertialFusion::Impl::initialize(const InertialFusionOptions& options, double time_s) {
  std::vector<inertial::ImuSample> before;
  const core::Timestamp end = stamp_of(time_s);
  const core::Timestamp begin = stamp_of(time_s - options.initialization.window_s);
  for (const auto& s : imu) {
    if (s.stamp >= begin && s.stamp <= end) before.push_back(s);
  }
  if (before.size() < 10) {  // the IMU starts with the scans: use its first window instead
    before.clear();
    for (const auto& s : imu) {
      if (s.stamp.seconds() - imu.front().stamp.seconds() <= options.initialization.window_s) before.push_back(s);
    }
    if (!imu.empty()) static_window_end_s = imu.front().stamp.seconds() + options.initialization.window_s;
  }
  initialization.statics = inertial::initialize_static(before, options.initialization);
  initialization.still = initialization.statics.ok;
  initialization.message = initialization.statics.message;
  core::SO3 R_world_body = initialization.statics.R_world_body;
  if (!initialization.still && initialization.statics.mean_accel_mps2.norm() > 0.0) {
    const Vector3 up = initialization.statics.mean_accel_mps2.normalized();
    R_world_body = core::SO3::from_rpy(std::atan2(up.y(), up.z()), std::atan2(-up.x(), std::hypot(up.y(), up.z())), 0.0);
    initialization.statics.gyro_bias_rad_s.setZero();
  }
  // The first state at the sweep's start, or at the IMU's first sample when it starts later.
  start_time_s = imu.empty() ? time_s : std::max(time_s, imu.front().stamp.seconds());
  start_state = NavState{core::SE3(R_world_body, Vector3::Zero()), Vector3::Zero()};
  gravity = inertial::gravity_z_up(options.gravity_mps2);
  initialized = true;
}

NavState LidarInertialFusion::Impl::latest_nav(double& time_s, ImuBias& bias) const {
  if (window.empty()) {
    time_s = start_time_s;
    bias = ImuBias{initialization.statics.gyro_bias_rad_s, Vector3::Zero()};
    return start_state;
  }
  time_s = window.back().time_s;
  bias = inertial::bias_from_values(window.back().bias.data());
  return window.back().nav();
}

std::optional<PreintegratedImu> LidarInertialFusion::Impl::preintegrate(const InertialFusionOptions& o, double from_s,
                                                                         double to_s, const ImuBias& bias) const {
  PreintegratedImu pim(o.noise, bias);
  if (!(from_s < to_s)) return pim;
  if (!inertial::integrate_interval(imu, stamp_of(from_s), stamp_of(to_s), pim)) return std::nullopt;
  return pim;
}

std::optional<MotionPrior> LidarInertialFusion::predict_sweep(double from_s, double to_s) {
  Impl& m = *impl_;
  if (!m.initialized) m.initialize(options_, from_s);
  double t_k = 0.0;
  ImuBias bias;
  const NavState state_k = m.latest_nav(t_k, bias);
  const Vector3 gravity = m.gravity;
  MotionPrior prior;
  if (from_s < t_k) {  // a sweep starting before the latest state: hold its pose before it
    prior.times_s.push_back(from_s);
    prior.T_world_sensor.push_back(state_k.T_world_body * options_.T_imu_lidar);
  }
  prior.times_s.push_back(t_k);
  prior.T_world_sensor.push_back(state_k.T_world_body * options_.T_imu_lidar);
  PreintegratedImu pim(options_.noise, bias);
  double t = t_k;
  // Every IMU sample instant after t_k up to to_s, then to_s itself.
  auto next = std::upper_bound(m.imu.begin(), m.imu.end(), stamp_of(t_k),
                               [](core::Timestamp a, const inertial::ImuSample& s) { return a < s.stamp; });
  while (t < to_s) {
    const double target = (next != m.imu.end() && next->stamp.seconds() < to_s) ? next->stamp.seconds() : to_s;
    if (target > t && !inertial::integrate_interval(m.imu, stamp_of(t), stamp_of(target), pim)) return std::nullopt;
    t = target;
    if (next != m.imu.end()) ++next;
    if (!(t > prior.times_s.back())) continue;
    prior.times_s.push_back(t);
    prior.T_world_sensor.push_back(pim.predict(state_k, bias, gravity).T_world_body * options_.T_imu_lidar);
  }
  return prior;
}

namespace {

/// The LiDAR factor's covariance in the LiDAR frame (rho, phi): isotropic, except a degenerate
/// translation direction (in the world frame) gets degenerate_translation_sigma_m.
Matrix6 lidar_covariance(const InertialFusionOptions& o, const OdometryScanResult& odometry, const core::SE3& T_world_lidar) {
  Matrix3 translation = Matrix3::Identity() * o.lidar_translation_sigma_m * o.lidar_translation_sigma_m;
  const RegistrationResult& reg = odometry.registration;
  if (reg.degenerate_directions >= 2) {
    translation = Matrix3::Identity() * o.degenerate_translation_sigma_m * o.degenerate_translation_sigma_m;
  } else if (reg.degenerate_directions == 1) {
    const Vector3 d_world = reg.weakest_direction.head<3>().normalized();
    const double extra = o.degenerate_translation_sigma_m * o.degenerate_translation_sigma_m -
                         o.lidar_translation_sigma_m * o.lidar_translation_sigma_m;
    translation += extra * d_world * d_world.transpose();
  }
  const Matrix3 R_lidar_world = T_world_lidar.so3().inverse().matrix();
  Matrix6 covariance = Matrix6::Zero();
  covariance.topLeftCorner<3, 3>() = R_lidar_world * translation * R_lidar_world.transpose();
  covariance.bottomRightCorner<3, 3>() = Matrix3::Identity() * o.lidar_rotation_sigma_rad * o.lidar_rotation_sigma_rad;
  return covariance;
}

/// The IMU prediction's covariance as a LiDAR-frame pose error (rho, phi), from the preintegrated
/// covariance (dphi in the body frame at j; dp in the body frame at i, rotated into the LiDAR's).
Matrix6 prediction_covariance(const PreintegratedImu& pim, const NavState& state_i, const core::SE3& T_world_lidar_j) {
  const Matrix3 A = T_world_lidar_j.so3().inverse().matrix() * state_i.T_world_body.so3().matrix();
  const inertial::Matrix9& S = pim.covariance();  // (dphi, dv, dp)
  Matrix6 covariance;
  covariance.topLeftCorner<3, 3>() = A * S.block<3, 3>(6, 6) * A.transpose();
  covariance.topRightCorner<3, 3>() = A * S.block<3, 3>(6, 0);
  covariance.bottomLeftCorner<3, 3>() = covariance.topRightCorner<3, 3>().transpose();
  covariance.bottomRightCorner<3, 3>() = S.block<3, 3>(0, 0);
  return covariance;
}

}  // namespace

// Restarts the window at `state` (the first scan, or after the IMU stopped covering the scans):
// tight priors on its pose, the velocity's by whether the IMU started still, the biases' and
// gravity's from the initialisation.
void LidarInertialFusion::Impl::restart_window(const InertialFusionOptions& o, const WindowState& state, bool imu_covered) {
  if (window.empty()) {
    first_time_s = state.time_s;
    first_lidar_position = (state.nav().T_world_body * o.T_imu_lidar).translation();
  }
  window.clear();
  priors = OldestPriors{};
  priors.pose = state.nav().T_world_body;
  priors.pose_covariance = Matrix6::Identity() * 1e-8;
  priors.velocity = state.velocity;
  const double v_sigma = initialization.still && imu_covered ? o.initial_velocity_sigma_still_mps
                                                             : o.initial_velocity_sigma_moving_mps;
  priors.velocity_covariance = Matrix3::Identity() * v_sigma * v_sigma;
  priors.bias = state.bias;
  Eigen::Matrix<double, 6, 1> bias_sigma;
  bias_sigma << Vector3::Constant(o.initial_gyro_bias_sigma_rad_s), Vector3::Constant(o.initial_accel_bias_sigma_mps2);
  priors.bias_covariance = bias_sigma.cwiseAbs2().asDiagonal();
  // Gravity's direction: from the still window to the accelerometer bias' level, otherwise loose
  // (the first registrations' accelerations tell it apart from the biases).
  priors.gravity = gravity;
  const double g_sigma = initialization.still ? o.initial_accel_bias_sigma_mps2 : 0.25 * o.gravity_mps2;
  priors.gravity_covariance = Matrix3::Identity() * g_sigma * g_sigma;
}

// The registered pose as the new state's LiDAR factor (none for a lost scan), and how far it lies
// from the IMU's prediction (the contradiction test).
void LidarInertialFusion::Impl::add_lidar_measurement(const InertialFusionOptions& o, const OdometryScanResult& odometry,
                                                      const core::SE3& T_odom_lidar, const PreintegratedImu& pim,
                                                      const NavState& state_k, const NavState& predicted, WindowState& state,
                                                      InertialScanState& out) const {
  const bool registered = odometry.health != Health::kLost && odometry.registration.correspondences > 0;
  if (!registered) return;
  const Matrix6 lidar_cov = lidar_covariance(o, odometry, T_odom_lidar);
  state.lidar = LidarMeasurement{T_odom_lidar, lidar_cov};
  const core::SE3 T_pred_lidar = predicted.T_world_body * o.T_imu_lidar;
  const Vector6 r = (T_odom_lidar.inverse() * T_pred_lidar).log();
  const Matrix6 total = lidar_cov + prediction_covariance(pim, state_k, T_pred_lidar);
  out.imu_lidar_chi2 = r.dot(total.ldlt().solve(r));
  out.contradicts_imu = out.imu_lidar_chi2 > o.contradiction_chi2;
  out.lidar_used = true;
  out.degenerate = odometry.registration.degenerate_directions > 0;
}

// The LiDAR's view of the static window: a scan registered inside it, farther than
// still_lidar_motion_max_m from the first, means the sensor moved while the IMU looked still. The
// stillness is withdrawn and the oldest state's velocity and gravity priors loosened to the moving
// start's (restart_window), while they are still per-variable (before the window first slides).
void LidarInertialFusion::Impl::check_stillness_with_lidar(const InertialFusionOptions& o, const WindowState& state) {
  if (!initialization.still || !state.lidar || state.time_s > static_window_end_s || priors.joint_covariance) return;
  const double moved_m = (state.lidar->Z_world_lidar.translation() - first_lidar_position).norm();
  if (!(moved_m > o.still_lidar_motion_max_m)) return;
  initialization.still = false;
  initialization.overruled_by_lidar = true;
  char message[200];
  std::snprintf(message, sizeof message,
                "the IMU looked still over its first %.2f s but the LiDAR moved %.3f m by %.2f s: a constant "
                "acceleration, not gravity; the tilt is left to the window",
                o.initialization.window_s, moved_m, state.time_s - first_time_s);
  initialization.message = message;
  priors.velocity_covariance = Matrix3::Identity() * o.initial_velocity_sigma_moving_mps * o.initial_velocity_sigma_moving_mps;
  const double g_sigma = 0.25 * o.gravity_mps2;
  priors.gravity_covariance = Matrix3::Identity() * g_sigma * g_sigma;
}

// Solves the window (a few LM iterations from the prediction) and returns the latest state.
void LidarInertialFusion::Impl::solve_window(const InertialFusionOptions& o, InertialScanState& out) {
  gravity_held = gravity_held || window.back().time_s - first_time_s > o.gravity_estimation_s;
  backend::LeastSquaresProblem problem = build_problem(o, window.size());
  backend::LeastSquaresOptions solve_options;
  solve_options.linear_solver = backend::LinearSolverType::kSparseNormalCholesky;
  solve_options.threads = 1;
  solve_options.max_iterations = 10;
  backend::solve(problem, solve_options);
  const WindowState& latest = window.back();
  out.state = latest.nav();
  out.bias = inertial::bias_from_values(latest.bias.data());
  out.gravity_world = gravity;
  out.T_world_lidar = out.state.T_world_body * o.T_imu_lidar;
}

// Per scan: preintegrate to the registration instant, predict, add the state with its LiDAR
// factor (or restart the window), solve, slide.
InertialScanState LidarInertialFusion::fuse(const OdometryScanResult& odometry, const core::SE3& T_odom_lidar) {
  Impl& m = *impl_;
  const auto start = Clock::now();
  InertialScanState out;
  out.time_s = odometry.registered_time_s;
  double t_k = 0.0;
  ImuBias bias_k;
  const NavState state_k = m.latest_nav(t_k, bias_k);
  const std::optional<PreintegratedImu> pim = m.preintegrate(options_, t_k, out.time_s, bias_k);
  WindowState state;
  state.time_s = out.time_s;
  state.bias = inertial::to_values(bias_k);
  if (m.window.empty() || !pim) {
    // The registered pose (the prior's at the first scan), the IMU's velocity when it covered the interval.
    const Vector3 v = pim ? pim->predict(state_k, bias_k, m.gravity).v_world_mps : Vector3::Zero();
    state.set(NavState{T_odom_lidar * options_.T_imu_lidar.inverse(), v});
    m.restart_window(options_, state, pim.has_value());
  } else {
    const NavState predicted = pim->predict(state_k, bias_k, m.gravity);
    state.set(predicted);
    state.from_previous = pim;
    m.add_lidar_measurement(options_, odometry, T_odom_lidar, *pim, state_k, predicted, state, out);
    m.check_stillness_with_lidar(options_, state);
  }
  m.window.push_back(std::move(state));
  m.solve_window(options_, out);
  if (static_cast<int>(m.window.size()) > options_.window_states) m.slide(options_);
  out.solve_s = seconds_since(start);
  return out;
}

// The window's factor graph: priors on the oldest state, then per state its IMU and bias
// random-walk factors from the state before and its LiDAR factor (Huber, at the contradiction
// threshold's distance, so one wrong registration cannot drag the window).
//
// For marginalisation (`states` = 2) it holds only what touches the oldest state: its priors, its
// LiDAR factor and the IMU and bias factors to the next state, not the factors that stay in the
// window (the next state's LiDAR factor, gravity's magnitude), which would otherwise be counted
// again by the prior they leave behind.
backend::LeastSquaresProblem LidarInertialFusion::Impl::build_problem(const InertialFusionOptions& o, std::size_t states) {
  const bool marginalising = states < window.size();
  backend::LeastSquaresProblem problem;
  ids.clear();
  for (std::size_t k = 0; k < states; ++k) {
    WindowState& s = window[k];
    ids.push_back({problem.add_variable(s.pose.data(), backend::se3_manifold()),
                   problem.add_variable(s.velocity.data(), backend::euclidean_manifold(3)),
                   problem.add_variable(s.bias.data(), backend::euclidean_manifold(6))});
  }
  gravity_id = problem.add_variable(gravity.data(), backend::euclidean_manifold(3));
  const bool joint_with_gravity = priors.joint_covariance && priors.joint_covariance->rows() == 18;
  if (gravity_held) {
    problem.set_constant(gravity_id);
  } else {
    if (!marginalising) problem.add_factor(std::make_unique<inertial::GravityMagnitudeFactor>(o.gravity_mps2, 1e-3), {gravity_id});
    if (!joint_with_gravity) {
      problem.add_factor(std::make_unique<inertial::VectorPriorFactor<3>>(priors.gravity, priors.gravity_covariance), {gravity_id});
    }
  }
  if (priors.joint_covariance && (joint_with_gravity || gravity_held)) {
    // A joint prior that still holds gravity keeps it after gravity is held: with gravity constant
    // the factor is the state's prior conditioned on the held value. Its marginal (dropping
    // gravity's rows) would not be: on a straight drive only the accelerometer bias' sum with
    // gravity's tilt is observed, so the bias' marginal is loose by the tilt's uncertainty, and a
    // few misread registrations then move the bias far beyond its random walk (the tunnel's
    // portal, docs/lidar3d.md "LiDAR-inertial").
    std::vector<int> joint_vars = {ids[0][0], ids[0][1], ids[0][2]};
    if (joint_with_gravity) joint_vars.push_back(gravity_id);
    const WindowState& mean = priors.joint_mean;
    problem.add_factor(std::make_unique<inertial::StatePriorFactor>(backend::se3_from_values(mean.pose.data()), mean.velocity,
                                                                    mean.bias, joint_with_gravity ? &priors.gravity : nullptr,
                                                                    *priors.joint_covariance),
                       joint_vars);
  } else {
    problem.add_factor(std::make_unique<inertial::PosePriorFactor>(priors.pose, priors.pose_covariance), {ids[0][0]});
    problem.add_factor(std::make_unique<inertial::VectorPriorFactor<3>>(priors.velocity, priors.velocity_covariance), {ids[0][1]});
    problem.add_factor(std::make_unique<inertial::VectorPriorFactor<6>>(priors.bias, priors.bias_covariance), {ids[0][2]});
  }
  for (std::size_t k = 0; k < states; ++k) {
    const WindowState& s = window[k];
    if (k > 0 && s.from_previous) {
      problem.add_factor(std::make_unique<inertial::ImuFactor>(inertial::ImuFactor::with_gravity_variable(*s.from_previous)),
                         {ids[k - 1][0], ids[k - 1][1], ids[k][0], ids[k][1], ids[k - 1][2], gravity_id});
      problem.add_factor(std::make_unique<inertial::BiasRandomWalkFactor>(o.noise, s.from_previous->delta_time_s()),
                         {ids[k - 1][2], ids[k][2]});
    }
    if (s.lidar && !(marginalising && k > 0)) {
      problem.add_factor(std::make_unique<inertial::PosePriorFactor>(s.lidar->Z_world_lidar, s.lidar->covariance, o.T_imu_lidar),
                         {ids[k][0]}, backend::FactorLoss{backend::RobustKernel::kHuber, std::sqrt(o.contradiction_chi2)});
    }
  }
  return problem;
}

// Slides the window: the oldest state is marginalised (the factors touching it, linearised at the
// solution, its block eliminated: Sibley, Matthies & Sukhatme, "Sliding window filter with
// application to planetary landing", JFR 27(5), 2010, Sec. 3), and the next state's joint marginal
// (with gravity's while it is estimated) becomes the prior; the oldest state leaves.
void LidarInertialFusion::Impl::slide(const InertialFusionOptions& o) {
  const backend::LeastSquaresProblem problem = build_problem(o, 2);
  std::vector<int> joint_vars = {ids[1][0], ids[1][1], ids[1][2]};
  if (!gravity_held) joint_vars.push_back(gravity_id);
  const Eigen::MatrixXd covariance = inertial::joint_marginal_covariance(problem, joint_vars);
  const WindowState& next = window[1];
  priors.pose = next.nav().T_world_body;
  priors.velocity = next.velocity;
  priors.bias = next.bias;
  priors.gravity = gravity;
  if (covariance.allFinite()) {
    priors.joint_covariance = covariance;
    priors.joint_mean = next;
  }
  window.pop_front();
  window.front().from_previous.reset();
}

}  // namespace cairn::lidar3d
