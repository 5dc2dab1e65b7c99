#include "cairn/lidar3d/inertial_fusion.hpp"

#include <array>
#include <cmath>
#include <stdexcept>

#include "cairn/backend/least_squares.hpp"
#include "cairn/core/problems.hpp"
#include "cairn/core/timer.hpp"

using cairn::core::Clock;
using cairn::core::seconds_since;
#include "cairn/inertial/imu_factors.hpp"

namespace cairn::lidar3d {

bool InertialFusionOptions::is_valid(std::string* why) const {
  core::Problems problems;
  std::string nested;
  if (!noise.is_valid(&nested)) problems.add_all("noise: ", nested);
  nested.clear();
  if (!initialization.is_valid(&nested)) problems.add_all("initialization: ", nested);
  const auto positive = [&](double value, const char* name) {
    if (!(std::isfinite(value) && value > 0.0)) problems.add(std::string(name) + " must be finite and > 0");
  };
  positive(gravity_mps2, "gravity_mps2");
  positive(lidar_rotation_sigma_rad, "lidar_rotation_sigma_rad");
  positive(lidar_translation_sigma_m, "lidar_translation_sigma_m");
  positive(degenerate_translation_sigma_m, "degenerate_translation_sigma_m");
  positive(initial_velocity_sigma_still_mps, "initial_velocity_sigma_still_mps");
  positive(initial_velocity_sigma_moving_mps, "initial_velocity_sigma_moving_mps");
  positive(initial_gyro_bias_sigma_rad_s, "initial_gyro_bias_sigma_rad_s");
  positive(initial_accel_bias_sigma_mps2, "initial_accel_bias_sigma_mps2");
  positive(contradiction_chi2, "contradiction_chi2");
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
struct WindowState {
  double time_s = 0.0;
  std::array<double, 7> pose{};
  Vector3 velocity = Vector3::Zero();
  BiasValues bias = BiasValues::Zero();
  std::optional<PreintegratedImu> from_previous;
  std::optional<LidarMeasurement> lidar;

  NavState nav() const { return {backend::se3_from_values(pose.data()), velocity}; }
  void set(const NavState& s) {
    backend::se3_to_values(s.T_world_body, pose.data());
    velocity = s.v_world_mps;
  }
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

/// The oldest state's prior as one Gaussian over (pose, velocity, bias[, gravity]): the residual
/// S (Log(P^-1 T), v - v0, b - b0[, g - g0]), S^T S the inverse of the joint marginal covariance.
/// Keeping the blocks together keeps the correlations the window built up, above all between
/// the accelerometer bias and gravity (only their sum is observable on a straight drive).
class JointStatePriorFactor final : public backend::Factor {
 public:
  JointStatePriorFactor(const WindowState& mean, const Vector3* gravity_mean, const Eigen::MatrixXd& covariance)
      : pose_(backend::se3_from_values(mean.pose.data())),
        velocity_(mean.velocity),
        bias_(mean.bias),
        with_gravity_(gravity_mean != nullptr),
        gravity_(gravity_mean != nullptr ? *gravity_mean : Vector3::Zero()) {
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(covariance);
    const Eigen::VectorXd inverse_root = eigen.eigenvalues().cwiseMax(1e-18).cwiseSqrt().cwiseInverse();
    sqrt_information_ = inverse_root.asDiagonal() * eigen.eigenvectors().transpose();
  }
  int residual_size() const override { return with_gravity_ ? 18 : 15; }
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override {
    const int n = residual_size();
    Matrix6 Jr_inv;
    Eigen::VectorXd e(n);
    e.head<6>() = (pose_.inverse() * backend::se3_from_values(values[0])).log(Jr_inv);
    e.segment<3>(6) = Eigen::Map<const Vector3>(values[1]) - velocity_;
    e.segment<6>(9) = Eigen::Map<const BiasValues>(values[2]) - bias_;
    if (with_gravity_) e.tail<3>() = Eigen::Map<const Vector3>(values[3]) - gravity_;
    Eigen::Map<Eigen::VectorXd>(residual, n) = sqrt_information_ * e;
    if (jacobians == nullptr) return true;
    using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    const int sizes[4] = {6, 3, 6, 3};
    for (int v = 0, offset = 0; v < (with_gravity_ ? 4 : 3); offset += sizes[v], ++v) {
      if (jacobians[v] == nullptr) continue;
      Eigen::MatrixXd J = sqrt_information_.middleCols(offset, sizes[v]);
      if (v == 0) J = J * Jr_inv;
      Eigen::Map<RowMajor>(jacobians[v], n, sizes[v]) = J;
    }
    return true;
  }

 private:
  core::SE3 pose_;
  Vector3 velocity_;
  BiasValues bias_;
  bool with_gravity_;
  Vector3 gravity_;
  Eigen::MatrixXd sqrt_information_;
};

/// The joint covariance of `variables` at the problem's current values: the matching block of
/// (J^T W J)^-1 over every free variable, J whitened and robust-reweighted (a dense inverse; the
/// window has at most a few hundred unknowns). Constant variables get zero rows and columns.
Eigen::MatrixXd joint_covariance(const backend::LeastSquaresProblem& problem, const std::vector<int>& variables) {
  std::vector<int> offset(static_cast<std::size_t>(problem.num_variables()), -1);
  int size = 0;
  for (int v = 0; v < problem.num_variables(); ++v) {
    if (problem.is_constant(v)) continue;
    offset[static_cast<std::size_t>(v)] = size;
    size += problem.manifold(v).tangent_size();
  }
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(size, size);
  for (int f = 0; f < problem.num_factors(); ++f) {
    const backend::Factor& factor = problem.factor(f);
    const std::vector<int>& vars = problem.factor_variables(f);
    const int m = factor.residual_size();
    std::vector<const double*> values;
    std::vector<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> J;
    std::vector<double*> jacobians;
    for (int v : vars) {
      values.push_back(problem.values(v));
      J.emplace_back(m, problem.manifold(v).tangent_size());
    }
    for (auto& block : J) jacobians.push_back(block.data());
    Eigen::VectorXd r(m);
    if (!factor.evaluate(values.data(), r.data(), jacobians.data())) continue;
    const backend::FactorLoss& loss = problem.factor_loss(f);
    const double w = backend::evaluate_kernel(loss.kernel, loss.scale, r.squaredNorm()).weight;
    for (std::size_t a = 0; a < vars.size(); ++a) {
      const int oa = offset[static_cast<std::size_t>(vars[a])];
      if (oa < 0) continue;
      for (std::size_t b = 0; b < vars.size(); ++b) {
        const int ob = offset[static_cast<std::size_t>(vars[b])];
        if (ob < 0) continue;
        H.block(oa, ob, J[a].cols(), J[b].cols()) += w * J[a].transpose() * J[b];
      }
    }
  }
  int out_size = 0;
  for (int v : variables) out_size += problem.manifold(v).tangent_size();
  Eigen::MatrixXd selector = Eigen::MatrixXd::Zero(size, out_size);
  int col = 0;
  for (int v : variables) {
    const int n = problem.manifold(v).tangent_size();
    if (offset[static_cast<std::size_t>(v)] >= 0) selector.block(offset[static_cast<std::size_t>(v)], col, n, n).setIdentity();
    col += n;
  }
  const Eigen::MatrixXd solved = H.ldlt().solve(selector);
  return selector.transpose() * solved;
}

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
  /// Variable indices of the last solve, per window state (pose, velocity, bias), and gravity's.
  std::vector<std::array<int, 3>> ids;
  int gravity_id = -1;

  void initialize(const InertialFusionOptions& options, double time_s);
  NavState latest_nav(double& time_s, ImuBias& bias) const;
  std::optional<PreintegratedImu> preintegrate(const InertialFusionOptions& o, double from_s, double to_s,
                                               const ImuBias& bias) const;
  backend::LeastSquaresProblem build_problem(const InertialFusionOptions& options);
  void slide(const InertialFusionOptions& options, backend::LeastSquaresProblem& problem);
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

InertialScanState LidarInertialFusion::fuse(const OdometryScanResult& odometry, const core::SE3& T_odom_lidar) {
  Impl& m = *impl_;
  const auto start = Clock::now();
  InertialScanState out;
  out.time_s = odometry.registered_time_s;
  double t_k = 0.0;
  ImuBias bias_k;
  const NavState state_k = m.latest_nav(t_k, bias_k);
  std::optional<PreintegratedImu> pim = m.preintegrate(options_, t_k, out.time_s, bias_k);
  const Vector3 gravity = m.gravity;
  const core::SE3 T_lidar_imu = options_.T_imu_lidar.inverse();

  WindowState state;
  state.time_s = out.time_s;
  state.bias = inertial::to_values(bias_k);
  const bool first = m.window.empty() || !pim;
  if (first) {
    // The window (re)starts here: the registered pose (the prior's at the first scan), the IMU's
    // velocity when it covered the interval.
    state.set(NavState{T_odom_lidar * T_lidar_imu, pim ? pim->predict(state_k, bias_k, gravity).v_world_mps : Vector3::Zero()});
    if (m.window.empty()) m.first_time_s = out.time_s;
    m.window.clear();
    m.priors = OldestPriors{};
    m.priors.pose = state.nav().T_world_body;
    m.priors.pose_covariance = Matrix6::Identity() * 1e-8;
    m.priors.velocity = state.velocity;
    const double v_sigma = m.initialization.still && pim ? options_.initial_velocity_sigma_still_mps
                                                         : options_.initial_velocity_sigma_moving_mps;
    m.priors.velocity_covariance = Matrix3::Identity() * v_sigma * v_sigma;
    m.priors.bias = state.bias;
    Eigen::Matrix<double, 6, 1> bias_sigma;
    bias_sigma << Vector3::Constant(options_.initial_gyro_bias_sigma_rad_s), Vector3::Constant(options_.initial_accel_bias_sigma_mps2);
    m.priors.bias_covariance = bias_sigma.cwiseAbs2().asDiagonal();
    // Gravity's direction: from the still window to the accelerometer bias' level, otherwise loose
    // (the first registrations' accelerations tell it apart from the biases).
    m.priors.gravity = m.gravity;
    const double g_sigma = m.initialization.still ? options_.initial_accel_bias_sigma_mps2 : 0.25 * options_.gravity_mps2;
    m.priors.gravity_covariance = Matrix3::Identity() * g_sigma * g_sigma;
  } else {
    const NavState predicted = pim->predict(state_k, bias_k, gravity);
    state.set(predicted);
    state.from_previous = pim;
    const bool registered = odometry.health != Health::kLost && odometry.registration.correspondences > 0;
    if (registered) {
      const Matrix6 lidar_cov = lidar_covariance(options_, odometry, T_odom_lidar);
      state.lidar = LidarMeasurement{T_odom_lidar, lidar_cov};
      const core::SE3 T_pred_lidar = predicted.T_world_body * options_.T_imu_lidar;
      const Vector6 r = (T_odom_lidar.inverse() * T_pred_lidar).log();
      const Matrix6 total = lidar_cov + prediction_covariance(*pim, state_k, T_pred_lidar);
      out.imu_lidar_chi2 = r.dot(total.ldlt().solve(r));
      out.contradicts_imu = out.imu_lidar_chi2 > options_.contradiction_chi2;
      out.lidar_used = true;
      out.degenerate = odometry.registration.degenerate_directions > 0;
    }
  }
  m.window.push_back(std::move(state));
  backend::LeastSquaresProblem problem = m.build_problem(options_);
  backend::LeastSquaresOptions solve_options;
  solve_options.linear_solver = backend::LinearSolverType::kSparseNormalCholesky;
  solve_options.threads = 1;
  solve_options.max_iterations = 10;
  backend::solve(problem, solve_options);
  const WindowState& latest = m.window.back();
  out.state = latest.nav();
  out.bias = inertial::bias_from_values(latest.bias.data());
  out.gravity_world = m.gravity;
  out.T_world_lidar = out.state.T_world_body * options_.T_imu_lidar;
  if (static_cast<int>(m.window.size()) > options_.window_states) m.slide(options_, problem);
  out.solve_s = seconds_since(start);
  return out;
}

// The window's factor graph: priors on the oldest state, then per state its IMU and bias
// random-walk factors from the state before and its LiDAR factor (Huber, at the contradiction
// threshold's distance, so one wrong registration cannot drag the window).
backend::LeastSquaresProblem LidarInertialFusion::Impl::build_problem(const InertialFusionOptions& o) {
  backend::LeastSquaresProblem problem;
  ids.clear();
  for (WindowState& s : window) {
    ids.push_back({problem.add_variable(s.pose.data(), backend::se3_manifold()),
                   problem.add_variable(s.velocity.data(), backend::euclidean_manifold(3)),
                   problem.add_variable(s.bias.data(), backend::euclidean_manifold(6))});
  }
  gravity_id = problem.add_variable(gravity.data(), backend::euclidean_manifold(3));
  const bool joint_with_gravity = priors.joint_covariance && priors.joint_covariance->rows() == 18;
  gravity_held = gravity_held || window.back().time_s - first_time_s > o.gravity_estimation_s;
  if (gravity_held) {
    problem.set_constant(gravity_id);
  } else {
    problem.add_factor(std::make_unique<inertial::GravityMagnitudeFactor>(o.gravity_mps2, 1e-3), {gravity_id});
    if (!joint_with_gravity) {
      problem.add_factor(std::make_unique<inertial::VectorPriorFactor<3>>(priors.gravity, priors.gravity_covariance), {gravity_id});
    }
  }
  if (priors.joint_covariance && (joint_with_gravity || gravity_held)) {
    std::vector<int> joint_vars = {ids[0][0], ids[0][1], ids[0][2]};
    if (joint_with_gravity) joint_vars.push_back(gravity_id);
    Eigen::MatrixXd covariance = *priors.joint_covariance;
    if (joint_with_gravity && gravity_held) covariance = covariance.topLeftCorner(15, 15).eval();
    if (joint_with_gravity && gravity_held) joint_vars.pop_back();
    problem.add_factor(std::make_unique<JointStatePriorFactor>(priors.joint_mean, gravity_held ? nullptr : &priors.gravity,
                                                               covariance),
                       joint_vars);
  } else {
    problem.add_factor(std::make_unique<inertial::PosePriorFactor>(priors.pose, priors.pose_covariance), {ids[0][0]});
    problem.add_factor(std::make_unique<inertial::VectorPriorFactor<3>>(priors.velocity, priors.velocity_covariance), {ids[0][1]});
    problem.add_factor(std::make_unique<inertial::VectorPriorFactor<6>>(priors.bias, priors.bias_covariance), {ids[0][2]});
  }
  for (std::size_t k = 0; k < window.size(); ++k) {
    const WindowState& s = window[k];
    if (k > 0 && s.from_previous) {
      problem.add_factor(std::make_unique<inertial::ImuFactor>(inertial::ImuFactor::with_gravity_variable(*s.from_previous)),
                         {ids[k - 1][0], ids[k - 1][1], ids[k][0], ids[k][1], ids[k - 1][2], gravity_id});
      problem.add_factor(std::make_unique<inertial::BiasRandomWalkFactor>(o.noise, s.from_previous->delta_time_s()),
                         {ids[k - 1][2], ids[k][2]});
    }
    if (s.lidar) {
      problem.add_factor(std::make_unique<inertial::PosePriorFactor>(s.lidar->Z_world_lidar, s.lidar->covariance, o.T_imu_lidar),
                         {ids[k][0]}, backend::FactorLoss{backend::RobustKernel::kHuber, std::sqrt(o.contradiction_chi2)});
    }
  }
  return problem;
}

// Slides the window: the second state's joint marginal (with gravity's while it is estimated)
// becomes the prior, the oldest state leaves.
void LidarInertialFusion::Impl::slide(const InertialFusionOptions&, backend::LeastSquaresProblem& problem) {
  std::vector<int> joint_vars = {ids[1][0], ids[1][1], ids[1][2]};
  if (!gravity_held) joint_vars.push_back(gravity_id);
  const Eigen::MatrixXd covariance = joint_covariance(problem, joint_vars);
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
