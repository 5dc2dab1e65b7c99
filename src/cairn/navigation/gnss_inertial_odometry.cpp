#include "cairn/navigation/gnss_inertial_odometry.hpp"

#include <algorithm>
#include <array>
#include <climits>
#include <cstdint>
#include <cmath>
#include <deque>
#include <optional>
#include <stdexcept>

#include "cairn/backend/least_squares.hpp"
#include "cairn/core/problems.hpp"
#include "cairn/core/timer.hpp"
#include "cairn/inertial/imu_factors.hpp"
#include "cairn/inertial/preintegration.hpp"
#include "cairn/navigation/navigation_factors.hpp"
#include "cairn/inertial/window_prior.hpp"

namespace cairn::navigation {

bool GnssInertialOdometryOptions::is_valid(std::string* why) const {
  core::Problems problems;
  std::string nested;
  if (!noise.is_valid(&nested)) problems.add_all("noise: ", nested);
  nested.clear();
  if (!gnss.is_valid(&nested)) problems.add_all("gnss: ", nested);
  nested.clear();
  if (!outliers.is_valid(&nested)) problems.add_all("outliers: ", nested);
  nested.clear();
  if (!yaw.is_valid(&nested)) problems.add_all("yaw: ", nested);
  nested.clear();
  if (!initialization.is_valid(&nested)) problems.add_all("initialization: ", nested);
  problems.require_positive(gravity_mps2, "gravity_mps2");
  problems.require_positive(wheel_speed_sigma_mps, "wheel_speed_sigma_mps");
  problems.require_positive(min_wheel_speed_sigma_mps, "min_wheel_speed_sigma_mps");
  problems.require_positive(nonholonomic_sigma_mps, "nonholonomic_sigma_mps");
  problems.require_positive(max_wheel_gap_s, "max_wheel_gap_s");
  problems.require_positive(initial_velocity_sigma_mps, "initial_velocity_sigma_mps");
  problems.require_positive(initial_gyro_bias_sigma_rad_s, "initial_gyro_bias_sigma_rad_s");
  problems.require_positive(initial_accel_bias_sigma_mps2, "initial_accel_bias_sigma_mps2");
  problems.require_positive(initial_tilt_sigma_rad, "initial_tilt_sigma_rad");
  if (!(state_period_s >= 0.01 && state_period_s <= 1.0)) problems.add("state_period_s must be in [0.01, 1]");
  if (window_states < 3) problems.add("window_states must be >= 3");
  if (!(std::isfinite(latency_s) && latency_s >= 0.0)) problems.add("latency_s must be finite and >= 0");
  if (max_iterations < 1) problems.add("max_iterations must be >= 1");
  return problems.report(why);
}

namespace {

using inertial::BiasValues;
using inertial::ImuBias;
using inertial::NavState;
using inertial::PreintegratedImu;
using Matrix15 = Eigen::Matrix<double, 15, 15>;
using inertial::joint_marginal_covariance;

struct WheelMeasurement {
  double speed_mps = 0.0;
  Vector3 sigma_mps = Vector3::Ones();
  Vector3 omega_imu_rad_s = Vector3::Zero();
};

/// A fix on a state: its index in the received fixes and its time minus the state's.
struct FixOnState {
  std::size_t fix = 0;
  double dt_s = 0.0;
};

struct WindowState : inertial::StateValues {
  std::int64_t index = 0;  ///< state k at t0 + k period
  core::Timestamp stamp;
  std::optional<PreintegratedImu> from_previous;
  std::optional<WheelMeasurement> wheel;
  std::vector<FixOnState> fixes;  ///< with factors once aligned
  NavState predicted;
};

/// The prior on the oldest state: its mean and the joint covariance over (pose, velocity, bias).
struct OldestPrior {
  core::SE3 pose;
  Vector3 velocity = Vector3::Zero();
  BiasValues bias = BiasValues::Zero();
  Matrix15 covariance = Matrix15::Identity();
};

/// Moves a state into another world frame: p' = T p, v' = R v.
NavState transform(const core::SE3& T_new_old, const NavState& s) {
  return {T_new_old * s.T_world_body, T_new_old.so3() * s.v_world_mps};
}

/// The fix as the estimator uses it: without its altitude's weight when use_gnss_altitude is false.
gnss::GnssFix used_fix(const gnss::GnssFix& fix, const GnssInertialOdometryOptions& o) {
  if (o.use_gnss_altitude) return fix;
  gnss::GnssFix horizontal = fix;
  Matrix3 covariance = gnss::factor_covariance_enu(fix, o.gnss);
  covariance.row(2).setZero();
  covariance.col(2).setZero();
  covariance(2, 2) = kUnusedVerticalVariance;
  horizontal.covariance_enu_m2 = covariance;
  horizontal.covariance_known = true;
  return horizontal;
}

}  // namespace

struct GnssInertialOdometry::Impl {
  const GnssInertialOdometryOptions& o;
  std::int64_t period_ns = 0;
  std::vector<inertial::ImuSample> imu;
  std::vector<WheelSpeed> wheels;
  std::vector<gnss::GnssFix> fixes;
  std::vector<GnssFixResult> fix_results;
  std::vector<std::int64_t> fix_state;  ///< per received fix: its state's index (-1: none)
  std::vector<double> fix_dt;
  std::size_t next_fix = 0;
  std::vector<std::size_t> pending;  ///< fixes on states before the alignment
  core::Timestamp clock;              ///< latest stamp of any stream
  bool any_stamp = false;
  bool initialized = false;
  bool finished = false;
  core::Timestamp t0;
  std::int64_t next_index = 0;
  std::deque<WindowState> window;
  OldestPrior prior;
  std::vector<NavigationState> history;
  std::optional<gnss::LocalFrame> frame;
  bool aligned = false;
  NavigationSummary summary;
  std::vector<std::array<int, 3>> ids;

