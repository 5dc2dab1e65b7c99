// The one trust-region minimiser (backend/trust_region.hpp) on a model small enough to check by
// hand: Rosenbrock's function as least squares, r = (10 (y - x^2), 1 - x), minimum 0 at (1, 1)
// (Rosenbrock 1960; the standard start (-1.2, 1), More, Garbow & Hillstrom 1981, problem 1).
// Then its rules one by one (invalid steps, inexact steps, interruption), and the general
// engine's Gauss-Newton and dog-leg on bundle adjustment against its LM.

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "cairn/backend/least_squares.hpp"
#include "cairn/backend/reprojection_factors.hpp"
#include "cairn/backend/trust_region.hpp"

namespace cairn::backend {
namespace {

/// Cost 1/2 ||r||^2 with r = (10 (y - x^2), 1 - x); dense Gauss-Newton model H = J^T J,
/// D = diag(J^T J) as Ceres' LM.
class Rosenbrock : public TrustRegionModel {
 public:
  explicit Rosenbrock(Eigen::Vector2d x) : x_(std::move(x)) {}

  static Eigen::Vector2d residual(const Eigen::Vector2d& x) { return {10.0 * (x.y() - x.x() * x.x()), 1.0 - x.x()}; }
  static Eigen::Matrix2d jacobian(const Eigen::Vector2d& x) {
    Eigen::Matrix2d J;
    J << -20.0 * x.x(), 10.0, -1.0, 0.0;
    return J;
  }
  static double cost(const Eigen::Vector2d& x) { return 0.5 * residual(x).squaredNorm(); }

  bool start(double* cost_out, std::string* /*error*/) override {
    linearize();
    *cost_out = cost(x_);
    return true;
  }
  double gradient_max_norm() override { return g_.cwiseAbs().maxCoeff(); }
  double values_norm() override { return x_.norm(); }
  StepQuality compute_step(double lambda, Eigen::VectorXd& step, double* predicted, TrustRegionIteration& /*it*/) override {
    lambdas.push_back(lambda);
    if (fail_steps > 0) {
      --fail_steps;
      return StepQuality::kFailed;
    }
    const Eigen::Matrix2d A = H_ + lambda * Eigen::Matrix2d(H_.diagonal().asDiagonal());
    const Eigen::LDLT<Eigen::Matrix2d> ldlt(A);
    if (ldlt.info() != Eigen::Success || ldlt.vectorD().minCoeff() <= 0.0) return StepQuality::kFailed;
    step = ldlt.solve(-g_);
    if (inexact_bad_steps > 0 || exact_bad_steps > 0) {  // a wild step: rejected by the ratio test
      const bool inexact = inexact_bad_steps > 0;
      --(inexact ? inexact_bad_steps : exact_bad_steps);
      step *= 100.0;
      *predicted = model_decrease(step);
      return inexact ? StepQuality::kInexact : StepQuality::kExact;
    }
    *predicted = model_decrease(step);
    return StepQuality::kExact;
  }
  const Eigen::VectorXd& gradient() override { return g_; }
  double curvature(const Eigen::VectorXd& v) override { return v.dot(H_ * v); }
  double model_decrease(const Eigen::VectorXd& step) override { return -g_.dot(step) - 0.5 * curvature(step); }
  bool evaluate_trial(const Eigen::VectorXd& step, double* cost_out, TrustRegionIteration& /*it*/) override {
    trial_ = x_ + step;
    *cost_out = cost(trial_);
    return true;
  }
  void accept_trial(double old_cost, double new_cost, bool /*final*/, TrustRegionIteration& /*it*/) override {
    EXPECT_EQ(old_cost, cost(x_));
    EXPECT_EQ(new_cost, cost(trial_));
    x_ = trial_;
    linearize();
  }
  void reject_trial(StepQuality quality) override { rejected.push_back(quality); }

  const Eigen::Vector2d& x() const { return x_; }
  std::vector<double> lambdas;               // lambda of every compute_step call
  std::vector<StepQuality> rejected;         // quality of every rejected step
  int fail_steps = 0;                        // the next compute_step calls that fail
  int inexact_bad_steps = 0;                 // the next steps that are wild and inexact
  int exact_bad_steps = 0;                   // the next steps that are wild and claimed exact

