// Sim(3) on the least-squares engine: the manifold's storage and retraction, the relative and
// prior factors' analytic Jacobians against central differences through the manifold on 2,000
// random configurations each, and a monocular-style loop whose odometry drifts in scale, closed
// by one loop-closure edge and solved with solve() (Strasdat et al., RSS 2010).

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "cairn/backend/sim3_factors.hpp"
#include "factor_jacobian_check.hpp"
#include "cairn/core/sim3.hpp"

namespace cairn::backend {
namespace {

using test::jacobian_error;

using core::Sim3;
using Tangent = Sim3::Tangent;


std::string sci(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", x);
  return buffer;
}

double unit(std::mt19937& rng) { return std::uniform_real_distribution<double>(-1.0, 1.0)(rng); }

Sim3 random_sim3(std::mt19937& rng) {
  const Eigen::Quaterniond q = Eigen::Quaterniond(unit(rng), unit(rng), unit(rng), unit(rng)).normalized();
  return Sim3(q, Eigen::Vector3d(3.0 * unit(rng), 3.0 * unit(rng), 3.0 * unit(rng)), std::exp(unit(rng)));
}

/// Rotation angle up to max_angle, translation up to `translation` per coordinate, sigma up to
/// max_sigma.
Tangent random_tangent(std::mt19937& rng, double max_angle, double translation, double max_sigma) {
  const Eigen::Vector3d axis = Eigen::Vector3d(unit(rng), unit(rng), unit(rng)).normalized();
  Tangent xi;
  xi << translation * unit(rng), translation * unit(rng), translation * unit(rng), max_angle * unit(rng) * axis,
      max_sigma * unit(rng);
  return xi;
}

std::vector<double> to_values(const Sim3& S) {
  std::vector<double> x(8);
  sim3_to_values(S, x.data());
  return x;
}

Sim3SquareRootInformation random_sqrt_information(std::mt19937& rng) {
  Sim3SquareRootInformation L = Sim3SquareRootInformation::Identity();
  for (int i = 0; i < 7; ++i) {
    for (int j = 0; j < 7; ++j) L(i, j) += 0.3 * unit(rng);
  }
  return L;
}

TEST(Sim3Manifold, StorageAndRetraction) {
  std::mt19937 rng(3);
  const Manifold& manifold = sim3_manifold();
  EXPECT_EQ(manifold.ambient_size(), 8);
  EXPECT_EQ(manifold.tangent_size(), 7);
  EXPECT_EQ(manifold.name(), "Sim(3)");
  for (int trial = 0; trial < 1000; ++trial) {
    const Sim3 S = random_sim3(rng);
    const std::vector<double> x = to_values(S);
    EXPECT_EQ(x[7], S.scale());
    EXPECT_EQ(sim3_from_values(x.data()).matrix(), S.matrix());
    // x [+] 0 = x, and x [+] delta = S exp(delta), in place as well.
    std::vector<double> y(8);
    const Tangent zero = Tangent::Zero();
    manifold.plus(x.data(), zero.data(), y.data());
    for (int i = 0; i < 8; ++i) EXPECT_NEAR(y[i], x[i], 1e-15);
    const Tangent delta = random_tangent(rng, 1.0, 1.0, 0.5);
    std::vector<double> z = x;
    manifold.plus(z.data(), delta.data(), z.data());
    const Eigen::Matrix4d expected = (S * Sim3::exp(delta)).matrix();
    EXPECT_LE((sim3_from_values(z.data()).matrix() - expected).cwiseAbs().maxCoeff(), 1e-14 * (1.0 + expected.norm()));
    EXPECT_GT(z[7], 0.0);
  }
}

// dr/d(delta_i), dr/d(delta_j) of the relative factor: random poses (scales e^[-1, 1]), random
// square-root informations, measurements from the true relative similarity perturbed by up to
// 2.5 rad, 1 m and sigma 1 (so the residual's angle stays away from pi, where log jumps), and
// every tenth measurement exact (residual ~0).
TEST(Sim3Factors, RelativeJacobiansMatchNumericDerivatives) {
  std::mt19937 rng(17);
  double worst = 0.0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Sim3 S_world_i = random_sim3(rng);
    const Sim3 S_world_j = random_sim3(rng);
    const Sim3 S_i_j = S_world_i.inverse() * S_world_j;
    const Sim3 Z = trial % 10 == 0 ? S_i_j : S_i_j * Sim3::exp(random_tangent(rng, 2.5, 1.0, 1.0));
    const Sim3RelativeFactor factor(Z, random_sqrt_information(rng));
    worst = std::max(worst, jacobian_error(factor, {to_values(S_world_i), to_values(S_world_j)},
                                           {&sim3_manifold(), &sim3_manifold()}));
  }
  RecordProperty("worst_relative_jacobian_error", sci(worst));
  // Central differences at h = 1e-6: truncation ~h^2, rounding ~1e-16 / h.
  EXPECT_LT(worst, 1e-7);
}

TEST(Sim3Factors, PriorJacobiansMatchNumericDerivatives) {
  std::mt19937 rng(19);
  double worst = 0.0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Sim3 S = random_sim3(rng);
    const Sim3 Z = trial % 10 == 0 ? S : S * Sim3::exp(random_tangent(rng, 2.5, 1.0, 1.0));
    const Sim3PriorFactor factor(Z, random_sqrt_information(rng));
    worst = std::max(worst, jacobian_error(factor, {to_values(S)}, {&sim3_manifold()}));
  }
  RecordProperty("worst_prior_jacobian_error", sci(worst));
  EXPECT_LT(worst, 1e-7);
}

