// Inertial-only initialisation (Campos et al., ICRA 2020): see inertial_initialization.hpp.

#include "cairn/inertial/inertial_initialization.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "cairn/core/problems.hpp"
#include "cairn/inertial/imu_factors.hpp"
#include "cairn/inertial/preintegration.hpp"

namespace cairn::inertial {

ScaledPoseFactor::ScaledPoseFactor(const core::SE3& T_world_camera, const core::SE3& T_camera_body, double sigma_m, double sigma_rad)
    : R_world_body_(T_world_camera.so3() * T_camera_body.so3()),
      p_camera_(T_world_camera.translation()),
      offset_(T_world_camera.so3() * T_camera_body.translation()),
      inv_sigma_m_(1.0 / sigma_m),
      inv_sigma_rad_(1.0 / sigma_rad) {}

bool ScaledPoseFactor::evaluate(const double* const* values, double* residual, double* const* jacobians) const {
  const core::SE3 T = backend::se3_from_values(values[0]);
  const double s = std::exp(values[1][0]);
  const Vector3 r_R = (R_world_body_.inverse() * T.so3()).log();
  const Vector3 r_p = T.translation() - (s * p_camera_ + offset_);
  Eigen::Map<Eigen::Matrix<double, 6, 1>> r(residual);
  r.head<3>() = inv_sigma_rad_ * r_R;
  r.tail<3>() = inv_sigma_m_ * r_p;
  if (jacobians == nullptr) return true;
  if (jacobians[0] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, 6, 6, Eigen::RowMajor>> J(jacobians[0]);
    J.setZero();
    // Pose tangent (rho, phi): R <- R Exp(phi) moves r_R by Jr^-1(r_R) phi; p <- p + R rho.
    J.block<3, 3>(0, 3) = inv_sigma_rad_ * core::SO3::right_jacobian_inverse(r_R);
    J.block<3, 3>(3, 0) = inv_sigma_m_ * T.rotation_matrix();
  }
  if (jacobians[1] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, 6, 1>> J(jacobians[1]);
    J.head<3>().setZero();
    J.tail<3>() = -inv_sigma_m_ * s * p_camera_;
  }
  return true;
}

const backend::Manifold& gravity_direction_manifold() {
  static const GravityDirectionManifold manifold;
  return manifold;
}

void GravityDirectionManifold::plus(const double* x, const double* delta, double* x_plus) const {
  const Eigen::Quaterniond q(x[3], x[0], x[1], x[2]);
  const Eigen::Quaterniond r = (core::SO3(q) * core::SO3::exp(Vector3(delta[0], delta[1], 0.0))).unit_quaternion();
  x_plus[0] = r.x();
  x_plus[1] = r.y();
  x_plus[2] = r.z();
  x_plus[3] = r.w();
}

GravityDirectionImuFactor::GravityDirectionImuFactor(const PreintegratedImu& preintegrated, double gravity_mps2)
    : inner_(ImuFactor::with_gravity_variable(preintegrated)), gravity_mps2_(gravity_mps2) {}

bool GravityDirectionImuFactor::evaluate(const double* const* values, double* residual, double* const* jacobians) const {
  const core::SO3 R_world_gravity(Eigen::Quaterniond(values[5][3], values[5][0], values[5][1], values[5][2]));
  const Vector3 g0(0.0, 0.0, -gravity_mps2_);
  const Vector3 g = R_world_gravity * g0;
  const double* inner_values[6] = {values[0], values[1], values[2], values[3], values[4], g.data()};
  if (jacobians == nullptr || jacobians[5] == nullptr) {
    double* inner_jacobians[6] = {};
    if (jacobians != nullptr) std::copy(jacobians, jacobians + 5, inner_jacobians);
    return inner_.evaluate(inner_values, residual, jacobians != nullptr ? inner_jacobians : nullptr);
  }
  Eigen::Matrix<double, 9, 3, Eigen::RowMajor> J_g;
  double* inner_jacobians[6] = {jacobians[0], jacobians[1], jacobians[2], jacobians[3], jacobians[4], J_g.data()};
  if (!inner_.evaluate(inner_values, residual, inner_jacobians)) return false;
  // g = R Exp(delta) g0: dg/d(delta) = -R [g0]x, of which the first two columns (the third turns
  // about g0 itself).
  const Matrix3 dg = -(R_world_gravity.matrix() * core::SO3::hat(g0));
  Eigen::Map<Eigen::Matrix<double, 9, 2, Eigen::RowMajor>>{jacobians[5]} = J_g * dg.leftCols<2>();
  return true;
}

bool InertialInitializationOptions::is_valid(std::string* why) const {
  core::Problems problems;
  if (!(gravity_mps2 > 0.0) || !std::isfinite(gravity_mps2)) problems.add("gravity_mps2 must be > 0");
  if (relinearisations < 1) problems.add("relinearisations must be >= 1");
  if (!(gyro_bias_prior_sigma > 0.0) || !(accel_bias_prior_sigma > 0.0)) problems.add("the bias prior sigmas must be > 0");
  if (!(pose_sigma_m > 0.0) || !(pose_sigma_rad > 0.0)) problems.add("the pose sigmas must be > 0");
  if (max_iterations < 1) problems.add("max_iterations must be >= 1");
  if (!(min_duration_s >= 0.0) || !(min_path_length >= 0.0)) problems.add("min_duration_s and min_path_length must be >= 0");
  return problems.report(why);
}

namespace {

// What the engine's variables are stored in.
struct InitializationValues {
  std::vector<std::array<double, 7>> poses;
  std::vector<Vector3> velocities;
  Eigen::Matrix<double, 6, 1> bias = Eigen::Matrix<double, 6, 1>::Zero();
  std::array<double, 4> R_world_gravity{0.0, 0.0, 0.0, 1.0};  // qx qy qz qw
  double log_scale = 0.0;
  Vector3 gravity(double g) const {
    return core::SO3(Eigen::Quaterniond(R_world_gravity[3], R_world_gravity[0], R_world_gravity[1], R_world_gravity[2])) *
           Vector3(0.0, 0.0, -g);
  }
};

// The starting point: body poses at scale 1, velocities by central differences, gravity along
// -sum R_i dv_ij ([C] Sec. IV-A: with velocities unknown, the accelerometer's mean direction).
void initial_values(const std::vector<core::Timestamp>& stamps, const std::vector<core::SE3>& T_world_body,
                    const std::vector<PreintegratedImu>& pieces, InitializationValues& x) {
  const std::size_t n = stamps.size();
  x.poses.resize(n);
  x.velocities.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    backend::se3_to_values(T_world_body[k], x.poses[k].data());
    const std::size_t a = k == 0 ? 0 : k - 1, b = k + 1 == n ? k : k + 1;
    const double dt = stamps[b].seconds() - stamps[a].seconds();
    x.velocities[k] = (T_world_body[b].translation() - T_world_body[a].translation()) / dt;
  }
  Vector3 direction = Vector3::Zero();
  for (std::size_t k = 0; k + 1 < n; ++k) direction -= T_world_body[k].so3() * pieces[k].delta_v();
  if (direction.norm() > 0.0) {
    const Eigen::Quaterniond q = Eigen::Quaterniond::FromTwoVectors(Vector3(0.0, 0.0, -1.0), direction.normalized());
    x.R_world_gravity = {q.x(), q.y(), q.z(), q.w()};
  }
}

// The IMU between consecutive keyframes, preintegrated at `bias`; "" or why not.
std::string preintegrate(const std::vector<core::Timestamp>& stamps, const std::vector<ImuSample>& samples, const ImuNoise& noise,
                         const ImuBias& bias, std::vector<PreintegratedImu>& pieces) {
  pieces.clear();
  for (std::size_t k = 0; k + 1 < stamps.size(); ++k) {
    pieces.emplace_back(noise, bias);
    if (!integrate_interval(samples, stamps[k], stamps[k + 1], pieces.back())) {
      return "the IMU samples do not cover the interval between keyframes " + std::to_string(k) + " and " + std::to_string(k + 1);
    }
  }
  return "";
}

// One MAP solve at the pieces' linearisation (the header's problem), from and into x.
backend::LeastSquaresSummary solve_once(const std::vector<core::SE3>& T_world_camera, const core::SE3& T_camera_body,
                                        const std::vector<PreintegratedImu>& pieces, const InertialInitializationOptions& options,
                                        InitializationValues& x) {
  const std::size_t n = T_world_camera.size();
  backend::LeastSquaresProblem problem;
  const int scale_id = problem.add_variable(&x.log_scale, backend::euclidean_manifold(1));
  if (!options.estimate_scale) problem.set_constant(scale_id);
  const int bias_id = problem.add_variable(x.bias.data(), backend::euclidean_manifold(6));
  const int gravity_id = problem.add_variable(x.R_world_gravity.data(), gravity_direction_manifold());
  std::vector<int> pose_id(n), velocity_id(n);
  for (std::size_t k = 0; k < n; ++k) {
    pose_id[k] = problem.add_variable(x.poses[k].data(), backend::se3_manifold());
    velocity_id[k] = problem.add_variable(x.velocities[k].data(), backend::euclidean_manifold(3));
    problem.add_factor(std::make_unique<ScaledPoseFactor>(T_world_camera[k], T_camera_body, options.pose_sigma_m, options.pose_sigma_rad),
                       {pose_id[k], scale_id});
  }
  for (std::size_t k = 0; k + 1 < n; ++k) {
    problem.add_factor(std::make_unique<GravityDirectionImuFactor>(pieces[k], options.gravity_mps2),
                       {pose_id[k], velocity_id[k], pose_id[k + 1], velocity_id[k + 1], bias_id, gravity_id});
  }
  Eigen::Matrix<double, 6, 1> sigma;
  sigma << Vector3::Constant(options.gyro_bias_prior_sigma), Vector3::Constant(options.accel_bias_prior_sigma);
  const Eigen::Matrix<double, 6, 6> prior_covariance = sigma.cwiseAbs2().asDiagonal();
  problem.add_factor(std::make_unique<VectorPriorFactor<6>>(Eigen::Matrix<double, 6, 1>::Zero(), prior_covariance), {bias_id});
  backend::LeastSquaresOptions solve_options;
  solve_options.linear_solver = backend::LinearSolverType::kSparseNormalCholesky;
  solve_options.threads = 1;
  solve_options.max_iterations = options.max_iterations;
  return backend::solve(problem, solve_options);
}

double path_length(const std::vector<core::SE3>& poses) {
  double length = 0.0;
  for (std::size_t k = 1; k < poses.size(); ++k) length += (poses[k].translation() - poses[k - 1].translation()).norm();
  return length;
}

}  // namespace

