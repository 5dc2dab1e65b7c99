// The least-squares engine (backend/least_squares.hpp): convergence on synthetic bundle
// adjustment with known ground truth, agreement of its three linear solvers, constant variables,
// robust kernels, failures reported in the summary, and Ceres' published iteration costs on the
// BAL problem its documentation runs.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdlib>
#include <random>
#include <vector>

#include "cairn/backend/bundle_adjustment.hpp"
#include "cairn/backend/least_squares.hpp"
// Included together on purpose: both once declared backend::MarginalCovariances (issue 36).
#include "cairn/backend/covariance.hpp"
#include "cairn/backend/reprojection_factors.hpp"
#include "cairn/io/bal.hpp"
#include "../test_data.hpp"

namespace cairn::backend {
namespace {

/// Cameras on a circle of radius 6 m looking at the origin, points in a 2 m cube around it.
struct SyntheticScene {
  PinholeIntrinsics K{500.0, 500.0, 320.0, 240.0};
  std::vector<std::vector<double>> poses_true, points_true;
  std::vector<std::vector<double>> poses, points;  // the estimate (perturbed)
  struct Observation {
    int camera, point;
    double u, v;
  };
  std::vector<Observation> observations;

  SyntheticScene(int cameras, int point_count, double pixel_noise, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::normal_distribution<double> noise(0.0, 1.0);
    for (int c = 0; c < cameras; ++c) {
      const double a = 2.0 * M_PI * c / cameras;
      const Eigen::Vector3d position(6.0 * std::cos(a), 6.0 * std::sin(a), 0.5 * unit(rng));
      // Camera z axis towards the origin, x axis horizontal.
      const Eigen::Vector3d z = -position.normalized();
      const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
      Eigen::Matrix3d R_world_camera;
      R_world_camera << x, z.cross(x), z;
      const Eigen::Quaterniond q(R_world_camera);
      poses_true.push_back({q.x(), q.y(), q.z(), q.w(), position.x(), position.y(), position.z()});
    }
    for (int p = 0; p < point_count; ++p) points_true.push_back({2.0 * unit(rng), 2.0 * unit(rng), 2.0 * unit(rng)});
    for (int c = 0; c < cameras; ++c) {
      const auto& pose = poses_true[c];
      const Eigen::Quaterniond q(pose[3], pose[0], pose[1], pose[2]);
      const Eigen::Vector3d t(pose[4], pose[5], pose[6]);
      for (int p = 0; p < point_count; ++p) {
        const Eigen::Vector3d p_camera = q.conjugate() * (Eigen::Vector3d(points_true[p].data()) - t);
        observations.push_back({c, p, K.fx * p_camera.x() / p_camera.z() + K.cx + pixel_noise * noise(rng),
                                K.fy * p_camera.y() / p_camera.z() + K.cy + pixel_noise * noise(rng)});
      }
    }
    poses = poses_true;
    points = points_true;
    for (std::size_t c = 2; c < poses.size(); ++c) {  // cameras 0 and 1 fix the gauge (7 DoF)
      const double delta[6] = {0.1 * unit(rng), 0.1 * unit(rng), 0.1 * unit(rng),
                               0.03 * unit(rng), 0.03 * unit(rng), 0.03 * unit(rng)};
      se3_manifold().plus(poses[c].data(), delta, poses[c].data());
    }
    for (auto& point : points) {
      for (double& value : point) value += 0.1 * unit(rng);
    }
  }

