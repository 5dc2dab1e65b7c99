// The dual certificate of SE-Sync's problem (backend/certificate.hpp): its lambda_min bracket
// against a dense eigen-decomposition of S = Q - Lambda built independently here from the
// objective's definition, certification of the optima of real graphs, refusal of points that
// are not optimal, and the suboptimality bound holding where the gap is known.

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

#include "cairn/backend/certificate.hpp"
#include "cairn/backend/factors.hpp"
#include "cairn/backend/initialization.hpp"
#include "cairn/backend/optimizer.hpp"
#include "cairn/backend/staircase.hpp"
#include "cairn/io/graph_io.hpp"
#include "test_data.hpp"

namespace cairn::backend {
namespace {

/// SE-Sync's f for arbitrary (unconstrained) d x d blocks R_i and vectors t_i, the columns of
/// X = [t_1 .. t_n | R_1 .. R_n] (only row `row` of X is used: f is a sum over rows).
template <class Group>
double f_of_row(const PoseGraphProblem<Group>& problem, const Eigen::VectorXd& x) {
  constexpr int d = kRotationDim<Group>;
  const int n = problem.size();
  double f = 0.0;
  for (const auto& e : problem.edges) {
    const Eigen::MatrixXd R_ij = rotation_matrix_of(e.T_i_j);
    const Eigen::VectorXd t_ij = e.T_i_j.translation();
    const Eigen::RowVectorXd Ri = x.segment(n + e.i * d, d).transpose();
    const Eigen::RowVectorXd Rj = x.segment(n + e.j * d, d).transpose();
    f += e.kappa * (Rj - Ri * R_ij).squaredNorm();
    const double r = x(e.j) - x(e.i) - Ri.dot(t_ij.transpose());
    f += e.tau * r * r;
  }
  return f;
}

/// lambda_min(Q - Lambda) at the problem's rotations, densely: M by polarisation of f, Q by the
/// pseudo-inverse of the translational block, Lambda = SymBlockDiag(Q R^T R).
template <class Group>
double dense_lambda_min(const PoseGraphProblem<Group>& problem, double* f_out) {
  constexpr int d = kRotationDim<Group>;
  const int n = problem.size();
  const int full = n * (d + 1);
  Eigen::MatrixXd M(full, full);
  Eigen::VectorXd fe(full);
  for (int a = 0; a < full; ++a) fe(a) = f_of_row(problem, Eigen::VectorXd::Unit(full, a));
  for (int a = 0; a < full; ++a) {
    for (int b = a; b < full; ++b) {
      M(a, b) = M(b, a) = 0.5 * (f_of_row(problem, Eigen::VectorXd::Unit(full, a) + Eigen::VectorXd::Unit(full, b)) -
                                 fe(a) - fe(b));
    }
  }
  const Eigen::MatrixXd Mtt = M.topLeftCorner(n, n);
  const Eigen::MatrixXd MtR = M.topRightCorner(n, n * d);
  const Eigen::MatrixXd MRR = M.bottomRightCorner(n * d, n * d);
  const Eigen::MatrixXd Q = MRR - MtR.transpose() * Mtt.completeOrthogonalDecomposition().pseudoInverse() * MtR;
  Eigen::MatrixXd R(d, n * d);
  for (int p = 0; p < n; ++p) R.block(0, p * d, d, d) = rotation_matrix_of(problem.T_world_pose[static_cast<std::size_t>(p)]);
  const Eigen::MatrixXd QRt = Q * R.transpose();
  Eigen::MatrixXd S = Q;
  for (int p = 0; p < n; ++p) {
    const Eigen::MatrixXd P = QRt.block(p * d, 0, d, d) * R.block(0, p * d, d, d);
    S.block(p * d, p * d, d, d) -= 0.5 * (P + P.transpose());
  }
  *f_out = (R * Q * R.transpose()).trace();
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(S, Eigen::EigenvaluesOnly).eigenvalues()(0);
}

template <class Group>
PoseGraphProblem<Group> read_problem(const std::string& relative) {
  io::GraphReadOptions read;
  read.information_policy = io::InformationPolicy::kKeep;
  const io::GraphFile file = io::read_graph(test::data_path(relative).string(), read);
  return make_problem(std::get<io::PoseGraphT<Group>>(file.graph), relative);
}

template <class Group>
void solve_chordal(PoseGraphProblem<Group>& problem) {
  initialize_chordal(problem);
  OptimizerOptions options;
  options.objective = Objective::kChordal;
  options.max_iterations = 500;
  optimize(problem, options);
}

/// The bracket contains the dense lambda_min, f agrees, and certification follows the sign.
template <class Group>
void expect_matches_dense(const PoseGraphProblem<Group>& problem, const std::string& what) {
  double f_dense = 0.0;
  const double lambda = dense_lambda_min(problem, &f_dense);
  const CertificateSummary c = certify_chordal(problem);
  EXPECT_NEAR(c.f, f_dense, 1e-9 * std::max(1.0, f_dense)) << what;
  const double slack = 1e-7 * std::max(1.0, std::abs(lambda));
  EXPECT_LE(c.lambda_min_lower, lambda + slack) << what << ": dense lambda_min " << lambda << "; " << c.message;
  EXPECT_GE(c.lambda_min_upper, lambda - slack) << what << ": dense lambda_min " << lambda << "; " << c.message;
  EXPECT_EQ(c.certified, lambda >= -CertificateOptions{}.eigenvalue_tolerance) << what << ": dense " << lambda;
}

TEST(Certificate, BracketsTheDenseLambdaMinOnRealGraphsAndPerturbedPoints) {
  CAIRN_REQUIRE_DATA("posegraph/se-sync/tinyGrid3D.g2o");
  for (const char* relative : {"posegraph/se-sync/tinyGrid3D.g2o", "posegraph/se-sync/smallGrid3D.g2o"}) {
    auto problem = read_problem<core::SE3>(relative);
    solve_chordal(problem);
    expect_matches_dense(problem, relative);
    // One pose turned away from the optimum: a point that is not optimal must not be certified.
    auto moved = problem;
    moved.T_world_pose[3] = moved.T_world_pose[3] * core::SE3::exp((Eigen::Matrix<double, 6, 1>() << 0, 0, 0, 0.3, -0.2, 0.5).finished());
    expect_matches_dense(moved, std::string(relative) + " with pose 3 turned");
  }
  CAIRN_REQUIRE_DATA("posegraph/se-sync/MIT.g2o");
  // 2D: the first 60 poses of MIT would need re-indexing; a noisy small world is built instead.
  io::PoseGraph2D graph;
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.05);
  const int n = 30;
  std::vector<core::SE2> truth;
  for (int k = 0; k < n; ++k) truth.push_back(core::SE2(std::cos(0.4 * k) * 5.0, std::sin(0.4 * k) * 5.0, 0.4 * k + 1.57));
  for (int k = 0; k < n; ++k) graph.vertices.push_back({k, truth[static_cast<std::size_t>(k)]});
  auto add = [&](int i, int j) {
    io::GraphEdge<core::SE2> e;
    e.from = i;
    e.to = j;
    const core::SE2 Z = truth[static_cast<std::size_t>(i)].inverse() * truth[static_cast<std::size_t>(j)];
    e.T_from_to = Z * core::SE2(noise(rng), noise(rng), noise(rng));
    e.information = Eigen::Matrix3d::Identity() * 100.0;
    graph.edges.push_back(e);
  };
  for (int k = 0; k + 1 < n; ++k) add(k, k + 1);
  for (int k = 0; k + 16 < n; k += 3) add(k, k + 16);
  auto problem = make_problem(graph, "noisy circle");
  solve_chordal(problem);
  expect_matches_dense(problem, "noisy circle");
  auto moved = problem;
  moved.T_world_pose[7] = moved.T_world_pose[7] * core::SE2(0.0, 0.0, 2.5);
  expect_matches_dense(moved, "noisy circle with pose 7 turned");
}

// On the small SE-Sync graphs, the optimum cairn reaches is certified, and the bound covers
// the distance to SE-Sync's certified value; a point that is not optimal gets a bound that still
// covers its true gap (weak duality), and is not certified.
TEST(Certificate, CertifiesTheOptimaOfSeSyncGraphsAndBoundsTheGapOfOtherPoints) {
  CAIRN_REQUIRE_DATA("posegraph/se-sync/intel.g2o");
  struct Case {
    const char* relative;
    double f_star;
  };
  for (const Case& c : {Case{"posegraph/se-sync/intel.g2o", 52.348227285553435},
                        Case{"posegraph/se-sync/MIT.g2o", 61.154115524460529},
                        Case{"posegraph/se-sync/CSAIL.g2o", 31.703715883737345}}) {
    auto problem = read_problem<core::SE2>(c.relative);
    solve_chordal(problem);
    const CertificateSummary at_optimum = certify_chordal(problem);
    EXPECT_TRUE(at_optimum.certified) << c.relative << ": " << at_optimum.message;
    EXPECT_NEAR(at_optimum.f, c.f_star, 1e-8 * c.f_star) << c.relative;
    EXPECT_LT(at_optimum.relative_suboptimality_bound, 1e-5) << c.relative;

    auto moved = problem;
    for (std::size_t k = 10; k < 20; ++k) moved.T_world_pose[k] = moved.T_world_pose[k] * core::SE2(0.0, 0.0, 0.8);
    const CertificateSummary away = certify_chordal(moved);
    EXPECT_FALSE(away.certified) << c.relative << ": " << away.message;
    EXPECT_LT(away.lambda_min_upper, 0.0) << c.relative;
    EXPECT_GE(away.f - c.f_star, 0.0) << c.relative;
    EXPECT_LE(away.f - c.f_star, away.suboptimality_bound) << c.relative << ": " << away.message;
  }
}

// From a start with every rotation turned by 3 rad of noise, LM on the chordal objective ends in
// a local minimum of MIT that the certificate refuses; the staircase climbs (rank 3 is not
// certified either, rank 4 is), rounds, polishes and ends at SE-Sync's certified optimum.
TEST(Staircase, EscapesALocalMinimumToTheCertifiedGlobalOptimum) {
  CAIRN_REQUIRE_DATA("posegraph/se-sync/MIT.g2o");
  auto problem = read_problem<core::SE2>("posegraph/se-sync/MIT.g2o");
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0.0, 3.0);
  for (std::size_t k = 1; k < problem.T_world_pose.size(); ++k) {
    problem.T_world_pose[k] = problem.T_world_pose[k] * core::SE2(0.0, 0.0, noise(rng));
  }
  OptimizerOptions options;
  options.objective = Objective::kChordal;
  options.max_iterations = 500;
  optimize(problem, options);
  const double f_local = evaluate_cost(problem, options);
  const CertificateSummary local = certify_chordal(problem);
  ASSERT_FALSE(local.certified) << "this start no longer ends in a local minimum: " << local.message;
  EXPECT_LT(local.lambda_min_upper, 0.0);