TEST(Sim3Factors, ResidualIsTheWhitenedGeodesicError) {
  std::mt19937 rng(23);
  const Sim3 S_world_i = random_sim3(rng);
  const Sim3 S_world_j = random_sim3(rng);
  const Sim3 Z = random_sim3(rng);
  const Sim3SquareRootInformation L = random_sqrt_information(rng);
  const std::vector<double> xi = to_values(S_world_i), xj = to_values(S_world_j);
  const double* values[2] = {xi.data(), xj.data()};
  Tangent r;
  ASSERT_TRUE(Sim3RelativeFactor(Z, L).evaluate(values, r.data(), nullptr));
  const Tangent expected = L * (Z.inverse() * S_world_i.inverse() * S_world_j).log();
  EXPECT_LE((r - expected).cwiseAbs().maxCoeff(), 1e-13);
  // A scale of zero is outside the manifold: undefined, not an abort.
  std::vector<double> bad = xi;
  bad[7] = 0.0;
  values[0] = bad.data();
  EXPECT_FALSE(Sim3RelativeFactor(Z, L).evaluate(values, r.data(), nullptr));
}

// A monocular loop: 20 poses around a 10 m circle with a vertical wiggle, scale 1 throughout.
// The odometry says every step's relative similarity with scale 1.02 instead of 1 (2% scale drift
// per edge, 1.02^19 = 1.46 by the last pose) and a little rotation and translation noise; one
// loop-closure edge from the last pose to the first says the true relative Sim(3) (scale 1), as a
// loop detector with metric (e.g. stereo or map-point) alignment would. Starting from the drifted
// odometry chain with the first pose fixed, the Sim(3) pose graph spreads the loop's error, scale
// included, along the loop (Strasdat et al. 2010).
struct LoopResult {
  double max_before = 0.0, mean_before = 0.0, scale_before = 0.0;  // position errors in m
  double max_after = 0.0, mean_after = 0.0, scale_after = 0.0;
  LeastSquaresSummary summary;
};

constexpr int kLoopPoses = 20;
constexpr double kDriftPerEdge = 1.02;

/// The loop above, odometry with identity information (as ORB-SLAM's essential graph) and the
/// loop-closure edge with loop_sqrt_weight^2 times the identity.
LoopResult solve_drifting_loop(double loop_sqrt_weight) {
  constexpr double kRadius = 10.0;
  std::mt19937 rng(29);
  std::vector<Sim3> truth;
  for (int k = 0; k < kLoopPoses; ++k) {
    const double angle = 2.0 * std::numbers::pi * k / kLoopPoses;
    const Eigen::Quaterniond q(Eigen::AngleAxisd(angle + std::numbers::pi / 2.0, Eigen::Vector3d::UnitZ()));
    truth.emplace_back(q, Eigen::Vector3d(kRadius * std::cos(angle), kRadius * std::sin(angle), std::sin(3.0 * angle)),
                       1.0);
  }
  std::vector<Sim3> odometry;
  for (int k = 0; k + 1 < kLoopPoses; ++k) {
    const Sim3 relative = truth[k].inverse() * truth[k + 1];
    Tangent noise = random_tangent(rng, 0.01, 0.02, 0.0);
    noise(6) = std::log(kDriftPerEdge);
    odometry.push_back(relative * Sim3::exp(noise));
  }
  const Sim3 loop = truth[kLoopPoses - 1].inverse() * truth[0];

  // Start: the odometry chain from the (fixed, true) first pose.
  std::vector<std::vector<double>> values(kLoopPoses, std::vector<double>(8));
  Sim3 S = truth[0];
  sim3_to_values(S, values[0].data());
  for (int k = 0; k + 1 < kLoopPoses; ++k) {
    S = S * odometry[k];
    sim3_to_values(S, values[k + 1].data());
  }
  const auto position_errors = [&](double& max_error, double& mean_error) {
    max_error = 0.0;
    double sum = 0.0;
    for (int k = 0; k < kLoopPoses; ++k) {
      const double e = (sim3_from_values(values[k].data()).translation() - truth[k].translation()).norm();
      max_error = std::max(max_error, e);
      sum += e;
    }
    mean_error = sum / kLoopPoses;
  };
  LoopResult result;
  position_errors(result.max_before, result.mean_before);
  result.scale_before = values[kLoopPoses - 1][7];

  LeastSquaresProblem problem;
  std::vector<int> ids;
  for (auto& v : values) ids.push_back(problem.add_variable(v.data(), sim3_manifold()));
  problem.set_constant(ids[0]);
  const Sim3SquareRootInformation identity = Sim3SquareRootInformation::Identity();
  for (int k = 0; k + 1 < kLoopPoses; ++k) {
    problem.add_factor(std::make_unique<Sim3RelativeFactor>(odometry[k], identity), {ids[k], ids[k + 1]});
  }
  problem.add_factor(std::make_unique<Sim3RelativeFactor>(loop, loop_sqrt_weight * identity),
                     {ids[kLoopPoses - 1], ids[0]});
  LeastSquaresOptions options;
  options.linear_solver = LinearSolverType::kSparseNormalCholesky;
  options.threads = 1;
  options.function_tolerance = 1e-12;
  result.summary = solve(problem, options);
  position_errors(result.max_after, result.mean_after);
  result.scale_after = values[kLoopPoses - 1][7];
  return result;
}