  LeastSquaresProblem problem(FactorLoss loss = {}) {
    LeastSquaresProblem ls;
    for (auto& pose : poses) ls.add_variable(pose.data(), se3_manifold());
    ls.set_constant(0);
    ls.set_constant(1);
    const int first_point = static_cast<int>(poses.size());
    for (auto& point : points) ls.add_variable(point.data(), euclidean_manifold(3), VariableGroup::kEliminate);
    for (const Observation& o : observations) {
      ls.add_factor(std::make_unique<PinholeReprojectionFactor>(K, o.u, o.v), {o.camera, first_point + o.point}, loss);
    }
    return ls;
  }
};

double max_point_error(const SyntheticScene& scene) {
  double worst = 0.0;
  for (std::size_t p = 0; p < scene.points.size(); ++p) {
    for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(scene.points[p][k] - scene.points_true[p][k]));
  }
  return worst;
}

class EveryLinearSolver : public ::testing::TestWithParam<LinearSolverType> {};

TEST_P(EveryLinearSolver, NoiseFreeBundleAdjustmentRecoversTheScene) {
  SyntheticScene scene(6, 40, 0.0, 3);
  LeastSquaresProblem problem = scene.problem();
  LeastSquaresOptions options;
  options.linear_solver = GetParam();
  options.function_tolerance = 1e-14;
  options.parameter_tolerance = 1e-14;
  options.cg_tolerance = 1e-6;
  const LeastSquaresSummary summary = solve(problem, options);
  ASSERT_TRUE(summary.is_solution_usable()) << summary.message;
  EXPECT_GT(summary.initial_cost, 1e3);
  EXPECT_LT(summary.final_cost, 1e-12) << summary.brief_report();
  EXPECT_LT(max_point_error(scene), 1e-6);
  EXPECT_EQ(summary.eliminated_variables, GetParam() == LinearSolverType::kSparseNormalCholesky ? 0 : 40);
  EXPECT_NEAR(summary.final_cost, evaluate_cost(problem), 1e-12);
}

INSTANTIATE_TEST_SUITE_P(LeastSquares, EveryLinearSolver,
                         ::testing::Values(LinearSolverType::kSparseNormalCholesky, LinearSolverType::kSparseSchur,
                                           LinearSolverType::kIterativeSchur));

TEST(LeastSquares, TheThreeLinearSolversReachTheSameMinimumWithNoise) {
  std::vector<double> costs;
  std::vector<std::vector<std::vector<double>>> solutions;
  for (const LinearSolverType type : {LinearSolverType::kSparseNormalCholesky, LinearSolverType::kSparseSchur,
                                      LinearSolverType::kIterativeSchur}) {
    SyntheticScene scene(5, 30, 1.0, 5);
    LeastSquaresProblem problem = scene.problem();
    LeastSquaresOptions options;
    options.linear_solver = type;
    options.function_tolerance = 1e-15;
    options.parameter_tolerance = 1e-14;
    options.cg_tolerance = 1e-8;
    options.max_iterations = 100;
    const LeastSquaresSummary summary = solve(problem, options);
    ASSERT_TRUE(summary.is_solution_usable()) << summary.message;
    costs.push_back(summary.final_cost);
    solutions.push_back(scene.points);
  }
  // 1 px noise on 150 observations: cost about 1/2 * (300 - 119 unknowns) px^2.
  EXPECT_GT(costs[0], 20.0);
  EXPECT_LT(costs[0], 200.0);
  for (std::size_t k = 1; k < costs.size(); ++k) {
    EXPECT_NEAR(costs[k], costs[0], 1e-7 * costs[0]);
    for (std::size_t p = 0; p < solutions[0].size(); ++p) {
      for (int i = 0; i < 3; ++i) EXPECT_NEAR(solutions[k][p][i], solutions[0][p][i], 1e-5);
    }
  }
}

TEST(LeastSquares, ConstantVariablesAreNotMoved) {
  SyntheticScene scene(5, 20, 0.5, 9);
  const std::vector<double> camera0 = scene.poses[0];
  const std::vector<double> camera1 = scene.poses[1];
  LeastSquaresProblem problem = scene.problem();
  const LeastSquaresSummary summary = solve(problem, LeastSquaresOptions{});
  ASSERT_TRUE(summary.is_solution_usable());
  EXPECT_EQ(scene.poses[0], camera0);
  EXPECT_EQ(scene.poses[1], camera1);
  EXPECT_LT(summary.final_cost, summary.initial_cost);
}

TEST(LeastSquares, HuberKernelBoundsAnOutliersInfluence) {
  // One observation moved by 200 px: with least squares it drags its point; with Huber (scale
  // 2 px) the point stays near the truth, and the reported cost is 1/2 sum rho.
  double error_plain = 0.0, error_huber = 0.0;
  for (const bool robust : {false, true}) {
    SyntheticScene scene(6, 20, 0.0, 13);
    scene.observations[0].u += 200.0;
    FactorLoss loss;
    if (robust) loss = {RobustKernel::kHuber, 2.0};
    LeastSquaresProblem problem = scene.problem(loss);
    LeastSquaresOptions options;
    options.function_tolerance = 1e-12;
    const LeastSquaresSummary summary = solve(problem, options);
    ASSERT_TRUE(summary.is_solution_usable());
    EXPECT_NEAR(summary.final_cost, evaluate_cost(problem), 1e-9 * (1.0 + summary.final_cost));
    const int p = scene.observations[0].point;
    const double error = (Eigen::Vector3d(scene.points[p].data()) - Eigen::Vector3d(scene.points_true[p].data())).norm();
    (robust ? error_huber : error_plain) = error;
  }
  EXPECT_LT(error_huber, 0.2 * error_plain);
}

/// A factor on two points: the Schur solvers must refuse it (one eliminated variable per factor).
class PointDistance final : public Factor {
 public:
  int residual_size() const override { return 3; }
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override {
    for (int i = 0; i < 3; ++i) residual[i] = values[1][i] - values[0][i];
    if (jacobians != nullptr) {
      for (int k = 0; k < 2; ++k) {
        if (jacobians[k] == nullptr) continue;
        for (int i = 0; i < 9; ++i) jacobians[k][i] = (i % 4 == 0) ? (k == 0 ? -1.0 : 1.0) : 0.0;
      }
    }
    return true;
  }
};

TEST(LeastSquares, FailuresAreReportedNotThrown) {
  double a[3] = {0, 0, 0}, b[3] = {1, 2, 3};
  LeastSquaresProblem problem;
  const int va = problem.add_variable(a, euclidean_manifold(3), VariableGroup::kEliminate);
  const int vb = problem.add_variable(b, euclidean_manifold(3), VariableGroup::kEliminate);
  problem.add_factor(std::make_unique<PointDistance>(), {va, vb});
  LeastSquaresSummary summary = solve(problem, LeastSquaresOptions{});
  EXPECT_EQ(summary.termination, LeastSquaresTermination::kFailure);
  EXPECT_NE(summary.message.find("two eliminated variables"), std::string::npos) << summary.message;

  // The same problem without elimination solves (b - a -> 0 with a held).
  LeastSquaresOptions normal;
  normal.linear_solver = LinearSolverType::kSparseNormalCholesky;
  problem.set_constant(va);
  summary = solve(problem, normal);
  ASSERT_TRUE(summary.is_solution_usable()) << summary.message;
  EXPECT_NEAR(b[0], 0.0, 1e-9);

  LeastSquaresOptions invalid;
  invalid.max_iterations = 0;
  invalid.cg_tolerance = 2.0;
  summary = solve(problem, invalid);
  EXPECT_EQ(summary.termination, LeastSquaresTermination::kFailure);
  EXPECT_NE(summary.message.find("max_iterations"), std::string::npos);
  EXPECT_NE(summary.message.find("cg_tolerance"), std::string::npos);

  b[0] = std::nan("");
  problem.set_constant(va, false);
  summary = solve(problem, normal);
  EXPECT_EQ(summary.termination, LeastSquaresTermination::kFailure);
  EXPECT_NE(summary.message.find("initial values"), std::string::npos);
}

TEST(LeastSquares, ShouldStopEndsTheSolveAtAnAcceptedPoint) {
  SyntheticScene scene(6, 30, 0.5, 17);
  LeastSquaresProblem problem = scene.problem();
  LeastSquaresOptions options;
  int polls = 0;
  options.should_stop = [&] { return ++polls > 2; };
  const LeastSquaresSummary summary = solve(problem, options);
  EXPECT_EQ(summary.termination, LeastSquaresTermination::kInterrupted);
  EXPECT_EQ(summary.iterations, 2);
  EXPECT_NEAR(summary.final_cost, evaluate_cost(problem), 1e-9 * summary.final_cost);
}

TEST(LeastSquares, ReproducesCeresIterationCostsOnProblem16) {
  // Ceres' documentation (docs/source/installation.rst at fe351d5, quoted in
  // ../shared/data/bal/SOURCE.txt): simple_bundle_adjuster on problem-16-22106-pre, LM with
  // Ceres' defaults: costs per iteration 4.185660e+06, 1.062590e+05, 4.992817e+04,
  // 1.899774e+04, 1.808729e+04, 1.803399e+04, 1.803390e+04. Same LM, same model, same start:
  // the same sequence to the printed digits.
  CAIRN_REQUIRE_DATA("bal/problem-16-22106-pre.txt.bz2");
  io::BalProblem bal = io::read_bal(cairn::test::data_path("bal/problem-16-22106-pre.txt.bz2").string());
  BundleAdjustmentOptions options;
  const LeastSquaresSummary summary = bundle_adjust(bal, options);
  ASSERT_TRUE(summary.is_solution_usable()) << summary.message;
  const std::vector<double> ceres = {1.062590e+05, 4.992817e+04, 1.899774e+04, 1.808729e+04, 1.803399e+04,
                                     1.803390e+04};
  EXPECT_NEAR(summary.initial_cost, 4.185660e+06, 0.5e-6 * 4.185660e+06);
  ASSERT_GE(summary.iteration_log.size(), ceres.size());
  for (std::size_t k = 0; k < ceres.size(); ++k) {
    EXPECT_TRUE(summary.iteration_log[k].step_accepted);
    EXPECT_NEAR(summary.iteration_log[k].cost, ceres[k], 0.5e-6 * ceres[k]) << "iteration " << k + 1;
  }
  EXPECT_EQ(summary.termination, LeastSquaresTermination::kConvergence);
}

TEST(LeastSquares, ScalarSchurKernelsWhenAvxIsTurnedOff) {
  // Run by ctest a second time with CAIRN_NO_AVX=1 (tests/backend/CMakeLists.txt) together with
  // the solver tests, so that the scalar kernels are exercised on a CPU with AVX too.
  if (std::getenv("CAIRN_NO_AVX") == nullptr) GTEST_SKIP() << "CAIRN_NO_AVX is not set: the kernels follow the CPU";
  EXPECT_FALSE(schur_kernels_use_avx());
}

TEST(LeastSquares, SchurSolversAgreeOnARealBalProblem) {
  // The BAL camera (9 parameters) takes the Schur kernels for two residuals on 3-dimensional
  // points and 9-dimensional cameras: the rank-2 updates that form S (sparse Schur) and the
  // product with the implicit S (iterative Schur), AVX where the CPU has it. Run to convergence,
  // both must reach the same minimum; docs/benchmarks.md's convergence table has 3.03786358e+04
  // for both and for Ceres.
  CAIRN_REQUIRE_DATA("bal/problem-21-11315-pre.txt.bz2");
  std::vector<double> costs;
  for (const LinearSolverType type : {LinearSolverType::kSparseSchur, LinearSolverType::kIterativeSchur}) {
    io::BalProblem bal = io::read_bal(cairn::test::data_path("bal/problem-21-11315-pre.txt.bz2").string());
    BundleAdjustmentOptions options;
    options.solver.linear_solver = type;
    options.solver.function_tolerance = 1e-12;
    options.solver.max_iterations = 100;
    options.solver.min_cg_iterations = 5;
    options.solver.cg_tolerance = 1e-2;
    const LeastSquaresSummary summary = bundle_adjust(bal, options);
    ASSERT_TRUE(summary.is_solution_usable()) << summary.message;
    EXPECT_EQ(summary.termination, LeastSquaresTermination::kConvergence) << summary.brief_report();
    EXPECT_NEAR(summary.final_cost, evaluate_cost(make_bundle_adjustment_problem(bal, options)), 1e-9 * summary.final_cost);
    costs.push_back(summary.final_cost);
  }
  EXPECT_LT(costs[0], 3.0379e4);  // from 4.41e6 at the start
  EXPECT_NEAR(costs[1], costs[0], 1e-9 * costs[0]);
}

}  // namespace
}  // namespace cairn::backend