 private:
  void linearize() {
    const Eigen::Matrix2d J = jacobian(x_);
    H_ = J.transpose() * J;
    g_ = J.transpose() * residual(x_);
  }
  Eigen::Vector2d x_, trial_;
  Eigen::Matrix2d H_;
  Eigen::VectorXd g_;
};

TrustRegionOptions tight(Algorithm algorithm) {
  TrustRegionOptions options;
  options.algorithm = algorithm;
  options.max_iterations = 200;
  options.function_tolerance = 1e-20;
  options.gradient_tolerance = 1e-12;
  options.parameter_tolerance = 1e-14;
  options.initial_trust_region_radius = algorithm == Algorithm::kDogleg ? 1.0 : 1e4;
  return options;
}

class EveryAlgorithm : public ::testing::TestWithParam<Algorithm> {};

TEST_P(EveryAlgorithm, SolvesRosenbrock) {
  // Gauss-Newton's first step from the standard start overshoots to (1, -3.84), cost 1171
  // (below); from (0.5, 0.5) its steps go down.
  const bool gauss_newton = GetParam() == Algorithm::kGaussNewton;
  Rosenbrock model(gauss_newton ? Eigen::Vector2d(0.5, 0.5) : Eigen::Vector2d(-1.2, 1.0));
  const TrustRegionResult result = minimize(model, tight(GetParam()));
  EXPECT_EQ(result.termination, TerminationType::kConvergence) << result.message;
  // 1/2 (4.4^2 + 2.2^2), or 1/2 (2.5^2 + 0.5^2)
  EXPECT_NEAR(result.initial_cost, gauss_newton ? 3.25 : 12.1, 1e-12);
  EXPECT_LT(result.final_cost, 1e-20) << result.message;
  EXPECT_NEAR(model.x().x(), 1.0, 1e-9);
  EXPECT_NEAR(model.x().y(), 1.0, 1e-9);
  // The log: the cost never rises, accepted steps lower it, the counts add up.
  ASSERT_EQ(static_cast<int>(result.iteration_log.size()), result.iterations);
  double previous = result.initial_cost;
  int accepted = 0;
  for (const TrustRegionIteration& it : result.iteration_log) {
    EXPECT_LE(it.cost, previous);
    if (it.step_accepted) {
      ++accepted;
    } else {
      EXPECT_EQ(it.cost, previous);
    }
    previous = it.cost;
  }
  EXPECT_EQ(accepted, result.successful_iterations);
  EXPECT_EQ(result.final_cost, result.iteration_log.back().cost);
}

INSTANTIATE_TEST_SUITE_P(TrustRegion, EveryAlgorithm,
                         ::testing::Values(Algorithm::kLevenbergMarquardt, Algorithm::kGaussNewton, Algorithm::kDogleg));

TEST(TrustRegion, GaussNewtonStopsWhenItsStepRaisesTheCost) {
  Rosenbrock model({-1.2, 1.0});
  const TrustRegionResult result = minimize(model, tight(Algorithm::kGaussNewton));
  EXPECT_EQ(result.termination, TerminationType::kConvergence);
  EXPECT_NE(result.message.find("did not decrease"), std::string::npos) << result.message;
  EXPECT_EQ(result.iterations, 1);
  EXPECT_NEAR(result.iteration_log[0].cost_change, 12.1 - 0.5 * 48.4 * 48.4, 1e-9);
  EXPECT_EQ(model.x(), Eigen::Vector2d(-1.2, 1.0));
}

TEST(TrustRegion, LevenbergMarquardtFollowsNielsensUpdate) {
  Rosenbrock model({-1.2, 1.0});
  TrustRegionOptions options = tight(Algorithm::kLevenbergMarquardt);
  const TrustRegionResult result = minimize(model, options);
  ASSERT_GE(result.iteration_log.size(), 3U);
  // After an accepted step lambda is multiplied by max(1/3, 1 - (2 rho - 1)^3); after a
  // rejected one by nu = 2, 4, 8, ... (reset to 2 by an acceptance).
  double nu = 2.0;
  for (std::size_t k = 0; k + 1 < result.iteration_log.size(); ++k) {
    const TrustRegionIteration& it = result.iteration_log[k];
    double expected = 0.0;
    if (it.step_accepted) {
      const double t = 2.0 * it.relative_decrease - 1.0;
      expected = std::max(1e-16, it.lambda * std::max(1.0 / 3.0, 1.0 - t * t * t));
      nu = 2.0;
    } else {
      expected = it.lambda * nu;
      nu *= 2.0;
    }
    EXPECT_DOUBLE_EQ(result.iteration_log[k + 1].lambda, expected) << "iteration " << it.iteration;
    EXPECT_DOUBLE_EQ(it.trust_region_radius, 1.0 / it.lambda);
  }
  EXPECT_DOUBLE_EQ(result.iteration_log.front().lambda, 1e-4);  // 1 / initial radius
}

TEST(TrustRegion, InvalidStepsRaiseTheDampingThenFail) {
  Rosenbrock model({-1.2, 1.0});
  model.fail_steps = 1000;
  TrustRegionOptions options = tight(Algorithm::kLevenbergMarquardt);
  options.max_consecutive_invalid_steps = 5;
  const TrustRegionResult result = minimize(model, options);
  EXPECT_EQ(result.termination, TerminationType::kFailure);
  EXPECT_EQ(result.iterations, 5);
  ASSERT_EQ(model.lambdas.size(), 5U);
  for (std::size_t k = 1; k < model.lambdas.size(); ++k) EXPECT_GT(model.lambdas[k], model.lambdas[k - 1]);
  EXPECT_EQ(result.final_cost, result.initial_cost);

  // A few failures are survived: the damping grows and the solve goes on to the minimum.
  Rosenbrock recovering({-1.2, 1.0});
  recovering.fail_steps = 3;
  const TrustRegionResult recovered = minimize(recovering, options);
  EXPECT_EQ(recovered.termination, TerminationType::kConvergence) << recovered.message;
  EXPECT_LT(recovered.final_cost, 1e-20);

  // Gauss-Newton and dog-leg have no damping to raise: the first failure ends the solve.
  for (const Algorithm algorithm : {Algorithm::kGaussNewton, Algorithm::kDogleg}) {
    Rosenbrock undamped({-1.2, 1.0});
    undamped.fail_steps = 1;
    const TrustRegionResult failed = minimize(undamped, tight(algorithm));
    EXPECT_EQ(failed.termination, TerminationType::kFailure) << to_string(algorithm);
    EXPECT_EQ(failed.iterations, 1);
  }
}

TEST(TrustRegion, ARejectedInexactStepKeepsTheDamping) {
  Rosenbrock model({-1.2, 1.0});
  model.inexact_bad_steps = 1;
  const TrustRegionResult result = minimize(model, tight(Algorithm::kLevenbergMarquardt));
  ASSERT_FALSE(model.rejected.empty());
  EXPECT_EQ(model.rejected.front(), StepQuality::kInexact);
  ASSERT_GE(model.lambdas.size(), 2U);
  EXPECT_EQ(model.lambdas[1], model.lambdas[0]);  // retried with the same lambda
  EXPECT_FALSE(result.iteration_log.front().step_accepted);
  EXPECT_LT(result.final_cost, 1e-20);

  // The same wild step claimed exact raises lambda.
  Rosenbrock exact({-1.2, 1.0});
  exact.exact_bad_steps = 1;
  const TrustRegionResult reference = minimize(exact, tight(Algorithm::kLevenbergMarquardt));
  ASSERT_GE(exact.lambdas.size(), 2U);
  EXPECT_GT(exact.lambdas[1], exact.lambdas[0]);
  EXPECT_EQ(exact.rejected.front(), StepQuality::kExact);
  EXPECT_LT(reference.final_cost, 1e-20);
}

TEST(TrustRegion, ShouldStopEndsAtTheLastAcceptedPoint) {
  Rosenbrock model({-1.2, 1.0});
  TrustRegionOptions options = tight(Algorithm::kLevenbergMarquardt);
  int polls = 0;
  options.should_stop = [&] { return ++polls > 3; };
  const TrustRegionResult result = minimize(model, options);
  EXPECT_EQ(result.termination, TerminationType::kInterrupted);
  EXPECT_EQ(result.iterations, 3);
  EXPECT_EQ(result.final_cost, Rosenbrock::cost(model.x()));
}

TEST(TrustRegion, GradientToleranceAtTheStartTakesNoStep) {
  Rosenbrock model({1.0, 1.0});
  const TrustRegionResult result = minimize(model, tight(Algorithm::kLevenbergMarquardt));
  EXPECT_EQ(result.termination, TerminationType::kConvergence);
  EXPECT_EQ(result.iterations, 0);
  EXPECT_TRUE(model.lambdas.empty());
}

TEST(TrustRegion, ANonFiniteStartIsAFailureNotASolve) {
  Rosenbrock model({std::numeric_limits<double>::quiet_NaN(), 1.0});
  const TrustRegionResult result = minimize(model, tight(Algorithm::kLevenbergMarquardt));
  EXPECT_EQ(result.termination, TerminationType::kFailure);
  EXPECT_NE(result.message.find("not finite"), std::string::npos) << result.message;
  EXPECT_EQ(result.iterations, 0);
}

TEST(TrustRegion, InvalidOptionsAreNamed) {
  TrustRegionOptions options;
  options.max_iterations = 0;
  options.max_trust_region_radius = 1.0;
  std::string error;
  EXPECT_FALSE(options.is_valid(&error));
  EXPECT_NE(error.find("max_iterations"), std::string::npos) << error;
  EXPECT_NE(error.find("max_trust_region_radius"), std::string::npos) << error;
}

// The general engine with each algorithm of the minimiser on a small noisy bundle adjustment:
// the same minimum as LM (the problem is well conditioned from a close start).
TEST(TrustRegion, EngineGaussNewtonAndDoglegReachLevenbergMarquardtsMinimum) {
  const PinholeIntrinsics K{500.0, 500.0, 320.0, 240.0};
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.5);
  constexpr int kCameras = 4;
  constexpr int kPoints = 25;
  std::vector<std::array<double, 7>> poses_true;
  for (int c = 0; c < kCameras; ++c) {  // a row of cameras looking along +z
    poses_true.push_back({0.0, 0.0, 0.0, 1.0, 0.5 * c, 0.1 * unit(rng), 0.0});
  }
  std::vector<Eigen::Vector3d> points_true;
  for (int p = 0; p < kPoints; ++p) points_true.emplace_back(2.0 * unit(rng), 1.5 * unit(rng), 6.0 + 2.0 * unit(rng));
  struct Observation {
    int camera, point;
    double u, v;
  };
  std::vector<Observation> observations;
  for (int c = 0; c < kCameras; ++c) {
    for (int p = 0; p < kPoints; ++p) {
      const Eigen::Vector3d q = points_true[p] - Eigen::Vector3d(poses_true[c][4], poses_true[c][5], poses_true[c][6]);
      observations.push_back({c, p, K.fx * q.x() / q.z() + K.cx + noise(rng), K.fy * q.y() / q.z() + K.cy + noise(rng)});
    }
  }
  std::vector<double> final_costs;
  std::vector<std::vector<double>> solutions;
  for (const Algorithm algorithm : {Algorithm::kLevenbergMarquardt, Algorithm::kGaussNewton, Algorithm::kDogleg}) {
    std::vector<std::array<double, 7>> poses = poses_true;
    std::vector<Eigen::Vector3d> points = points_true;
    std::mt19937 perturb(5);
    for (int c = 2; c < kCameras; ++c) {
      const double delta[6] = {0.05 * unit(perturb), 0.05 * unit(perturb), 0.05 * unit(perturb),
                               0.01 * unit(perturb), 0.01 * unit(perturb), 0.01 * unit(perturb)};
      se3_manifold().plus(poses[c].data(), delta, poses[c].data());
    }
    for (auto& point : points) point += 0.05 * Eigen::Vector3d(unit(perturb), unit(perturb), unit(perturb));
    LeastSquaresProblem problem;
    for (auto& pose : poses) problem.add_variable(pose.data(), se3_manifold());
    problem.set_constant(0);
    problem.set_constant(1);
    for (auto& point : points) problem.add_variable(point.data(), euclidean_manifold(3), VariableGroup::kEliminate);
    for (const Observation& o : observations) {
      problem.add_factor(std::make_unique<PinholeReprojectionFactor>(K, o.u, o.v), {o.camera, kCameras + o.point});
    }
    LeastSquaresOptions options;
    options.algorithm = algorithm;
    options.initial_trust_region_radius = algorithm == Algorithm::kDogleg ? 1.0 : 1e4;
    options.function_tolerance = 1e-14;
    options.parameter_tolerance = 1e-14;
    options.max_iterations = 100;
    options.threads = 1;
    const LeastSquaresSummary summary = solve(problem, options);
    ASSERT_TRUE(summary.is_solution_usable()) << to_string(algorithm) << ": " << summary.message;
    EXPECT_EQ(summary.algorithm, algorithm);
    EXPECT_LT(summary.final_cost, summary.initial_cost);
    final_costs.push_back(summary.final_cost);
    std::vector<double> flat;
    for (const auto& point : points) flat.insert(flat.end(), point.data(), point.data() + 3);
    solutions.push_back(flat);
  }
  for (std::size_t k = 1; k < final_costs.size(); ++k) {
    EXPECT_NEAR(final_costs[k], final_costs[0], 1e-8 * final_costs[0]) << "algorithm " << k;
    for (std::size_t i = 0; i < solutions[0].size(); ++i) EXPECT_NEAR(solutions[k][i], solutions[0][i], 1e-6);
  }
}

}  // namespace
}  // namespace cairn::backend