InertialInitialization initialize_inertial(const std::vector<core::Timestamp>& stamps, const std::vector<core::SE3>& T_world_camera,
                                           const core::SE3& T_camera_body, const std::vector<ImuSample>& samples, const ImuNoise& noise,
                                           const InertialInitializationOptions& options) {
  if (std::string p; !options.is_valid(&p)) throw std::invalid_argument("inertial initialisation options: " + p);
  if (std::string p; !noise.is_valid(&p)) throw std::invalid_argument("IMU noise: " + p);
  if (stamps.size() != T_world_camera.size()) throw std::invalid_argument("initialize_inertial: as many stamps as poses needed");
  for (std::size_t k = 1; k < stamps.size(); ++k) {
    if (!(stamps[k] > stamps[k - 1])) throw std::invalid_argument("initialize_inertial: stamps must be strictly increasing");
  }
  InertialInitialization out;
  const std::size_t n = stamps.size();
  if (n < 3) {
    out.why = "needs at least 3 keyframes, got " + std::to_string(n);
    return out;
  }
  const double duration = stamps.back().seconds() - stamps.front().seconds();
  if (duration < options.min_duration_s) {
    out.why = "the keyframes span " + std::to_string(duration) + " s, less than min_duration_s";
    return out;
  }
  if (options.min_path_length > 0.0 && path_length(T_world_camera) < options.min_path_length) {
    out.why = "the camera moved less than min_path_length: gravity and the accelerometer bias cannot be told apart";
    return out;
  }
  std::vector<PreintegratedImu> pieces;
  if (std::string why = preintegrate(stamps, samples, noise, ImuBias{}, pieces); !why.empty()) {
    out.why = std::move(why);
    return out;
  }
  std::vector<core::SE3> T_world_body(n);
  for (std::size_t k = 0; k < n; ++k) T_world_body[k] = T_world_camera[k] * T_camera_body;
  InitializationValues x;
  initial_values(stamps, T_world_body, pieces, x);
  for (int round = 0; round < options.relinearisations; ++round) {
    const Eigen::Matrix<double, 6, 1> bias_before = x.bias;
    if (round > 0) preintegrate(stamps, samples, noise, bias_from_values(x.bias.data()), pieces);
    const backend::LeastSquaresSummary summary = solve_once(T_world_camera, T_camera_body, pieces, options, x);
    if (round == 0) out.initial_cost = summary.initial_cost;
    out.final_cost = summary.final_cost;
    out.iterations += summary.iterations;
    if (round > 0 && (x.bias - bias_before).cwiseAbs().maxCoeff() < 1e-6) break;
  }
  out.scale = std::exp(x.log_scale);
  out.gravity_world = x.gravity(options.gravity_mps2);
  out.bias = bias_from_values(x.bias.data());
  for (std::size_t k = 0; k < n; ++k) {
    out.T_world_body.push_back(backend::se3_from_values(x.poses[k].data()));
    out.v_world_mps.push_back(x.velocities[k]);
  }
  const bool finite = out.gravity_world.allFinite() && x.bias.allFinite() && std::isfinite(x.log_scale);
  if (!finite) {
    out.why = "the estimate is not finite";
  } else if (!(out.scale > 1e-3 && out.scale < 1e3)) {
    out.why = "the scale " + std::to_string(out.scale) + " is outside (1e-3, 1e3)";
  } else {
    out.ok = true;
  }
  return out;
}