namespace cairn::backend {
namespace {

/// r = (p - z) / sigma on an R^2 variable.
class PointPrior2 final : public Factor {
 public:
  PointPrior2(double zx, double zy, double sigma) : z_(zx, zy), sigma_(sigma) {}
  int residual_size() const override { return 2; }
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override {
    residual[0] = (values[0][0] - z_.x()) / sigma_;
    residual[1] = (values[0][1] - z_.y()) / sigma_;
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      jacobians[0][0] = jacobians[0][3] = 1.0 / sigma_;
      jacobians[0][1] = jacobians[0][2] = 0.0;
    }
    return true;
  }

 private:
  Eigen::Vector2d z_;
  double sigma_;
};

TEST(LeastSquaresCovariance, TwoPriorsCombineAsInverseVariances) {
  // Two independent measurements of a point with sigma 1 and 2: the posterior covariance is
  // (1/1 + 1/4)^-1 I = 0.8 I, whatever the measured values.
  double p[2] = {0.3, -0.2};
  double q[2] = {5.0, 5.0};
  LeastSquaresProblem problem;
  const int vp = problem.add_variable(p, euclidean_manifold(2));
  const int vq = problem.add_variable(q, euclidean_manifold(2));
  problem.set_constant(vq);
  problem.add_factor(std::make_unique<PointPrior2>(0.0, 0.0, 1.0), {vp});
  problem.add_factor(std::make_unique<PointPrior2>(1.0, 1.0, 2.0), {vp});
  problem.add_factor(std::make_unique<PointPrior2>(5.0, 5.0, 1.0), {vq});
  const VariableCovariances covariance = marginal_covariances(problem, {vp, vq});
  ASSERT_TRUE(covariance.ok) << covariance.message;
  ASSERT_EQ(covariance.blocks.size(), 2u);
  EXPECT_TRUE(covariance.blocks[0].isApprox(0.8 * Eigen::Matrix2d::Identity(), 1e-12)) << covariance.blocks[0];
  EXPECT_TRUE(covariance.blocks[1].isZero()) << "a constant variable has no uncertainty";
}

TEST(LeastSquaresCovariance, AGaugeFreedomIsReportedNotInverted) {
  double a[3] = {0, 0, 0}, b[3] = {1, 2, 3};
  LeastSquaresProblem problem;
  const int va = problem.add_variable(a, euclidean_manifold(3));
  const int vb = problem.add_variable(b, euclidean_manifold(3));
  problem.add_factor(std::make_unique<PointDistance>(), {va, vb});
  VariableCovariances covariance = marginal_covariances(problem, {va});
  EXPECT_FALSE(covariance.ok);
  EXPECT_NE(covariance.message.find("singular"), std::string::npos) << covariance.message;
  // Holding a fixes the gauge: b - a has unit information, so Sigma_b = I.
  problem.set_constant(va);
  covariance = marginal_covariances(problem, {vb});
  ASSERT_TRUE(covariance.ok) << covariance.message;
  EXPECT_TRUE(covariance.blocks[0].isApprox(Eigen::Matrix3d::Identity(), 1e-12));
}

}  // namespace
}  // namespace cairn::backend