  explicit Impl(const GnssInertialOdometryOptions& options) : o(options) {
    period_ns = static_cast<std::int64_t>(std::llround(options.state_period_s * 1e9));
  }
  void see(core::Timestamp stamp) {
    if (!any_stamp || stamp > clock) clock = stamp;
    any_stamp = true;
  }
  core::Timestamp state_time(std::int64_t k) const { return core::Timestamp::from_nanoseconds(t0.nanoseconds() + k * period_ns); }
  void advance(bool all);
  bool try_initialize(bool all);
  void step(core::Timestamp t);
  void first_state(WindowState& s);
  std::optional<WheelMeasurement> wheel_at(core::Timestamp t, const ImuBias& bias) const;
  void attach_fixes(WindowState& s);
  backend::LeastSquaresProblem build_problem();
  void add_link_factors(backend::LeastSquaresProblem& problem, std::size_t k);
  void add_measurement_factors(backend::LeastSquaresProblem& problem, std::size_t k);
  Matrix15 marginalize_oldest();
  void solve();
  bool try_align();
  void move_world(const core::SE3& T_enu_world);
  void loosen_prior(const gnss::YawAlignment& alignment);
  void slide();
  NavigationState final_state(const WindowState& s) const;
  void judge_fixes();
};

GnssInertialOdometry::GnssInertialOdometry(const GnssInertialOdometryOptions& options) : options_(options) {
  std::string why;
  if (!options.is_valid(&why)) throw std::invalid_argument("invalid GNSS-inertial odometry options: " + why);
  impl_ = std::make_unique<Impl>(options_);
}

GnssInertialOdometry::~GnssInertialOdometry() = default;

void GnssInertialOdometry::add_imu(const inertial::ImuSample& sample) {
  Impl& m = *impl_;
  if (m.finished) throw std::invalid_argument("GnssInertialOdometry::add_imu after finish()");
  if (!m.imu.empty() && !(m.imu.back().stamp < sample.stamp)) {
    throw std::invalid_argument("GnssInertialOdometry::add_imu: stamps must increase strictly, " +
                                sample.stamp.to_seconds_string() + " s after " + m.imu.back().stamp.to_seconds_string() + " s");
  }
  m.imu.push_back(sample);
  m.see(sample.stamp);
  m.advance(false);
}

void GnssInertialOdometry::add_wheel_odometry(const WheelSpeed& reading) {
  Impl& m = *impl_;
  if (m.finished) throw std::invalid_argument("GnssInertialOdometry::add_wheel_odometry after finish()");
  if (!m.wheels.empty() && !(m.wheels.back().stamp < reading.stamp)) {
    throw std::invalid_argument("GnssInertialOdometry::add_wheel_odometry: stamps must increase strictly");
  }
  if (!std::isfinite(reading.forward_speed_mps) || !(reading.variance_m2_s2 >= 0.0)) {
    throw std::invalid_argument("GnssInertialOdometry::add_wheel_odometry: a finite speed and a variance >= 0 expected");
  }
  m.wheels.push_back(reading);
  m.see(reading.stamp);
  m.advance(false);
}

void GnssInertialOdometry::add_gnss(const gnss::GnssFix& fix) {
  Impl& m = *impl_;
  if (m.finished) throw std::invalid_argument("GnssInertialOdometry::add_gnss after finish()");
  if (!m.fixes.empty() && !(m.fixes.back().stamp < fix.stamp)) {
    throw std::invalid_argument("GnssInertialOdometry::add_gnss: stamps must increase strictly");
  }
  std::string why;
  if (fix.status == gnss::kStatusNoFix || !gnss::is_valid_geodetic({fix.latitude_deg, fix.longitude_deg, fix.altitude_m}, &why)) {
    throw std::invalid_argument("GnssInertialOdometry::add_gnss: not a position fix: " + why);
  }
  if (!m.frame) {
    m.frame.emplace(gnss::GeodeticPosition{fix.latitude_deg, fix.longitude_deg, fix.altitude_m});
    m.summary.enu_origin = m.frame->origin();
  }
  m.fixes.push_back(fix);
  GnssFixResult result;
  result.time_s = fix.stamp.seconds();
  result.p_enu_m = m.frame->forward(fix);
  m.fix_results.push_back(result);
  m.fix_state.push_back(-1);
  m.fix_dt.push_back(0.0);
  m.see(fix.stamp);
  m.advance(false);
}

void GnssInertialOdometry::finish() {
  Impl& m = *impl_;
  if (m.finished) return;
  m.advance(true);
  for (const WindowState& s : m.window) m.history.push_back(m.final_state(s));
  m.window.clear();
  m.finished = true;
  m.judge_fixes();
}

const std::vector<NavigationState>& GnssInertialOdometry::states() const { return impl_->history; }
const std::vector<GnssFixResult>& GnssInertialOdometry::fix_results() const { return impl_->fix_results; }

NavigationSummary GnssInertialOdometry::summary() const {
  const Impl& m = *impl_;
  NavigationSummary s = m.summary;
  s.states = m.history.size() + m.window.size();
  s.imu_samples = m.imu.size();
  s.wheel_readings = m.wheels.size();
  s.fixes_received = m.fixes.size();
  s.gate_squared_mahalanobis = gnss::chi_square_3_quantile(options_.outliers.probability);
  std::vector<core::Timestamp> stamps;
  for (const auto& fix : m.fixes) stamps.push_back(fix.stamp);
  s.dropouts = gnss::find_dropouts(stamps, options_.outliers.max_gap_s);
  if (m.imu.empty()) {
    s.status = NavigationStatus::kNoImu;
    s.message = "no IMU sample";
  } else if (!m.aligned) {
    s.status = NavigationStatus::kNotAligned;
    s.message = m.fixes.empty() ? "no GNSS fix: the world is the IMU's start frame"
                                : "GNSS never aligned (" + s.alignment.message + "): the world is the IMU's start frame";
  } else {
    s.status = NavigationStatus::kOk;
    s.message = "ok";
  }
  return s;
}

// Solves every state whose time every stream has passed (all: every state the IMU covers).
void GnssInertialOdometry::Impl::advance(bool all) {
  if (!initialized && !try_initialize(all)) return;
  while (true) {
    const core::Timestamp t = state_time(next_index);
    if (imu.back().stamp < t) return;
    const std::int64_t wait_ns = period_ns / 2 + static_cast<std::int64_t>(std::llround(o.latency_s * 1e9));
    if (!all && clock.nanoseconds() < t.nanoseconds() + wait_ns) return;
    step(t);
    ++next_index;
  }
}


// Waits for the static-initialisation window of IMU (or for finish()), then fixes t0 at the first
// IMU sample: the first state's time.
bool GnssInertialOdometry::Impl::try_initialize(bool all) {
  if (imu.empty()) return false;
  const double span_s = imu.back().stamp.seconds() - imu.front().stamp.seconds();
  if (!all && span_s < o.initialization.window_s) return false;
  t0 = imu.front().stamp;
  initialized = true;
  return true;
}

// The first state: attitude from the IMU's first window (static initialisation, or the tilt of the
// mean specific force while moving, yaw 0), at the world's origin, velocity from the wheels.
void GnssInertialOdometry::Impl::first_state(WindowState& s) {
  std::vector<inertial::ImuSample> first;
  for (const auto& sample : imu) {
    if (sample.stamp.seconds() - t0.seconds() <= o.initialization.window_s) first.push_back(sample);
  }
  const inertial::StaticInitialization statics = inertial::initialize_static(first, o.initialization);
  summary.still_start = statics.ok;
  core::SO3 R_world_imu = statics.R_world_body;
  ImuBias bias;
  if (statics.ok) {
    bias.gyro_rad_s = statics.gyro_bias_rad_s;
  } else if (statics.mean_accel_mps2.norm() > 0.0) {
    const Vector3 up = statics.mean_accel_mps2.normalized();
    R_world_imu = core::SO3::from_rpy(std::atan2(up.y(), up.z()), std::atan2(-up.x(), std::hypot(up.y(), up.z())), 0.0);
  }
  Vector3 v_world = Vector3::Zero();
  if (const auto wheel = wheel_at(s.stamp, bias)) {
    v_world = R_world_imu * (o.T_imu_vehicle.so3() * Vector3(wheel->speed_mps, 0.0, 0.0));
  }
  s.set(NavState{core::SE3(R_world_imu, Vector3::Zero()), v_world});
  s.bias = inertial::to_values(bias);
  prior = OldestPrior{s.nav().T_world_body, v_world, s.bias, Matrix15::Zero()};
  // Position and yaw are the world's gauge (tight); roll and pitch as good as the tilt; the
  // tangent phi is in the IMU frame: Sigma_phi = R^T diag(tilt^2, tilt^2, gauge) R.
  const double gauge = 1e-8;
  const Matrix3 R = R_world_imu.matrix();
  const Vector3 attitude(o.initial_tilt_sigma_rad * o.initial_tilt_sigma_rad, o.initial_tilt_sigma_rad * o.initial_tilt_sigma_rad, gauge);
  prior.covariance.block<3, 3>(0, 0) = Matrix3::Identity() * gauge;
  prior.covariance.block<3, 3>(3, 3) = R.transpose() * attitude.asDiagonal() * R;
  prior.covariance.block<3, 3>(6, 6) = Matrix3::Identity() * o.initial_velocity_sigma_mps * o.initial_velocity_sigma_mps;
  // A still start measured the gyro bias (to its standard error, three of them here); else the option.
  Vector3 gyro_sigma = Vector3::Constant(o.initial_gyro_bias_sigma_rad_s);
  if (statics.ok) gyro_sigma = (3.0 * statics.gyro_bias_sigma_rad_s).cwiseMax(1e-5).cwiseMin(o.initial_gyro_bias_sigma_rad_s);
  prior.covariance.block<3, 3>(9, 9) = gyro_sigma.cwiseAbs2().asDiagonal();
  prior.covariance.block<3, 3>(12, 12) = Matrix3::Identity() * o.initial_accel_bias_sigma_mps2 * o.initial_accel_bias_sigma_mps2;
}

// The wheels' forward speed at t, interpolated between the readings around it (none when they
// are farther apart than max_wheel_gap_s), with the IMU's rate at t for the lever arm.
std::optional<WheelMeasurement> GnssInertialOdometry::Impl::wheel_at(core::Timestamp t, const ImuBias& bias) const {
  const auto after = std::lower_bound(wheels.begin(), wheels.end(), t,
                                      [](const WheelSpeed& w, core::Timestamp x) { return w.stamp < x; });
  if (after == wheels.end()) return std::nullopt;
  const WheelSpeed* a = &*after;
  const WheelSpeed* b = &*after;
  if (after->stamp > t) {
    if (after == wheels.begin()) return std::nullopt;
    a = &*(after - 1);
  }
  const double gap_s = b->stamp.seconds() - a->stamp.seconds();
  if (gap_s > o.max_wheel_gap_s) return std::nullopt;
  const double w = gap_s > 0.0 ? (t.seconds() - a->stamp.seconds()) / gap_s : 0.0;
  const double variance = std::max(a->variance_m2_s2, b->variance_m2_s2);
  const double sigma = variance > 0.0 ? std::max(std::sqrt(variance), o.min_wheel_speed_sigma_mps)
                                      : std::max(o.wheel_speed_sigma_mps, o.min_wheel_speed_sigma_mps);
  WheelMeasurement m;
  m.speed_mps = (1.0 - w) * a->forward_speed_mps + w * b->forward_speed_mps;
  m.sigma_mps = Vector3(sigma, o.nonholonomic_sigma_mps, o.nonholonomic_sigma_mps);
  const auto sample = std::upper_bound(imu.begin(), imu.end(), t,
                                       [](core::Timestamp x, const inertial::ImuSample& s) { return x < s.stamp; });
  if (sample != imu.begin()) m.omega_imu_rad_s = (sample - 1)->gyro_rad_s - bias.gyro_rad_s;
  return m;
}

// The received fixes within half a period of state s go on it: as factors once aligned, else
// kept for the alignment. Fixes older than that arrived too late (or before the first state).
void GnssInertialOdometry::Impl::attach_fixes(WindowState& s) {
  const std::int64_t half = period_ns / 2;
  for (; next_fix < fixes.size(); ++next_fix) {
    const std::int64_t d = fixes[next_fix].stamp.nanoseconds() - s.stamp.nanoseconds();
    if (d >= period_ns - half) break;
    if (d < -half) {
      ++summary.fixes_late;
      continue;
    }
    fix_state[next_fix] = s.index;
    fix_dt[next_fix] = static_cast<double>(d) * 1e-9;
    if (aligned) {
      s.fixes.push_back({next_fix, fix_dt[next_fix]});
      fix_results[next_fix].used = true;
      ++summary.fixes_used;
    } else {
      pending.push_back(next_fix);
    }
  }
}

void GnssInertialOdometry::Impl::step(core::Timestamp t) {
  const auto start = core::Clock::now();
  WindowState s;
  s.index = next_index;
  s.stamp = t;
  if (window.empty()) {
    first_state(s);
    s.predicted = s.nav();
  } else {
    const WindowState& previous = window.back();
    const ImuBias bias = inertial::bias_from_values(previous.bias.data());
    PreintegratedImu pim(o.noise, bias);
    if (!inertial::integrate_interval(imu, previous.stamp, t, pim)) {
      throw std::logic_error("GnssInertialOdometry: the IMU does not cover a state interval");  // advance() ensures it does
    }
    s.set(pim.predict(previous.nav(), bias, inertial::gravity_z_up(o.gravity_mps2)));
    s.bias = previous.bias;
    s.predicted = s.nav();
    s.from_previous = std::move(pim);
  }
  s.wheel = wheel_at(t, inertial::bias_from_values(s.bias.data()));
  if (!s.wheel) ++summary.states_without_wheel;
  attach_fixes(s);
  window.push_back(std::move(s));
  solve();
  if (!aligned && !pending.empty() && try_align()) solve();
  if (static_cast<int>(window.size()) > o.window_states) slide();
  const double step_s = core::seconds_since(start);
  summary.solve_s += step_s;
  summary.max_step_s = std::max(summary.max_step_s, step_s);
}

void GnssInertialOdometry::Impl::solve() {
  backend::LeastSquaresProblem problem = build_problem();
  backend::LeastSquaresOptions options;
  options.linear_solver = backend::LinearSolverType::kSparseNormalCholesky;
  options.threads = 1;
  options.max_iterations = o.max_iterations;
  backend::solve(problem, options);
}

// The window's graph: the joint prior on the oldest state, then each state's factors.
backend::LeastSquaresProblem GnssInertialOdometry::Impl::build_problem() {
  backend::LeastSquaresProblem problem;
  ids.clear();
  for (WindowState& s : window) {
    ids.push_back({problem.add_variable(s.pose.data(), backend::se3_manifold()),
                   problem.add_variable(s.velocity.data(), backend::euclidean_manifold(3)),
                   problem.add_variable(s.bias.data(), backend::euclidean_manifold(6))});
  }
  problem.add_factor(std::make_unique<inertial::StatePriorFactor>(prior.pose, prior.velocity, prior.bias, nullptr, prior.covariance),
                     {ids[0][0], ids[0][1], ids[0][2]});
  for (std::size_t k = 0; k < window.size(); ++k) {
    add_link_factors(problem, k);
    add_measurement_factors(problem, k);
  }
  return problem;
}

void GnssInertialOdometry::Impl::add_link_factors(backend::LeastSquaresProblem& problem, std::size_t k) {
  const WindowState& s = window[k];
  if (k == 0 || !s.from_previous) return;
  problem.add_factor(std::make_unique<inertial::ImuFactor>(*s.from_previous, inertial::gravity_z_up(o.gravity_mps2)),
                     {ids[k - 1][0], ids[k - 1][1], ids[k][0], ids[k][1], ids[k - 1][2]});
  problem.add_factor(std::make_unique<inertial::BiasRandomWalkFactor>(o.noise, s.from_previous->delta_time_s()),
                     {ids[k - 1][2], ids[k][2]});
}

void GnssInertialOdometry::Impl::add_measurement_factors(backend::LeastSquaresProblem& problem, std::size_t k) {
  const WindowState& s = window[k];
  const auto& id = ids[k];
  if (s.wheel) {
    problem.add_factor(std::make_unique<WheelVelocityFactor>(s.wheel->speed_mps, s.wheel->sigma_mps, s.wheel->omega_imu_rad_s,
                                                             o.T_imu_vehicle),
                       {id[0], id[1]});
  }
  gnss::GnssFactorOptions gnss_options = o.gnss;
  gnss_options.T_enu_world = core::SE3();
  for (const FixOnState& f : s.fixes) {
    problem.add_factor(std::make_unique<ShiftedGnssFactor>(gnss::make_gnss_factor(used_fix(fixes[f.fix], o), *frame, gnss_options), f.dt_s),
                       {id[0], id[1]}, o.gnss.loss);
  }
}

namespace {

/// The antenna's position at a fix's time from the fix's state (pose and velocity).
Vector3 antenna_at(const NavState& s, double dt_s, const Vector3& lever_arm_imu_m) {
  return s.T_world_body * lever_arm_imu_m + s.v_world_mps * dt_s;
}

}  // namespace

// Fits the world to ENU on the dead-reckoned antenna positions of the fixes received so far
// (gnss_yaw.hpp); on success moves everything into ENU and gives the window's fixes their factors.
bool GnssInertialOdometry::Impl::try_align() {
  std::vector<Vector3> p_world;
  std::vector<Vector3> p_enu;
  const std::int64_t first_in_window = window.front().index;
  for (const std::size_t i : pending) {
    const std::int64_t k = fix_state[i];
    const NavState s = k >= first_in_window ? window[static_cast<std::size_t>(k - first_in_window)].nav()
                                            : history[static_cast<std::size_t>(k)].state;
    p_world.push_back(antenna_at(s, fix_dt[i], o.gnss.lever_arm_body_m));
    p_enu.push_back(fix_results[i].p_enu_m);
  }
  summary.alignment = gnss::align_world_to_enu(p_world, p_enu, o.yaw);
  if (!summary.alignment.ok()) return false;
  aligned = true;
  summary.alignment_time_s = window.back().stamp.seconds();
  move_world(summary.alignment.T_enu_world);
  loosen_prior(summary.alignment);
  for (const std::size_t i : pending) {
    const std::int64_t k = fix_state[i];
    if (k < first_in_window) continue;
    window[static_cast<std::size_t>(k - first_in_window)].fixes.push_back({i, fix_dt[i]});
    fix_results[i].used = true;
    ++summary.fixes_used;
  }
  pending.clear();
  return true;
}

// Every estimate and the prior's mean into the new world (ENU). Pose covariances are in the
// body's tangent space (right perturbations) and do not change; the velocity's rotates.
void GnssInertialOdometry::Impl::move_world(const core::SE3& T_enu_world) {
  for (WindowState& s : window) {
    s.set(transform(T_enu_world, s.nav()));
    s.predicted = transform(T_enu_world, s.predicted);
  }
  for (NavigationState& s : history) {
    s.state = transform(T_enu_world, s.state);
    s.predicted = transform(T_enu_world, s.predicted);
  }
  const NavState moved = transform(T_enu_world, NavState{prior.pose, prior.velocity});
  prior.pose = moved.T_world_body;
  prior.velocity = moved.v_world_mps;
  const Matrix3 R = T_enu_world.so3().matrix();
  prior.covariance.middleRows<3>(6) = (R * prior.covariance.middleRows<3>(6)).eval();
  prior.covariance.middleCols<3>(6) = (prior.covariance.middleCols<3>(6) * R.transpose()).eval();
}

// The oldest state's position and yaw were the world's gauge; after the fit they are as
// uncertain as the fit: position by its RMS residual plus the yaw error over the state's distance
// from the fixes' centroid (bounded by the spread), yaw by the fit's sigma; the velocity turns with
// the yaw. Three sigmas of the fit, so a poor fit is corrected by the fixes rather than kept.
void GnssInertialOdometry::Impl::loosen_prior(const gnss::YawAlignment& alignment) {
  const double k = 3.0;
  const double yaw_sigma = k * std::max(alignment.yaw_sigma_rad, 1e-3);
  const double position_sigma = k * alignment.rms_residual_m + yaw_sigma * 2.0 * alignment.spread_m + 0.1;
  const Matrix3 R_world_imu = prior.pose.so3().matrix();
  const Vector3 up_imu = R_world_imu.transpose() * Vector3::UnitZ();
  prior.covariance.block<3, 3>(0, 0) += Matrix3::Identity() * position_sigma * position_sigma;
  prior.covariance.block<3, 3>(3, 3) += yaw_sigma * yaw_sigma * up_imu * up_imu.transpose();
  const double speed_sigma = yaw_sigma * prior.velocity.norm();
  prior.covariance.block<3, 3>(6, 6) += Matrix3::Identity() * speed_sigma * speed_sigma;
}

// Marginalises the oldest state: the factors that touch it (the prior, its wheel and GNSS factors,
// the IMU and bias factors to the next state), linearised at the solution, with the oldest state's
// block eliminated (the Schur complement: Sibley, Matthies, Sukhatme, "Sliding window filter with
// application to planetary landing", JFR 27(5), 2010, Sec. 3; Leutenegger et al., "Keyframe-based
// visual-inertial odometry using nonlinear optimization", IJRR 34(3), 2015, Sec. IV-E) give the next
// state's covariance. Only those factors: the next state's marginal in the whole window would count
// the factors that stay in the window a second time, and the prior would grow overconfident.
Matrix15 GnssInertialOdometry::Impl::marginalize_oldest() {
  backend::LeastSquaresProblem problem;
  ids.clear();
  for (std::size_t k = 0; k < 2; ++k) {
    WindowState& s = window[k];
    ids.push_back({problem.add_variable(s.pose.data(), backend::se3_manifold()),
                   problem.add_variable(s.velocity.data(), backend::euclidean_manifold(3)),
                   problem.add_variable(s.bias.data(), backend::euclidean_manifold(6))});
  }
  problem.add_factor(std::make_unique<inertial::StatePriorFactor>(prior.pose, prior.velocity, prior.bias, nullptr, prior.covariance),
                     {ids[0][0], ids[0][1], ids[0][2]});
  add_measurement_factors(problem, 0);
  add_link_factors(problem, 1);
  const Eigen::MatrixXd covariance = joint_marginal_covariance(problem, {ids[1][0], ids[1][1], ids[1][2]});
  if (!covariance.allFinite() || covariance.rows() != 15) return prior.covariance;
  return covariance;
}

// The oldest state leaves the window (final); the next one gets the prior.
void GnssInertialOdometry::Impl::slide() {
  prior.covariance = marginalize_oldest();
  const WindowState& next = window[1];
  prior.pose = next.nav().T_world_body;
  prior.velocity = next.velocity;
  prior.bias = next.bias;
  history.push_back(final_state(window.front()));
  window.pop_front();
  window.front().from_previous.reset();
}

NavigationState GnssInertialOdometry::Impl::final_state(const WindowState& s) const {
  NavigationState out;
  out.time_s = s.stamp.seconds();
  out.state = s.nav();
  out.predicted = s.predicted;
  out.bias = inertial::bias_from_values(s.bias.data());
  out.wheel_used = s.wheel.has_value();
  out.gnss_fixes = static_cast<int>(s.fixes.size());
  return out;
}

// Each fix against its state's final estimate: the error and e^T Sigma^-1 e of the factor it
// had (or would have had), and the gate. Nothing to judge when the world never reached ENU.
void GnssInertialOdometry::Impl::judge_fixes() {
  if (!aligned) return;
  gnss::GnssFactorOptions gnss_options = o.gnss;
  gnss_options.T_enu_world = core::SE3();
  const double gate = gnss::chi_square_3_quantile(o.outliers.probability);
  summary.outliers = 0;
  for (std::size_t i = 0; i < fixes.size(); ++i) {
    const std::int64_t k = fix_state[i];
    if (k < 0 || k >= static_cast<std::int64_t>(history.size())) continue;
    const NavState& s = history[static_cast<std::size_t>(k)].state;
    const auto factor = gnss::make_gnss_factor(used_fix(fixes[i], o), *frame, gnss_options);
    const core::SE3 T_at_fix(s.T_world_body.so3(), s.T_world_body.translation() + s.v_world_mps * fix_dt[i]);
    GnssFixResult& r = fix_results[i];
    r.error_enu_m = factor->error_enu_m(T_at_fix);
    r.squared_mahalanobis = factor->squared_mahalanobis(T_at_fix);
    r.outlier = r.squared_mahalanobis > gate;
    if (r.outlier) ++summary.outliers;
  }
}

void run_in_time_order(GnssInertialOdometry& odometry, const std::vector<inertial::ImuSample>& imu,
                       const std::vector<WheelSpeed>& wheels, const std::vector<gnss::GnssFix>& fixes) {
  std::size_t i = 0, w = 0, g = 0;
  while (i < imu.size() || w < wheels.size() || g < fixes.size()) {
    const std::int64_t ti = i < imu.size() ? imu[i].stamp.nanoseconds() : INT64_MAX;
    const std::int64_t tw = w < wheels.size() ? wheels[w].stamp.nanoseconds() : INT64_MAX;
    const std::int64_t tg = g < fixes.size() ? fixes[g].stamp.nanoseconds() : INT64_MAX;
    if (ti <= tw && ti <= tg) {
      odometry.add_imu(imu[i++]);
    } else if (tw <= tg) {
      odometry.add_wheel_odometry(wheels[w++]);
    } else {
      odometry.add_gnss(fixes[g++]);
    }
  }
  odometry.finish();
}

}  // namespace cairn::navigation