  const StaircaseSummary staircase = riemannian_staircase(problem);
  EXPECT_TRUE(staircase.certified) << staircase.message;
  ASSERT_GE(staircase.levels.size(), 2u);
  EXPECT_FALSE(staircase.levels.front().certificate.certified);
  EXPECT_TRUE(staircase.levels.back().certificate.certified) << staircase.levels.back().certificate.message;
  EXPECT_GT(staircase.levels.back().rank, 2);
  const double f_star = 61.154115524460529;
  EXPECT_NEAR(evaluate_cost(problem, options), f_star, 1e-8 * f_star) << "from " << f_local;
  EXPECT_NEAR(staircase.f_final, f_star, 1e-8 * f_star);
  EXPECT_TRUE(certify_chordal(problem).certified);
}

// A point that certifies at rank d is left as it is.
TEST(Staircase, LeavesACertifiedPointAlone) {
  CAIRN_REQUIRE_DATA("posegraph/se-sync/intel.g2o");
  auto problem = read_problem<core::SE2>("posegraph/se-sync/intel.g2o");
  solve_chordal(problem);
  const auto before = problem.T_world_pose;
  const StaircaseSummary staircase = riemannian_staircase(problem);
  EXPECT_TRUE(staircase.certified);
  EXPECT_EQ(staircase.levels.size(), 1u);
  for (std::size_t k = 0; k < before.size(); ++k) EXPECT_EQ(before[k].translation(), problem.T_world_pose[k].translation());
}