#include "cairn/backend/initialization.hpp"
#include "cairn/backend/optimizer.hpp"
#include "cairn/backend/pose_graph_engine.hpp"
#include "cairn/io/graph_io.hpp"

namespace cairn::backend {
namespace {

// The pose graph on the engine (pose_graph_engine.hpp) against the pose-graph optimiser, from
// the same chordal start, geodesic objective: the same optimum (g2o's chi2 to 1e-9) in 2D and 3D,
// reached by the engine's own LM through the same factors.
template <class Group>
void expect_engine_matches_optimizer(const std::string& relative) {
  io::GraphReadOptions read;
  const io::GraphFile file = io::read_graph(cairn::test::data_path(relative).string(), read);
  PoseGraphProblem<Group> start = make_problem(std::get<io::PoseGraphT<Group>>(file.graph), relative);
  initialize_chordal(start);
  OptimizerOptions optimizer;
  optimizer.function_tolerance = 1e-12;
  auto a = start;
  ASSERT_TRUE(optimize(a, optimizer).is_solution_usable());
  LeastSquaresOptions engine;
  engine.function_tolerance = 1e-12;
  auto b = start;
  const LeastSquaresSummary summary = optimize_on_engine(b, Objective::kGeodesic, engine);
  ASSERT_TRUE(summary.is_solution_usable()) << summary.message;
  const double chi2_a = evaluate_cost(a, optimizer);
  const double chi2_b = evaluate_cost(b, optimizer);
  EXPECT_NEAR(chi2_b, chi2_a, 1e-9 * chi2_a) << relative;
  EXPECT_NEAR(2.0 * summary.final_cost, chi2_b, 1e-9 * chi2_b) << "the engine's cost is half the chi2";
}

TEST(PoseGraphOnEngine, ReachesTheOptimisersOptimum) {
  CAIRN_REQUIRE_DATA("posegraph/se-sync/intel.g2o");
  expect_engine_matches_optimizer<core::SE2>("posegraph/se-sync/intel.g2o");
  expect_engine_matches_optimizer<core::SE3>("posegraph/se-sync/smallGrid3D.g2o");
}

}  // namespace
}  // namespace cairn::backend