/// The last pose's log-scale D if only the scale mattered: minimising sum_k (d_k - a)^2 + w D^2
/// over the 19 odometry increments d_k of the log-scale, D = sum_k d_k, a = ln 1.02 and
/// w = loop_sqrt_weight^2 the loop edge's weight, gives d_k = a - w D and D = 19 a / (1 + 19 w).
double predicted_last_log_scale(double loop_sqrt_weight) {
  const double a = std::log(kDriftPerEdge);
  const double w = loop_sqrt_weight * loop_sqrt_weight;
  return (kLoopPoses - 1) * a / (1.0 + (kLoopPoses - 1) * w);
}

void record(const LoopResult& r) {
  ::testing::Test::RecordProperty("max_position_error_before_m", std::to_string(r.max_before));
  ::testing::Test::RecordProperty("max_position_error_after_m", std::to_string(r.max_after));
  ::testing::Test::RecordProperty("mean_position_error_before_m", std::to_string(r.mean_before));
  ::testing::Test::RecordProperty("mean_position_error_after_m", std::to_string(r.mean_after));
  ::testing::Test::RecordProperty("last_scale_before", std::to_string(r.scale_before));
  ::testing::Test::RecordProperty("last_scale_after", std::to_string(r.scale_after));
  ::testing::Test::RecordProperty("initial_cost", std::to_string(r.summary.initial_cost));
  ::testing::Test::RecordProperty("final_cost", std::to_string(r.summary.final_cost));
  ::testing::Test::RecordProperty("iterations", std::to_string(r.summary.iterations));
}

TEST(Sim3PoseGraph, LoopClosureCorrectsScaleDrift) {
  const LoopResult r = solve_drifting_loop(1.0);
  ASSERT_TRUE(r.summary.is_solution_usable()) << r.summary.message;
  record(r);
  // Measured with this seed: position error max 4.63 m / mean 2.25 m before, 0.284 m / 0.146 m
  // after; last scale 1.457 before, 1.0185 after; cost 7.60 -> 0.00356 in 6 iterations. With
  // equal weights the loop's log-scale error 19 ln 1.02 is shared by its 20 edges, which leaves
  // the last pose at about 1.02^(19/20) = 1.019: the drift is cut to 1/20, not removed. Bounds
  // ~20% above the measured values.
  EXPECT_NEAR(r.scale_before, std::pow(kDriftPerEdge, kLoopPoses - 1), 1e-12);
  EXPECT_GT(r.max_before, 4.0);
  EXPECT_GT(r.mean_before, 2.0);
  EXPECT_LT(r.max_after, 0.35);
  EXPECT_LT(r.mean_after, 0.18);
  EXPECT_NEAR(r.scale_after, 1.0, 0.022);
  // 0.01829 against the scale-only prediction 0.01881 (the translations pull a little too).
  EXPECT_NEAR(std::log(r.scale_after), predicted_last_log_scale(1.0), 1e-3);
  EXPECT_LT(r.summary.final_cost, 0.0045);
}

// The same loop with the loop-closure edge 100 times as informative as an odometry edge: the
// odometry then absorbs nearly all of the inconsistency and the last scale returns to ~1.
TEST(Sim3PoseGraph, AConfidentLoopClosureRemovesTheScaleDrift) {
  const LoopResult r = solve_drifting_loop(10.0);
  ASSERT_TRUE(r.summary.is_solution_usable()) << r.summary.message;
  record(r);
  // Measured with this seed: position error max 0.191 m / mean 0.082 m after (4.63 / 2.25
  // before); last scale 1.000203 (1.457 before); cost 760 -> 0.00374 in 6 iterations. Bounds ~20%
  // above the measured values.
  EXPECT_LT(r.max_after, 0.23);
  EXPECT_LT(r.mean_after, 0.1);
  EXPECT_NEAR(r.scale_after, 1.0, 2.5e-4);
  // 2.03e-4 against the scale-only prediction 1.98e-4.
  EXPECT_NEAR(std::log(r.scale_after), predicted_last_log_scale(10.0), 2e-5);
  EXPECT_LT(r.summary.final_cost, 0.0045);
}

}  // namespace
}  // namespace cairn::backend
