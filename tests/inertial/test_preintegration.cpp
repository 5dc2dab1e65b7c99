// IMU preintegration (Forster et al., T-RO 2017) against closed forms, numeric Jacobians and Monte
// Carlo. The expected values come from tests/inertial/imu_test_trajectory.hpp's closed-form motion,
// from central differences, or from the noise the test draws itself.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

#include "cairn/backend/least_squares.hpp"
#include "cairn/inertial/imu_factors.hpp"
#include "cairn/inertial/preintegration.hpp"
#include "cairn/inertial/static_initialization.hpp"
#include "inertial/imu_test_trajectory.hpp"

namespace cairn::inertial {
namespace {

using test::AnalyticTrajectory;

PreintegratedImu integrate_truth(const AnalyticTrajectory& truth, double t0, double t1, double dt,
                                 const ImuBias& true_bias = {}, const ImuBias& linearisation = {}) {
  PreintegratedImu pim(ImuNoise{}, linearisation);
  const auto samples = test::sample_imu(truth, t0, t1, dt, true_bias);
  EXPECT_TRUE(integrate_interval(samples, samples.front().stamp, core::Timestamp::from_seconds(t1), pim));
  return pim;
}

struct StateError {
  double rotation_rad, velocity_mps, position_m;
};

StateError error_of(const NavState& predicted, const NavState& truth) {
  return {(truth.T_world_body.so3().inverse() * predicted.T_world_body.so3()).angle(),
          (predicted.v_world_mps - truth.v_world_mps).norm(),
          (predicted.T_world_body.translation() - truth.T_world_body.translation()).norm()};
}

// A random preintegration for the Jacobian checks: biases up to 0.05 rad/s and 0.3 m/s^2, 5-64
// samples at 200 Hz of a rate up to 15 rad/s (fast rotation) wobbling by 2 rad/s, and
// accelerations up to 20 m/s^2. `random3(scale)` draws a vector with components in +-scale.
template <class Random3>
PreintegratedImu random_preintegration(std::mt19937& rng, Random3& random3) {
  PreintegratedImu pim(ImuNoise{}, ImuBias{random3(0.05), random3(0.3)});
  const Vector3 rate = random3(15.0);
  const int samples = 5 + static_cast<int>(rng() % 60);
  for (int k = 0; k < samples; ++k) pim.integrate(rate + random3(2.0), random3(20.0), 0.005);
  return pim;
}

// The largest difference between `factor`'s analytic Jacobians (9 residuals) for the variables
// `checked` and central differences through their manifolds, relative to the column's size plus
// the rounding of residuals far from zero (whitened by the ADIS16448's small noise, |r| reaches
// 1e7 here): 4 eps |r| / h. Infinite when the factor cannot be evaluated.
double imu_jacobian_error(const backend::Factor& factor, double* const* values, const std::vector<const backend::Manifold*>& manifolds,
                          const std::vector<int>& checked) {
  const std::size_t n = manifolds.size();
  std::vector<Eigen::Matrix<double, 9, Eigen::Dynamic, Eigen::RowMajor>> analytic(n);
  std::vector<double*> jacobians(n);
  for (std::size_t k = 0; k < n; ++k) {
    analytic[k].resize(9, manifolds[k]->tangent_size());
    jacobians[k] = analytic[k].data();
  }
  Vector9 r;
  if (!factor.evaluate(values, r.data(), jacobians.data())) return std::numeric_limits<double>::infinity();
  double worst = 0.0;
  const double h = 1e-6;
  for (const int var : checked) {
    const backend::Manifold& manifold = *manifolds[static_cast<std::size_t>(var)];
    const int ambient = manifold.ambient_size();
    const std::vector<double> saved(values[var], values[var] + ambient);
    for (int col = 0; col < manifold.tangent_size(); ++col) {
      std::vector<double> plus(static_cast<std::size_t>(ambient)), minus(static_cast<std::size_t>(ambient));
      Eigen::VectorXd delta = Eigen::VectorXd::Zero(manifold.tangent_size());
      delta[col] = h;
      manifold.plus(saved.data(), delta.data(), plus.data());
      delta[col] = -h;
      manifold.plus(saved.data(), delta.data(), minus.data());
      Vector9 r_plus, r_minus;
      std::copy(plus.begin(), plus.end(), values[var]);
      const bool ok_plus = factor.evaluate(values, r_plus.data(), nullptr);
      std::copy(minus.begin(), minus.end(), values[var]);
      const bool ok_minus = factor.evaluate(values, r_minus.data(), nullptr);
      std::copy(saved.begin(), saved.end(), values[var]);
      if (!ok_plus || !ok_minus) return std::numeric_limits<double>::infinity();
      const Vector9 numeric = (r_plus - r_minus) / (2.0 * h);
      const double scale = 1.0 + numeric.cwiseAbs().maxCoeff() + 4.0 * std::numeric_limits<double>::epsilon() * r.cwiseAbs().maxCoeff() / h / 1e-5;
      worst = std::max(worst, (numeric - analytic[static_cast<std::size_t>(var)].col(col)).cwiseAbs().maxCoeff() / scale);
    }
  }
  return worst;
}

// The prediction converges to the closed-form state at first order in dt (zero-order hold), with
// rotation rates up to 2 pi rad/s.
TEST(Preintegration, ConvergesToClosedFormMotionAtFirstOrder) {
  AnalyticTrajectory truth;
  truth.alpha = 2.0 * M_PI;  // 360 deg/s about z
  const double t0 = 0.3, t1 = 1.3;
  StateError errors[2];
  const double steps[2] = {1.0 / 1000.0, 1.0 / 4000.0};
  for (int k = 0; k < 2; ++k) {
    const PreintegratedImu pim = integrate_truth(truth, t0, t1, steps[k]);
    EXPECT_NEAR(pim.delta_time_s(), 1.0, 1e-9);
    errors[k] = error_of(pim.predict(truth.state(t0), ImuBias{}, gravity_z_up()), truth.state(t1));
  }
  EXPECT_LT(errors[1].rotation_rad, 2e-3);
  EXPECT_LT(errors[1].velocity_mps, 1e-2);
  EXPECT_LT(errors[1].position_m, 5e-3);
  // A fourth of the step, a fourth of the error (3 to 5 allows for the second-order terms).
  EXPECT_NEAR(errors[0].rotation_rad / errors[1].rotation_rad, 4.0, 1.0);
  EXPECT_NEAR(errors[0].velocity_mps / errors[1].velocity_mps, 4.0, 1.0);
  EXPECT_NEAR(errors[0].position_m / errors[1].position_m, 4.0, 1.0);
}

// The zero-order hold's error (hold_error_covariance) on noise-free 200 Hz readings of a fast
// nutation (0.5 rad at 12 rad/s about y while turning at 360 deg/s about z: angular
// accelerations of 70 rad/s^2): the prediction's errors over 0.1 s and 0.5 s windows lie within
// the hold's sigmas, where the white noise's sigmas (the ADIS16448's) are far smaller than them.
TEST(Preintegration, HoldErrorCovarianceCoversTheHoldsErrorInAFastTurn) {
  AnalyticTrajectory truth;
  truth.alpha = 2.0 * M_PI;
  truth.beta = 0.5;
  truth.gamma = 12.0;
  const auto samples = test::sample_imu(truth, 0.0, 3.0, 1.0 / 200.0);
  int windows = 0, beyond_white = 0;
  double worst_ratio = 0.0;
  for (const double window_s : {0.1, 0.5}) {
    for (double t0 = 0.05; t0 + window_s < 2.9; t0 += 0.13) {
      const core::Timestamp from = core::Timestamp::from_seconds(t0), to = core::Timestamp::from_seconds(t0 + window_s);
      PreintegratedImu pim(ImuNoise{}, ImuBias{});
      ASSERT_TRUE(integrate_interval(samples, from, to, pim));
      const Matrix9 hold = hold_error_covariance(samples, from, to);
      const StateError e = error_of(pim.predict(truth.state(t0), ImuBias{}, gravity_z_up()), truth.state(t0 + window_s));
      const double sigma[3] = {std::sqrt(hold(0, 0)), std::sqrt(hold(3, 3)), std::sqrt(hold(6, 6))};
      const double error[3] = {e.rotation_rad, e.velocity_mps, e.position_m};
      for (int b = 0; b < 3; ++b) {
        ASSERT_GT(sigma[b], 0.0);
        worst_ratio = std::max(worst_ratio, error[b] / sigma[b]);
        EXPECT_LT(error[b], sigma[b]) << "window " << window_s << " s from " << t0 << " s, block " << b;
        const double white = std::sqrt(pim.covariance()(3 * b, 3 * b));
        if (error[b] > 10.0 * white) ++beyond_white;
      }
      ++windows;
    }
  }
  // The white noise alone would call most of these errors impossible (> 10 sigma).
  EXPECT_GT(beyond_white, 3 * windows / 2);
  RecordProperty("windows", windows);
  RecordProperty("errors_beyond_10_white_sigma", beyond_white);
  RecordProperty("worst_error_over_hold_sigma", std::to_string(worst_ratio));
  std::printf("hold error: %d windows, worst error / hold sigma %.2f, %d of %d errors beyond 10 white-noise sigma\n", windows, worst_ratio,
              beyond_white, 3 * windows);
}

// First-order bias correction [F] (44): the corrected increments match a new integration with the
// new bias to second order in the bias change.
TEST(Preintegration, BiasCorrectionIsFirstOrderAccurate) {
  AnalyticTrajectory truth;
  const ImuBias zero;
  double previous_error = 0.0;
  for (const double scale : {2e-3, 1e-3}) {
    const ImuBias shift{Vector3(1.0, -2.0, 0.5) * scale, Vector3(-3.0, 1.0, 2.0) * scale * 10.0};
    const PreintegratedImu at_zero = integrate_truth(truth, 0.0, 1.0, 0.005, zero, zero);
    const PreintegratedImu at_shift = integrate_truth(truth, 0.0, 1.0, 0.005, zero, shift);
    const double change = (at_zero.delta_p() - at_shift.delta_p()).norm();
    const double error = (at_zero.corrected_delta_p(shift) - at_shift.delta_p()).norm() +
                         (at_zero.corrected_delta_v(shift) - at_shift.delta_v()).norm() +
                         (at_zero.corrected_delta_R(shift).inverse() * at_shift.delta_R()).angle();
    EXPECT_LT(error, 0.02 * change);
    if (previous_error > 0.0) {
      EXPECT_NEAR(previous_error / error, 4.0, 1.0);  // quadratic
    }
    previous_error = error;
  }
}

// Analytic Jacobians of the IMU factor against central differences on the manifolds, 1,000 random
// cases, rotation rates up to 15 rad/s (860 deg/s), states far from agreeing with the increments.
TEST(ImuFactor, JacobiansMatchNumericOnRandomCases) {
  std::mt19937 rng(38);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto random3 = [&](double scale) -> Vector3 { return Vector3(u(rng), u(rng), u(rng)) * scale; };
  const auto random_pose = [&]() -> core::SE3 { return core::SE3(core::SO3::exp(random3(M_PI)), random3(20.0)); };
  double worst = 0.0;
  for (int trial = 0; trial < 1000; ++trial) {
    const PreintegratedImu pim = random_preintegration(rng, random3);
    // Every other trial with gravity a variable (a random gravity vector of about 9.8 m/s^2).
    const bool gravity_variable = trial % 2 == 1;
    const ImuFactor factor = gravity_variable ? ImuFactor::with_gravity_variable(pim) : ImuFactor(pim, gravity_z_up());
    Vector3 gravity = random3(1.0).normalized() * 9.8;
    double pose_i[7], pose_j[7];
    backend::se3_to_values(random_pose(), pose_i);
    backend::se3_to_values(random_pose(), pose_j);
    Vector3 v_i = random3(5.0), v_j = random3(5.0);
    BiasValues bias = to_values(pim.bias_linearisation()) + (BiasValues() << random3(0.01), random3(0.1)).finished();
    double* values[6] = {pose_i, v_i.data(), pose_j, v_j.data(), bias.data(), gravity.data()};
    const backend::Manifold* manifolds[6] = {&backend::se3_manifold(), &backend::euclidean_manifold(3),
                                             &backend::se3_manifold(), &backend::euclidean_manifold(3),
                                             &backend::euclidean_manifold(6), &backend::euclidean_manifold(3)};
    const std::vector<int> checked = gravity_variable ? std::vector<int>{0, 1, 2, 3, 4, 5} : std::vector<int>{0, 1, 2, 3, 4};
    const double error = imu_jacobian_error(factor, values, {manifolds, manifolds + checked.size()}, checked);
    worst = std::max(worst, error);
    ASSERT_LT(error, 1e-5) << "trial " << trial;
  }
  RecordProperty("worst_relative_difference", std::to_string(worst));
}

// The preintegrated covariance [F] (62) against Monte Carlo: increments from noisy samples (white
// noise of the ADIS16448's densities) differ from noise-free ones by errors whose NEES averages 9.
TEST(Preintegration, CovarianceMatchesMonteCarloNees) {
  AnalyticTrajectory truth;
  truth.alpha = 4.0;  // 230 deg/s
  const double dt = 0.005;
  const ImuNoise noise;
  const auto clean = test::sample_imu(truth, 0.0, 1.0, dt);
  PreintegratedImu reference(noise, ImuBias{});
  for (std::size_t k = 0; k + 1 < clean.size(); ++k) reference.integrate(clean[k].gyro_rad_s, clean[k].accel_mps2, dt);
  std::mt19937 rng(9);
  std::normal_distribution<double> normal;
  const double gyro_sigma = noise.gyro_noise_density / std::sqrt(dt);
  const double accel_sigma = noise.accel_noise_density / std::sqrt(dt);
  const int runs = 1000;
  double nees_sum = 0.0;
  for (int run = 0; run < runs; ++run) {
    PreintegratedImu noisy(noise, ImuBias{});
    for (std::size_t k = 0; k + 1 < clean.size(); ++k) {
      const Vector3 gyro = clean[k].gyro_rad_s + gyro_sigma * Vector3(normal(rng), normal(rng), normal(rng));
      const Vector3 accel = clean[k].accel_mps2 + accel_sigma * Vector3(normal(rng), normal(rng), normal(rng));
      noisy.integrate(gyro, accel, dt);
    }
    Vector9 e;
    e << (reference.delta_R().inverse() * noisy.delta_R()).log(), noisy.delta_v() - reference.delta_v(),
        noisy.delta_p() - reference.delta_p();
    nees_sum += e.dot(noisy.covariance().ldlt().solve(e));
  }
  const double mean_nees = nees_sum / runs;
  // chi-square(9): the mean of 1,000 has standard deviation sqrt(18 / 1000) = 0.134; 4 sigma.
  EXPECT_NEAR(mean_nees, 9.0, 4.0 * std::sqrt(18.0 / runs));
  RecordProperty("mean_nees", std::to_string(mean_nees));
}

// A window of IMU factors on the engine pulls perturbed states back onto the true motion.
TEST(ImuFactor, SolveRecoversStatesFromPerturbedStart) {
  AnalyticTrajectory truth;
  const ImuNoise noise;
  const double dt = 0.001, period = 0.25;
  const int states = 9;
  std::vector<std::array<double, 7>> poses(states);
  std::vector<Vector3> velocities(states);
  std::vector<BiasValues> biases(states, BiasValues::Zero());
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  backend::LeastSquaresProblem problem;
  std::vector<int> pose_ids, velocity_ids, bias_ids;
  for (int k = 0; k < states; ++k) {
    const NavState s = truth.state(k * period);
    const core::SE3 perturbed =
        k == 0 ? s.T_world_body
               : s.T_world_body * core::SE3::exp((Vector6() << u(rng), u(rng), u(rng), u(rng), u(rng), u(rng)).finished() * 0.2);
    backend::se3_to_values(perturbed, poses[k].data());
    velocities[k] = s.v_world_mps;
    if (k > 0) velocities[k] += Vector3(u(rng), u(rng), u(rng)) * 0.3;
    pose_ids.push_back(problem.add_variable(poses[k].data(), backend::se3_manifold()));
    velocity_ids.push_back(problem.add_variable(velocities[k].data(), backend::euclidean_manifold(3)));
    bias_ids.push_back(problem.add_variable(biases[k].data(), backend::euclidean_manifold(6)));
  }
  problem.add_factor(std::make_unique<PosePriorFactor>(truth.state(0).T_world_body, Matrix6::Identity() * 1e-8),
                     {pose_ids[0]});
  problem.add_factor(std::make_unique<VectorPriorFactor<3>>(truth.v(0), Matrix3::Identity() * 1e-8), {velocity_ids[0]});
  problem.add_factor(std::make_unique<VectorPriorFactor<6>>(BiasValues::Zero(), Eigen::Matrix<double, 6, 6>::Identity() * 1e-8),
                     {bias_ids[0]});
  for (int k = 0; k + 1 < states; ++k) {
    problem.add_factor(std::make_unique<ImuFactor>(integrate_truth(truth, k * period, (k + 1) * period, dt), gravity_z_up()),
                       {pose_ids[k], velocity_ids[k], pose_ids[k + 1], velocity_ids[k + 1], bias_ids[k]});
    problem.add_factor(std::make_unique<BiasRandomWalkFactor>(noise, period), {bias_ids[k], bias_ids[k + 1]});
  }
  backend::LeastSquaresOptions options;
  options.linear_solver = backend::LinearSolverType::kSparseNormalCholesky;
  options.threads = 1;
  const auto summary = backend::solve(problem, options);
  ASSERT_TRUE(summary.is_solution_usable()) << summary.brief_report();
  for (int k = 1; k < states; ++k) {
    const StateError e = error_of({backend::se3_from_values(poses[k].data()), velocities[k]}, truth.state(k * period));
    // 1 kHz zero-order hold over up to 2 s: millimetres (ConvergesToClosedFormMotionAtFirstOrder).
    EXPECT_LT(e.rotation_rad, 5e-3) << k;
    EXPECT_LT(e.position_m, 2e-2) << k;
    EXPECT_LT(e.velocity_mps, 2e-2) << k;
  }
}

// The IMU factor on a camera's poses (a visual-inertial bundle adjustment's): its residual is the
// IMU factor's at the body poses T_world_camera T_camera_body, and its Jacobians on the camera poses
// match central differences; 1,000 random cases with fast rotation (up to 15 rad/s) and random
// extrinsics.
TEST(SensorPoseImuFactor, ResidualIsTheBodysAndJacobiansMatchNumeric) {
  std::mt19937 rng(40);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto random3 = [&](double scale) -> Vector3 { return Vector3(u(rng), u(rng), u(rng)) * scale; };
  const auto random_pose = [&](double metres) -> core::SE3 { return core::SE3(core::SO3::exp(random3(M_PI)), random3(metres)); };
  double worst = 0.0;
  for (int trial = 0; trial < 1000; ++trial) {
    const PreintegratedImu pim = random_preintegration(rng, random3);
    const core::SE3 T_body_camera = random_pose(0.3);
    const ImuFactor body_factor(pim, gravity_z_up());
    const SensorPoseImuFactor factor(body_factor, T_body_camera);
    const core::SE3 T_world_camera_i = random_pose(20.0), T_world_camera_j = random_pose(20.0);
    double pose_i[7], pose_j[7], body_i[7], body_j[7];
    backend::se3_to_values(T_world_camera_i, pose_i);
    backend::se3_to_values(T_world_camera_j, pose_j);
    backend::se3_to_values(T_world_camera_i * T_body_camera.inverse(), body_i);
    backend::se3_to_values(T_world_camera_j * T_body_camera.inverse(), body_j);
    Vector3 v_i = random3(5.0), v_j = random3(5.0);
    BiasValues bias = to_values(pim.bias_linearisation()) + (BiasValues() << random3(0.01), random3(0.1)).finished();
    double* values[5] = {pose_i, v_i.data(), pose_j, v_j.data(), bias.data()};
    const double* body_values[5] = {body_i, v_i.data(), body_j, v_j.data(), bias.data()};
    Vector9 r, r_body;
    ASSERT_TRUE(factor.evaluate(values, r.data(), nullptr));
    ASSERT_TRUE(body_factor.evaluate(body_values, r_body.data(), nullptr));
    ASSERT_LT((r - r_body).cwiseAbs().maxCoeff(), 1e-7 * (1.0 + r_body.cwiseAbs().maxCoeff()));
    const std::vector<const backend::Manifold*> manifolds = {&backend::se3_manifold(), &backend::euclidean_manifold(3), &backend::se3_manifold(),
                                                             &backend::euclidean_manifold(3), &backend::euclidean_manifold(6)};
    const double error = imu_jacobian_error(factor, values, manifolds, {0, 2});
    worst = std::max(worst, error);
    ASSERT_LT(error, 1e-5) << "trial " << trial;
  }
  RecordProperty("worst_relative_difference", std::to_string(worst));
}

// The LiDAR odometry factor (a pose measured through an extrinsic) and the gravity magnitude
// factor against central differences.
TEST(PosePriorFactor, JacobianThroughAnExtrinsicMatchesNumeric) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto random6 = [&]() -> Vector6 { return (Vector6() << u(rng), u(rng), u(rng), u(rng), u(rng), u(rng)).finished(); };
  for (int trial = 0; trial < 200; ++trial) {
    const core::SE3 T_body_sensor = core::SE3::exp(random6());
    const core::SE3 T_world_body = core::SE3::exp(3.0 * random6());
    const core::SE3 Z = T_world_body * T_body_sensor * core::SE3::exp(0.3 * random6());
    Matrix6 A = Matrix6::Random();
    const PosePriorFactor factor(Z, A * A.transpose() + Matrix6::Identity(), T_body_sensor);
    double pose[7];
    backend::se3_to_values(T_world_body, pose);
    const double* values[1] = {pose};
    Eigen::Matrix<double, 6, 6, Eigen::RowMajor> J;
    double* jacobians[1] = {J.data()};
    Vector6 r;
    ASSERT_TRUE(factor.evaluate(values, r.data(), jacobians));
    for (int col = 0; col < 6; ++col) {
      const double h = 1e-6;
      Vector6 delta = Vector6::Zero();
      double plus[7], minus[7];
      delta[col] = h;
      backend::se3_manifold().plus(pose, delta.data(), plus);
      delta[col] = -h;
      backend::se3_manifold().plus(pose, delta.data(), minus);
      Vector6 r_plus, r_minus;
      const double* vp[1] = {plus};
      const double* vm[1] = {minus};
      ASSERT_TRUE(factor.evaluate(vp, r_plus.data(), nullptr));
      ASSERT_TRUE(factor.evaluate(vm, r_minus.data(), nullptr));
      const Vector6 numeric = (r_plus - r_minus) / (2.0 * h);
      EXPECT_LT((numeric - J.col(col)).cwiseAbs().maxCoeff(), 1e-5 * (1.0 + numeric.cwiseAbs().maxCoeff()))
          << "trial " << trial << " column " << col;
    }
  }
  const GravityMagnitudeFactor gravity(9.81, 0.01);
  Vector3 g(1.0, -2.0, -9.5);
  const double* values[1] = {g.data()};
  double r = 0.0, J[3];
  double* jacobians[1] = {J};
  ASSERT_TRUE(gravity.evaluate(values, &r, jacobians));
  EXPECT_NEAR(r, (g.norm() - 9.81) / 0.01, 1e-9);
  EXPECT_NEAR(J[2], g.z() / g.norm() / 0.01, 1e-9);
}

TEST(BiasRandomWalkFactor, WhitensByTheRandomWalkOverTheInterval) {
  ImuNoise noise;
  noise.gyro_random_walk = 0.01;
  noise.accel_random_walk = 0.1;
  const BiasRandomWalkFactor factor(noise, 4.0);  // sigma = rw * 2
  BiasValues b_i = BiasValues::Zero(), b_j;
  b_j << 0.02, 0, 0, 0.2, 0, -0.4;
  const double* values[2] = {b_i.data(), b_j.data()};
  Eigen::Matrix<double, 6, 1> r;
  Eigen::Matrix<double, 6, 6, Eigen::RowMajor> J_i, J_j;
  double* jacobians[2] = {J_i.data(), J_j.data()};
  ASSERT_TRUE(factor.evaluate(values, r.data(), jacobians));
  EXPECT_NEAR(r[0], 1.0, 1e-12);
  EXPECT_NEAR(r[3], 1.0, 1e-12);
  EXPECT_NEAR(r[5], -2.0, 1e-12);
  EXPECT_NEAR(J_j(0, 0), 50.0, 1e-9);
  EXPECT_NEAR(J_i(4, 4), -5.0, 1e-9);
}

// Static initialisation on a synthetic still IMU: tilt, gyro bias and the accelerometer bias along
// gravity come back; a moving IMU is refused with the reason.
TEST(StaticInitialization, RecoversTiltAndGyroBias) {
  const core::SO3 R_world_body = core::SO3::from_rpy(0.1, -0.2, 0.0);
  const Vector3 gyro_bias(0.003, -0.002, 0.001);
  const double accel_bias_up = 0.05;
  std::mt19937 rng(1);
  std::normal_distribution<double> normal;
  std::vector<ImuSample> samples;
  const Vector3 up_body = R_world_body.inverse() * Vector3::UnitZ();
  for (int k = 0; k < 1000; ++k) {
    samples.push_back({core::Timestamp::from_nanoseconds(5'000'000LL * k),
                       gyro_bias + 0.002 * Vector3(normal(rng), normal(rng), normal(rng)),
                       up_body * (kStandardGravity + accel_bias_up) + 0.02 * Vector3(normal(rng), normal(rng), normal(rng))});
  }
  const StaticInitialization init = initialize_static(samples, StaticInitializationOptions{});
  ASSERT_TRUE(init.ok) << init.message;
  EXPECT_EQ(init.samples, 401);
  EXPECT_LT((init.gyro_bias_rad_s - gyro_bias).norm(), 5e-4);
  EXPECT_LT((init.R_world_body.inverse() * R_world_body).angle(), 2e-3);
  EXPECT_NEAR(init.accel_bias_along_gravity_mps2, accel_bias_up, 5e-3);

  for (std::size_t k = 0; k < samples.size(); ++k) samples[k].gyro_rad_s.z() += 0.5 * std::sin(0.05 * static_cast<double>(k));
  const StaticInitialization moving = initialize_static(samples, StaticInitializationOptions{});
  EXPECT_FALSE(moving.ok);
  EXPECT_NE(moving.message.find("not still"), std::string::npos) << moving.message;
}

}  // namespace
}  // namespace cairn::inertial