bool MovingInitializationCheckOptions::is_valid(std::string* why) const {
  core::Problems problems;
  if (!(window_s > 0.0) || !(every_s > 0.0) || !(keyframe_spacing_s > 0.0) || !(min_path_m >= 0.0)) {
    problems.add("window_s, every_s and keyframe_spacing_s must be > 0, min_path_m >= 0");
  }
  if (!(keyframe_spacing_s * 2.0 <= window_s)) problems.add("a window must hold at least 3 keyframes (window_s >= 2 keyframe_spacing_s)");
  if (std::string p; !initialization.is_valid(&p)) problems.add_all("initialization: ", p);
  return problems.report(why);
}

namespace {

// The states of one window, every keyframe_spacing_s from `first`; empty when it runs past the end.
std::vector<std::size_t> window_keyframes(const std::vector<GroundTruthState>& states, std::size_t first,
                                          const MovingInitializationCheckOptions& options) {
  std::vector<std::size_t> picked{first};
  const double start = states[first].stamp.seconds();
  for (std::size_t k = first + 1; k < states.size(); ++k) {
    const double t = states[k].stamp.seconds();
    if (t - start > options.window_s + 1e-6) return picked;
    if (t - states[picked.back()].stamp.seconds() >= options.keyframe_spacing_s - 1e-6) picked.push_back(k);
  }
  return {};
}

MovingInitializationWindow initialise_window(const std::vector<ImuSample>& samples, const std::vector<GroundTruthState>& states,
                                             const std::vector<std::size_t>& picked, const ImuNoise& noise,
                                             const MovingInitializationCheckOptions& options) {
  std::vector<core::Timestamp> stamps;
  std::vector<core::SE3> poses;
  for (const std::size_t k : picked) {
    stamps.push_back(states[k].stamp);
    poses.push_back(states[k].state.T_world_body);
  }
  InertialInitializationOptions o = options.initialization;
  o.estimate_scale = false;
  const InertialInitialization init = initialize_inertial(stamps, poses, core::SE3(), samples, noise, o);
  MovingInitializationWindow w;
  w.start_s = states[picked.front()].stamp.seconds() - states.front().stamp.seconds();
  w.ok = init.ok;
  w.why = init.why;
  if (!init.ok) return w;
  const Vector3 down(0.0, 0.0, -1.0);
  w.gravity_error_deg = std::atan2(init.gravity_world.cross(down).norm(), init.gravity_world.dot(down)) * 180.0 / M_PI;
  const ImuBias& truth = states[picked.front()].bias;
  w.gyro_bias_error_rad_s = (init.bias.gyro_rad_s - truth.gyro_rad_s).norm();
  w.accel_bias_error_mps2 = (init.bias.accel_mps2 - truth.accel_mps2).norm();
  return w;
}

}  // namespace