TEST(CertificateOptions, ReportsEveryProblem) {
  CertificateOptions options;
  options.eigenvalue_tolerance = 0.0;
  options.refinement_decades = -1;
  std::string why;
  EXPECT_FALSE(options.is_valid(&why));
  EXPECT_NE(why.find("eigenvalue_tolerance"), std::string::npos);
  EXPECT_NE(why.find("refinement_decades"), std::string::npos);
}

}  // namespace
}  // namespace cairn::backend
namespace cairn::backend {
namespace {

// The same in 3D, on a graph built so that the chordal start is not optimal: a cycle of 10 poses
// on a circle with exact measurements (the optimum is f = 0), started with the rotations twisted
// by one extra full turn about each pose's x axis along the cycle. A single turn is not
// contractible in SO(3) (its fundamental group is Z_2), so LM on the rank-3 problem cannot undo
// it and stops at f > 0, which the certificate refuses; in a higher rank the twist unwinds, and
// the staircase must end certified at f = 0. (From rotations perturbed at random, smallGrid3D,
// tinyGrid3D and sphere2500 returned to their certified optima on every seed tried, 10, 8 and 8;
// torus3D ended in an uncertified local minimum that the staircase escaped to f* = 24227.0456,
// but in 84 s: a benchmark, not a test.)
TEST(Staircase, UnwindsATwistedCycleIn3D) {
  const int n = 10;
  io::PoseGraphT<core::SE3> graph;
  std::vector<core::SE3> truth;
  for (int k = 0; k < n; ++k) {
    const double a = 2.0 * M_PI * k / n;
    truth.emplace_back(core::SO3::exp(Vector3(0, 0, a)), Vector3(10 * std::cos(a), 10 * std::sin(a), 0));
  }
  for (int k = 0; k < n; ++k) {
    const double twist = 2.0 * M_PI * k / n;
    graph.vertices.push_back({k, core::SE3(truth[k].so3() * core::SO3::exp(Vector3(twist, 0, 0)), truth[k].translation())});
    io::GraphEdge<core::SE3> edge;
    edge.from = k;
    edge.to = (k + 1) % n;
    edge.T_from_to = truth[k].inverse() * truth[(k + 1) % n];
    graph.edges.push_back(edge);
  }
  auto problem = make_problem(graph, "twisted cycle");
  OptimizerOptions options;
  options.objective = Objective::kChordal;
  options.max_iterations = 500;
  optimize(problem, options);
  const double f_local = evaluate_cost(problem, options);
  EXPECT_GT(f_local, 1.0) << "LM undid the twist at rank 3";
  const CertificateSummary local = certify_chordal(problem);
  ASSERT_FALSE(local.certified) << local.message;
  EXPECT_LT(local.lambda_min_upper, 0.0);
  const StaircaseSummary staircase = riemannian_staircase(problem);
  EXPECT_TRUE(staircase.certified) << staircase.message;
  ASSERT_GE(staircase.levels.size(), 2u);
  EXPECT_EQ(staircase.levels.front().rank, 3);
  EXPECT_FALSE(staircase.levels.front().certificate.certified);
  EXPECT_GT(staircase.levels.back().rank, 3);
  EXPECT_LT(evaluate_cost(problem, options), 1e-12) << "from " << f_local;
  for (int k = 0; k < n; ++k) {
    const core::SE3 error = (truth[0].inverse() * truth[k]).inverse() * (problem.T_world_pose[0].inverse() * problem.T_world_pose[k]);
    EXPECT_LT(error.log().norm(), 1e-6) << "pose " << k;
  }
  EXPECT_TRUE(certify_chordal(problem).certified);
}

}  // namespace
}  // namespace cairn::backend