namespace cairn::backend {
namespace {

// A rejected step must leave the current point's residuals alone: the next step is computed from
// them. Evaluating the trial's Jacobians with its cost (the default) or after acceptance gives
// the same iterates, through rejected steps too. (Before the trial got buffers of its own, a
// rejected step overwrote the residuals and the steps after it were wrong.)
TEST(LeastSquares, RejectedStepsLeaveTheIteratesAsTheyWere) {
  std::vector<std::vector<double>> costs;
  int rejected = 0;
  for (const bool with_trial : {true, false}) {
    SyntheticScene scene(6, 40, 1.0, 21);
    for (auto& pose : scene.poses) pose[4] += 3.0;  // far from the truth: LM's first steps fail
    LeastSquaresProblem problem = scene.problem();
    LeastSquaresOptions options;
    options.jacobians_with_trial_cost = with_trial;
    options.threads = 1;  // bit-identical sums (with more threads their order varies by an ulp)
    options.initial_trust_region_radius = 1e16;
    options.max_trust_region_radius = 1e16;
    options.function_tolerance = 1e-14;
    const LeastSquaresSummary summary = solve(problem, options);
    ASSERT_TRUE(summary.is_solution_usable()) << summary.message;
    std::vector<double> per_iteration;
    for (const auto& it : summary.iteration_log) {
      per_iteration.push_back(it.cost);
      if (with_trial && !it.step_accepted) ++rejected;
    }
    costs.push_back(per_iteration);
  }
  EXPECT_GE(rejected, 1) << "no step was rejected: this test checks nothing";
  ASSERT_EQ(costs[0].size(), costs[1].size());
  for (std::size_t k = 0; k < costs[0].size(); ++k) EXPECT_EQ(costs[0][k], costs[1][k]) << "iteration " << k + 1;
}

}  // namespace
}  // namespace cairn::backend