MovingInitializationCheck check_moving_initialization(const std::vector<ImuSample>& samples, const std::vector<GroundTruthState>& states,
                                                      const ImuNoise& noise, const MovingInitializationCheckOptions& options) {
  MovingInitializationCheck check;
  std::vector<double> gravity, gyro, accel;
  double next_start = states.empty() ? 0.0 : states.front().stamp.seconds();
  for (std::size_t first = 0; first < states.size(); ++first) {
    if (states[first].stamp.seconds() < next_start) continue;
    const std::vector<std::size_t> picked = window_keyframes(states, first, options);
    if (picked.size() < 3) break;  // the recording ends within the window
    next_start = states[first].stamp.seconds() + options.every_s;
    double path = 0.0;
    for (std::size_t i = 1; i < picked.size(); ++i) {
      path += (states[picked[i]].state.T_world_body.translation() - states[picked[i - 1]].state.T_world_body.translation()).norm();
    }
    if (path < options.min_path_m) {
      ++check.windows_still;
      continue;
    }
    check.windows.push_back(initialise_window(samples, states, picked, noise, options));
    const MovingInitializationWindow& w = check.windows.back();
    if (!w.ok) continue;
    gravity.push_back(w.gravity_error_deg);
    gyro.push_back(w.gyro_bias_error_rad_s);
    accel.push_back(w.accel_bias_error_mps2);
  }
  check.gravity_deg = spread_of(gravity);
  check.gyro_bias_rad_s = spread_of(gyro);
  check.accel_bias_mps2 = spread_of(accel);
  return check;
}

}  // namespace cairn::inertial
