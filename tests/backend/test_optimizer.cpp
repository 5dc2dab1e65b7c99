// The optimiser on synthetic graphs with a known answer, and on SE-Sync's benchmark graphs
// against the certified global optima measured with SE-Sync and printed in
// ../shared/data/README.md ("Optima measured with SE-Sync on this data").

#include <gtest/gtest.h>
#include <omp.h>

#include <random>

#include "cairn/backend/covariance.hpp"
#include "cairn/backend/factors.hpp"
#include "cairn/backend/gnc.hpp"
#include "cairn/backend/initialization.hpp"
#include "cairn/backend/outliers.hpp"
#include "cairn/backend/optimizer.hpp"
#include "cairn/backend/sparse_cholesky.hpp"
#include "cairn/io/graph_io.hpp"
#include "cairn/io/parse_error.hpp"
#include "test_data.hpp"

namespace cairn::backend {
namespace {

// A robot drives `laps` times around a square; odometry between consecutive poses, loop
// closures between laps. Measurements are exact, so the optimum has zero cost.
template <class Group>
io::PoseGraphT<Group> square_world(int laps, std::vector<Group>& truth) {
  io::PoseGraphT<Group> graph;
  const int per_lap = 12;
  for (int k = 0; k < laps * per_lap; ++k) {
    const double angle = 2.0 * M_PI * k / per_lap;
    typename Group::Tangent xi = Group::Tangent::Zero();
    if constexpr (Group::kDoF == 3) {
      truth.push_back(Group(5.0 * std::cos(angle), 5.0 * std::sin(angle), angle + M_PI / 2));
    } else {
      xi << 5.0 * std::cos(angle), 5.0 * std::sin(angle), 0.3 * std::sin(angle), 0.1, 0.05 * k, angle;
      truth.push_back(Group(core::SO3::exp(xi.template tail<3>()), xi.template head<3>()));
    }
  }
  auto add = [&](int i, int j) {
    io::GraphEdge<Group> e;
    e.from = i;
    e.to = j;
    e.T_from_to = truth[static_cast<std::size_t>(i)].inverse() * truth[static_cast<std::size_t>(j)];
    // sigma 5 cm in translation, 0.01 rad in rotation (translation first).
    e.information.setIdentity();
    constexpr int d = Group::kDoF == 3 ? 2 : 3;
    e.information.diagonal().template head<d>().setConstant(400.0);
    e.information.diagonal().template tail<Group::kDoF - d>().setConstant(1e4);
    graph.edges.push_back(e);
  };
  for (int k = 0; k + 1 < static_cast<int>(truth.size()); ++k) add(k, k + 1);
  for (int k = per_lap; k < static_cast<int>(truth.size()); ++k) add(k - per_lap, k);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 0.3);
  for (int k = 0; k < static_cast<int>(truth.size()); ++k) {
    typename Group::Tangent d;
    for (int c = 0; c < Group::kDoF; ++c) d[c] = k == 0 ? 0.0 : noise(rng);
    graph.vertices.push_back({k, truth[static_cast<std::size_t>(k)] * Group::exp(d)});
  }
  return graph;
}

template <class Group>
void expect_recovers_truth(Algorithm algorithm, Objective objective) {
  std::vector<Group> truth;
  const auto graph = square_world<Group>(3, truth);
  auto problem = make_problem(graph, "square");
  OptimizerOptions options;
  options.algorithm = algorithm;
  options.objective = objective;
  const OptimizerSummary summary = optimize(problem, options);
  EXPECT_TRUE(summary.is_solution_usable()) << summary.brief_report();
  EXPECT_GT(summary.initial_cost, 1.0);
  EXPECT_LT(summary.final_cost, 1e-16) << summary.brief_report();
  for (std::size_t k = 0; k < truth.size(); ++k) {
    EXPECT_LT((truth[k].inverse() * problem.T_world_pose[k]).log().norm(), 1e-6) << "pose " << k;
  }
}

TEST(Optimizer, LevenbergMarquardtRecoversTheTruth2D) { expect_recovers_truth<core::SE2>(Algorithm::kLevenbergMarquardt, Objective::kGeodesic); }
TEST(Optimizer, LevenbergMarquardtRecoversTheTruth3D) { expect_recovers_truth<core::SE3>(Algorithm::kLevenbergMarquardt, Objective::kGeodesic); }
TEST(Optimizer, GaussNewtonRecoversTheTruth3D) { expect_recovers_truth<core::SE3>(Algorithm::kGaussNewton, Objective::kGeodesic); }
TEST(Optimizer, DoglegRecoversTheTruth2D) { expect_recovers_truth<core::SE2>(Algorithm::kDogleg, Objective::kGeodesic); }
TEST(Optimizer, DoglegRecoversTheTruth3D) { expect_recovers_truth<core::SE3>(Algorithm::kDogleg, Objective::kGeodesic); }
TEST(Optimizer, ChordalObjectiveRecoversTheTruth3D) { expect_recovers_truth<core::SE3>(Algorithm::kLevenbergMarquardt, Objective::kChordal); }

TEST(Initialization, ChordalAndOdometryRecoverExactGraphs) {
  std::vector<core::SE3> truth;
  auto graph = square_world<core::SE3>(2, truth);
  for (const bool chordal : {true, false}) {
    auto problem = make_problem(graph, "square");
    for (std::size_t k = 1; k < truth.size(); ++k) problem.T_world_pose[k] = core::SE3();
    if (chordal) {
      initialize_chordal(problem);
    } else {
      EXPECT_EQ(initialize_odometry(problem).poses_reached, static_cast<int>(truth.size()));
    }
    for (std::size_t k = 0; k < truth.size(); ++k) {
      EXPECT_LT((truth[k].inverse() * problem.T_world_pose[k]).log().norm(), 1e-9) << (chordal ? "chordal " : "odometry ") << k;
    }
  }
}

TEST(Problem, RejectsAGraphWithAnUnanchoredComponent) {
  io::PoseGraph2D graph;
  for (int k = 0; k < 4; ++k) graph.vertices.push_back({k, core::SE2()});
  io::GraphEdge<core::SE2> e;
  e.from = 0;
  e.to = 1;
  graph.edges.push_back(e);
  e.from = 2;
  e.to = 3;
  graph.edges.push_back(e);
  try {
    make_problem(graph, "two.g2o");
    FAIL() << "expected ParseError";
  } catch (const io::ParseError& error) {
    EXPECT_NE(std::string(error.what()).find("2 connected components"), std::string::npos) << error.what();
  }
  graph.fixed = {0, 2};  // anchoring both components makes it well posed
  EXPECT_NO_THROW(make_problem(graph, "two.g2o"));
}

TEST(OptimizerOptions, ReportsEveryProblem) {
  OptimizerOptions options;
  options.max_iterations = 0;
  options.kernel_scale = -1.0;
  std::string error;
  EXPECT_FALSE(options.is_valid(&error));
  EXPECT_NE(error.find("max_iterations"), std::string::npos);
  EXPECT_NE(error.find("kernel_scale"), std::string::npos);
}

// SE-Sync's certified optima (../shared/data/README.md, "Optima measured with SE-Sync on this
// data"; about 8 significant digits are meaningful).
struct Optimum {
  const char* file;
  double f_star;
};

class SeSyncOptima : public ::testing::TestWithParam<Optimum> {};

TEST_P(SeSyncOptima, ChordalObjectiveFromChordalStartReachesTheCertifiedOptimum) {
  const Optimum& optimum = GetParam();
  const std::string relative = std::string("posegraph/se-sync/") + optimum.file;
  CAIRN_REQUIRE_DATA(relative);
  io::GraphReadOptions read;
  read.information_policy = io::InformationPolicy::kKeep;  // SE-Sync uses the raw diagonal blocks
  const io::GraphFile file = io::read_graph(test::data_path(relative).string(), read);
  OptimizerOptions options;
  options.objective = Objective::kChordal;
  options.max_iterations = 300;
  double f = 0.0;
  std::visit(
      [&](const auto& graph) {
        auto problem = make_problem(graph, relative);
        initialize_chordal(problem);
        const OptimizerSummary summary = optimize(problem, options);
        EXPECT_TRUE(summary.is_solution_usable()) << summary.brief_report();
        f = summary.final_cost;
      },
      file.graph);
  RecordProperty("f", std::to_string(f));
  // Four significant digits, as the published table prints them, and in fact much closer.
  EXPECT_NEAR(f, optimum.f_star, 2e-5 * optimum.f_star) << optimum.file;
}

// Reads a SE-Sync graph and returns it initialised by the chordal relaxation, or nothing (and
// the test skips) without the data.
template <class Body>
void with_chordal_start(const std::string& file, Body body) {
  const std::string relative = "posegraph/se-sync/" + file;
  const io::GraphFile graph_file = io::read_graph(test::data_path(relative).string());
  std::visit(
      [&](const auto& graph) {
        auto problem = make_problem(graph, relative);
        initialize_chordal(problem);
        body(problem);
      },
      graph_file.graph);
}

int factorizations(const OptimizerSummary& summary) {
  int n = 0;
  for (const auto& it : summary.iteration_log) n += it.factorize_s > 0.0 ? 1 : 0;
  return n;
}

// Steps from PCG on an earlier factorisation (OptimizerOptions::reuse_factorization, the
// default) must land where exact LM steps land; on the large graphs, where a factorisation costs
// many triangular solves, with fewer numeric factorisations (on intel, a small 2D graph, the
// saving is not asserted). PCG is not even tried after a step larger than
// reuse_step_fraction of the largest one; with the fraction at 1 it is tried right after the
// first step.
TEST(Optimizer, ReusedFactorisationReachesTheSameOptimumAsExactSteps) {
  for (const char* file : {"intel.g2o", "city10000.g2o", "sphere2500.g2o", "cubicle.g2o"}) {
    const bool large = std::string(file) != "intel.g2o";
    CAIRN_REQUIRE_DATA(std::string("posegraph/se-sync/") + file);
    with_chordal_start(file, [&](auto start) {
      OptimizerOptions options;
      options.max_iterations = 50;
      auto exact = start;
      options.reuse_factorization = false;
      const OptimizerSummary exact_summary = optimize(exact, options);
      auto reused = start;
      options.reuse_factorization = true;
      const OptimizerSummary reused_summary = optimize(reused, options);
      ASSERT_EQ(exact_summary.termination, TerminationType::kConvergence) << file << ": " << exact_summary.brief_report();
      ASSERT_EQ(reused_summary.termination, TerminationType::kConvergence) << file << ": " << reused_summary.brief_report();
      EXPECT_NEAR(reused_summary.final_cost, exact_summary.final_cost, 1e-9 * exact_summary.final_cost) << file;
      double worst = 0.0;
      for (std::size_t k = 0; k < exact.T_world_pose.size(); ++k) {
        worst = std::max(worst, (exact.T_world_pose[k].inverse() * reused.T_world_pose[k]).log().norm());
      }
      EXPECT_LT(worst, 1e-5) << file;
      int pcg_steps = 0;
      for (const auto& it : reused_summary.iteration_log) pcg_steps += it.reused_factorization && it.step_accepted ? 1 : 0;
      double last_step = 0.0;
      double largest_step = 0.0;
      for (const auto& it : reused_summary.iteration_log) {
        if (last_step > options.reuse_step_fraction * largest_step) {
          EXPECT_EQ(it.cg_iterations, 0) << file << " iteration " << it.iteration;
        }
        if (!it.step_accepted) continue;
        last_step = it.step_norm;
        largest_step = std::max(largest_step, it.step_norm);
      }
      auto always = start;
      options.reuse_step_fraction = 1.0;
      const OptimizerSummary always_summary = optimize(always, options);
      ASSERT_GE(always_summary.iteration_log.size(), 2u) << file;
      EXPECT_GT(always_summary.iteration_log[1].cg_iterations, 0) << file;
      EXPECT_NEAR(always_summary.final_cost, exact_summary.final_cost, 1e-9 * exact_summary.final_cost) << file;
      if (large) {
        EXPECT_GE(pcg_steps, 1) << file;
        EXPECT_LT(factorizations(reused_summary), factorizations(exact_summary)) << file;
      }
      std::printf("%s: exact %d iterations %d factorisations, reused %d iterations %d factorisations (%d PCG steps), cost %.12g vs %.12g, poses within %.2e\n",
                  file, exact_summary.iterations, factorizations(exact_summary), reused_summary.iterations,
                  factorizations(reused_summary), pcg_steps, exact_summary.final_cost, reused_summary.final_cost, worst);
    });
  }
}

// Block couplings of a random sparse system: a chain through all blocks plus `extra` random
// pairs (a != b; repeats possible).
std::vector<std::pair<int, int>> chain_and_random_pairs(int blocks, int extra, std::mt19937& rng) {
  std::uniform_int_distribution<int> pick(0, blocks - 1);
  std::vector<std::pair<int, int>> pairs;
  for (int k = 1; k < blocks; ++k) pairs.emplace_back(k - 1, k);
  for (int k = 0; k < extra; ++k) {
    const int a = pick(rng);
    const int b = pick(rng);
    if (a != b) pairs.emplace_back(a, b);
  }
  return pairs;
}

// A random sparse SPD system large enough for CHOLMOD's supernodal path and its OpenMP regions
// (n > 128): the factorisation solves it as a dense Cholesky does, and the caller's OpenMP
// setting, which SparseCholesky lowers around every CHOLMOD call, is back afterwards.
TEST(SparseCholesky, SolvesAsDenseCholeskyAndRestoresTheCallersOpenMpSetting) {
  const int blocks = 150;
  const int B = 3;
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  const std::vector<std::pair<int, int>> pairs = chain_and_random_pairs(blocks, 200, rng);
  BlockPattern pattern(blocks, B, pairs);
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(blocks * B, blocks * B);
  // H = sum over pairs of J^T J with J = [A_a, A_b] random 3x6, plus a diagonal: SPD.
  for (const auto& [a, b] : pairs) {
    const Eigen::Matrix<double, 3, 6> J = Eigen::Matrix<double, 3, 6>::NullaryExpr([&] { return normal(rng); });
    const Eigen::Matrix<double, 6, 6> H = J.transpose() * J;
    const int lo = std::min(a, b);
    const int hi = std::max(a, b);
    const int off_lo = a == lo ? 0 : 3;
    const int off_hi = a == lo ? 3 : 0;
    const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> H_lo = H.block<3, 3>(off_lo, off_lo);
    const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> H_hi = H.block<3, 3>(off_hi, off_hi);
    const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> H_lo_hi = H.block<3, 3>(off_lo, off_hi);
    pattern.add_diagonal(lo, H_lo.data());
    pattern.add_diagonal(hi, H_hi.data());
    pattern.add_off_diagonal(lo, hi, H_lo_hi.data());
    dense.block<3, 3>(lo * B, lo * B) += H_lo;
    dense.block<3, 3>(hi * B, hi * B) += H_hi;
    dense.block<3, 3>(lo * B, hi * B) += H_lo_hi;
    dense.block<3, 3>(hi * B, lo * B) += H_lo_hi.transpose();
  }
  for (int k = 0; k < blocks * B; ++k) {
    pattern.matrix().value[static_cast<std::size_t>(pattern.diagonal_index(k))] += 0.5;
    dense(k, k) += 0.5;
  }
  const Eigen::VectorXd rhs = Eigen::VectorXd::NullaryExpr(blocks * B, [&] { return normal(rng); });
  const Eigen::VectorXd expected = dense.llt().solve(rhs);

  const int callers_levels = 3;
  omp_set_max_active_levels(callers_levels);
  SparseCholesky cholesky;
  const std::vector<int> ordering = pattern.block_amd_ordering();
  cholesky.analyze(pattern.matrix(), &ordering);
  EXPECT_EQ(omp_get_max_active_levels(), callers_levels);
  ASSERT_EQ(cholesky.factorize(pattern.matrix()), FactorizationStatus::kSuccess);
  EXPECT_EQ(omp_get_max_active_levels(), callers_levels);
  const Eigen::VectorXd x = cholesky.solve(rhs);
  EXPECT_EQ(omp_get_max_active_levels(), callers_levels);
  Eigen::VectorXd y;
  cholesky.solve_in_place(rhs, y);
  EXPECT_EQ(omp_get_max_active_levels(), callers_levels);
  EXPECT_LT((x - expected).norm(), 1e-9 * expected.norm());
  EXPECT_LT((y - expected).norm(), 1e-9 * expected.norm());
  // The sparse product used by PCG agrees with the dense matrix too.
  EXPECT_LT((symmetric_multiply(pattern.matrix(), rhs) - dense * rhs).norm(), 1e-9 * (dense * rhs).norm());
}

// Blocks relabelled in block-AMD elimination order and analysed as stored: the same fill as the
// block AMD ordering handed to CHOLMOD (and far less than the original labels give), and the
// same solution as a dense Cholesky of the original system.
TEST(SparseCholesky, StoredOrderAnalysisOfAmdRelabelledBlocksKeepsTheFillAndTheSolution) {
  const int blocks = 150;
  const int B = 3;
  std::mt19937 rng(11);
  std::normal_distribution<double> normal;
  std::vector<std::pair<int, int>> pairs = chain_and_random_pairs(blocks, 60, rng);
  for (auto& [a, b] : pairs) std::tie(a, b) = std::pair(std::min(a, b), std::max(a, b));
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());  // one block per coupled pair
  Eigen::MatrixXd dense = Eigen::MatrixXd::Identity(blocks * B, blocks * B);
  for (const auto& [a, b] : pairs) {
    const Eigen::Matrix<double, 3, 6> J = Eigen::Matrix<double, 3, 6>::NullaryExpr([&] { return normal(rng); });
    const Eigen::Matrix<double, 6, 6> H = J.transpose() * J;
    dense.block<3, 3>(a * B, a * B) += H.block<3, 3>(0, 0);
    dense.block<3, 3>(b * B, b * B) += H.block<3, 3>(3, 3);
    dense.block<3, 3>(a * B, b * B) += H.block<3, 3>(0, 3);
    dense.block<3, 3>(b * B, a * B) += H.block<3, 3>(3, 0);
  }
  // The upper blocks of `dense` with block b stored at label[b].
  auto pattern_of = [&](const std::vector<int>& label) {
    std::vector<std::pair<int, int>> relabelled;
    for (const auto& [a, b] : pairs) relabelled.emplace_back(label[static_cast<std::size_t>(a)], label[static_cast<std::size_t>(b)]);
    BlockPattern pattern(blocks, B, relabelled);
    for (int b = 0; b < blocks; ++b) {
      const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> H = dense.block<3, 3>(b * B, b * B);
      pattern.add_diagonal(label[static_cast<std::size_t>(b)], H.data());
    }
    for (const auto& [a, b] : pairs) {
      const int la = label[static_cast<std::size_t>(a)];
      const int lb = label[static_cast<std::size_t>(b)];
      const int lo = la < lb ? a : b;
      const int hi = la < lb ? b : a;
      const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> H = dense.block<3, 3>(lo * B, hi * B);
      pattern.add_off_diagonal(std::min(la, lb), std::max(la, lb), H.data());
    }
    return pattern;
  };
  std::vector<int> identity(static_cast<std::size_t>(blocks));
  for (int b = 0; b < blocks; ++b) identity[static_cast<std::size_t>(b)] = b;
  const std::vector<int> label = block_amd_labels(blocks, pairs);
  std::vector<int> sorted = label;
  std::sort(sorted.begin(), sorted.end());
  ASSERT_EQ(sorted, identity) << "labels must be a permutation of the blocks";
  // Through a cache: the same labels, computed again only for another block graph.
  BlockOrderCache cache;
  EXPECT_EQ(block_amd_labels(blocks, pairs, cache), label);
  const std::uint64_t digest = cache.digest;
  cache.label[0] = -7;  // a reused entry shows through
  EXPECT_EQ(block_amd_labels(blocks, pairs, cache)[0], -7);
  auto fewer = pairs;
  fewer.pop_back();
  EXPECT_EQ(block_amd_labels(blocks, fewer, cache), block_amd_labels(blocks, fewer));
  EXPECT_NE(cache.digest, digest);

  const BlockPattern original = pattern_of(identity);
  SparseCholesky given;
  const std::vector<int> ordering = original.block_amd_ordering();
  given.analyze(original.matrix(), &ordering);
  SparseCholesky natural;
  natural.analyze_in_stored_order(original.matrix());
  const BlockPattern relabelled = pattern_of(label);
  SparseCholesky stored;
  stored.analyze_in_stored_order(relabelled.matrix());
  EXPECT_EQ(stored.factor_nonzeros(), given.factor_nonzeros());
  EXPECT_LT(2 * stored.factor_nonzeros(), natural.factor_nonzeros());

  ASSERT_EQ(stored.factorize(relabelled.matrix()), FactorizationStatus::kSuccess);
  const Eigen::VectorXd rhs = Eigen::VectorXd::NullaryExpr(blocks * B, [&] { return normal(rng); });
  Eigen::VectorXd rhs_relabelled(blocks * B);
  for (int b = 0; b < blocks; ++b) rhs_relabelled.segment<3>(label[static_cast<std::size_t>(b)] * B) = rhs.segment<3>(b * B);
  const Eigen::VectorXd x_relabelled = stored.solve(rhs_relabelled);
  Eigen::VectorXd x(blocks * B);
  for (int b = 0; b < blocks; ++b) x.segment<3>(b * B) = x_relabelled.segment<3>(label[static_cast<std::size_t>(b)] * B);
  const Eigen::VectorXd expected = dense.llt().solve(rhs);
  EXPECT_LT((x - expected).norm(), 1e-9 * expected.norm());
}

// J A^-1 J^T from forward solves along elimination-tree paths (SparseCholesky::
// solve_lower_sparse, GNC's innovation test) equals the dense inverse's, for Jacobians on two
// random blocks of a random block-sparse SPD matrix; solve() still works after the conversion
// to a simplicial LL^T, and the reach is smaller than the matrix.
TEST(SparseCholesky, SparseForwardSolvesGiveSelectedBlocksOfTheInverse) {
  const int blocks = 200;
  constexpr int B = 3;
  std::mt19937 rng(5);
  std::normal_distribution<double> normal;
  std::vector<std::pair<int, int>> pairs = chain_and_random_pairs(blocks, 80, rng);
  for (auto& [a, b] : pairs) std::tie(a, b) = std::pair(std::min(a, b), std::max(a, b));
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  const std::vector<int> label = block_amd_labels(blocks, pairs);
  std::vector<int> variable(static_cast<std::size_t>(blocks));
  for (int b = 0; b < blocks; ++b) variable[static_cast<std::size_t>(b)] = b;
  apply_block_labels(label, variable, pairs);  // blocks now in elimination order
  for (auto& [a, b] : pairs) std::tie(a, b) = std::pair(std::min(a, b), std::max(a, b));
  Eigen::MatrixXd dense = Eigen::MatrixXd::Identity(blocks * B, blocks * B);
  BlockPattern pattern(blocks, B, pairs);
  for (int b = 0; b < blocks; ++b) {
    const Eigen::Matrix<double, B, B, Eigen::RowMajor> I = Eigen::Matrix<double, B, B>::Identity();
    pattern.add_diagonal(b, I.data());
  }
  for (const auto& [a, b] : pairs) {
    const Eigen::Matrix<double, 3, 6> J = Eigen::Matrix<double, 3, 6>::NullaryExpr([&] { return normal(rng); });
    const Eigen::Matrix<double, 6, 6> H = J.transpose() * J;
    dense.block<B, B>(a * B, a * B) += H.block<B, B>(0, 0);
    dense.block<B, B>(b * B, b * B) += H.block<B, B>(3, 3);
    dense.block<B, B>(a * B, b * B) += H.block<B, B>(0, 3);
    dense.block<B, B>(b * B, a * B) += H.block<B, B>(3, 0);
    const Eigen::Matrix<double, B, B, Eigen::RowMajor> Haa = H.block<B, B>(0, 0);
    const Eigen::Matrix<double, B, B, Eigen::RowMajor> Hbb = H.block<B, B>(3, 3);
    const Eigen::Matrix<double, B, B, Eigen::RowMajor> Hab = H.block<B, B>(0, 3);
    pattern.add_diagonal(a, Haa.data());
    pattern.add_diagonal(b, Hbb.data());
    pattern.add_off_diagonal(a, b, Hab.data());
  }
  SparseCholesky cholesky;
  cholesky.analyze_in_stored_order(pattern.matrix());
  ASSERT_EQ(cholesky.factorize(pattern.matrix()), FactorizationStatus::kSuccess);
  const Eigen::MatrixXd inverse = dense.inverse();
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(blocks * B);
  std::vector<int> reach;
  std::uniform_int_distribution<int> pick(0, blocks - 1);
  std::size_t largest_reach = 0;
  for (int trial = 0; trial < 50; ++trial) {
    const int a = pick(rng);
    int b = pick(rng);
    if (b == a) b = (a + 1) % blocks;
    const Eigen::Matrix<double, 3, 6> J = Eigen::Matrix<double, 3, 6>::NullaryExpr([&] { return normal(rng); });
    std::vector<int> rows;
    for (int d = 0; d < B; ++d) rows.push_back(a * B + d);
    for (int d = 0; d < B; ++d) rows.push_back(b * B + d);
    Eigen::MatrixXd Y;
    for (int k = 0; k < 3; ++k) {
      rhs.segment<B>(a * B) = J.block<1, B>(k, 0).transpose();
      rhs.segment<B>(b * B) = J.block<1, B>(k, B).transpose();
      const double* y = cholesky.solve_lower_sparse(rows, rhs, reach);
      if (k == 0) Y.resize(static_cast<Eigen::Index>(reach.size()), 3);
      ASSERT_EQ(static_cast<Eigen::Index>(reach.size()), Y.rows());
      for (std::size_t q = 0; q < reach.size(); ++q) Y(static_cast<Eigen::Index>(q), k) = y[reach[q]];
    }
    largest_reach = std::max(largest_reach, reach.size());
    Eigen::MatrixXd expected(3, 3);
    Eigen::MatrixXd Jfull = Eigen::MatrixXd::Zero(3, blocks * B);
    Jfull.block<3, B>(0, a * B) = J.leftCols<B>();
    Jfull.block<3, B>(0, b * B) = J.rightCols<B>();
    expected = Jfull * inverse * Jfull.transpose();
    const Eigen::MatrixXd K = Y.transpose() * Y;
    EXPECT_LT((K - expected).norm(), 1e-9 * expected.norm()) << "blocks " << a << ", " << b;
  }
  EXPECT_LT(largest_reach, static_cast<std::size_t>(blocks * B));
  const Eigen::VectorXd x_expected = Eigen::VectorXd::NullaryExpr(blocks * B, [&] { return normal(rng); });
  const Eigen::VectorXd x = cholesky.solve(Eigen::VectorXd(dense * x_expected));
  EXPECT_LT((x - x_expected).norm(), 1e-9 * x_expected.norm());
}

// Edges below OptimizerOptions::coupling_weight_floor enter the cost and the gradient exactly but
// not the Hessian (GNC's fading false loop closures): the minimum stays where it is, and the
// factor is smaller, since those edges join distant poses.
TEST(Optimizer, WeakEdgesKeptOutOfTheFactorLeaveTheMinimumWhereItIs) {
  CAIRN_REQUIRE_DATA("posegraph/se-sync/intel.g2o");
  const io::GraphFile file = io::read_graph(test::data_path("posegraph/se-sync/intel.g2o").string());
  std::visit(
      [&](const auto& original) {
        auto corrupted = original;
        add_false_loop_closures(corrupted, OutlierOptions{300, 5, 10.0});
        auto start = make_problem(corrupted, "intel + 300 false loop closures");
        // From the chordal start of the uncorrupted graph, so both solves face one basin.
        auto uncorrupted = make_problem(original, "intel");
        initialize_chordal(uncorrupted);
        ASSERT_EQ(uncorrupted.T_world_pose.size(), start.T_world_pose.size());
        start.T_world_pose = uncorrupted.T_world_pose;
        OptimizerOptions options;
        // Both to the gradient or step tolerance: the weak edges leave flat directions, along
        // which the cost tolerance would stop the two solves at different points.
        options.function_tolerance = 0.0;
        options.max_iterations = 500;
        options.edge_weights.assign(start.edges.size(), 1.0);
        for (std::size_t e = original.edges.size(); e < start.edges.size(); ++e) options.edge_weights[e] = 1e-4;
        auto coupled = start;
        const OptimizerSummary all = optimize(coupled, options);
        options.coupling_weight_floor = 1e-3;
        auto decoupled = start;
        const OptimizerSummary strong = optimize(decoupled, options);
        ASSERT_EQ(all.termination, TerminationType::kConvergence) << all.brief_report();
        ASSERT_EQ(strong.termination, TerminationType::kConvergence) << strong.brief_report();
        EXPECT_NEAR(strong.final_cost, all.final_cost, 1e-9 * all.final_cost);
        double worst = 0.0;
        for (std::size_t k = 0; k < coupled.T_world_pose.size(); ++k) {
          worst = std::max(worst, (coupled.T_world_pose[k].inverse() * decoupled.T_world_pose[k]).log().norm());
        }
        EXPECT_LT(worst, 1e-5);
        EXPECT_LT(2 * strong.factor_nonzeros, all.factor_nonzeros)
            << "300 random false loop closures fill the factor in: " << strong.factor_nonzeros << " vs "
            << all.factor_nonzeros;
        std::printf("coupled: %d iterations, factor %zu non-zeros; weak edges out: %d iterations, %zu non-zeros; poses within %.2e\n",
                    all.iterations, all.factor_nonzeros, strong.iterations, strong.factor_nonzeros, worst);
      },
      file.graph);
}

// A workspace carried from one solve to the next with changed edge weights (GNC's outer loop)
// keeps the analysis while no edge's weight is 0, and its last factorisation preconditions the
// next solve: same minimum as a fresh solve, no factorisation at all when the weights change
// little. With weights at 0 the pattern is rebuilt without those edges.
TEST(Optimizer, WorkspaceCarriesTheAnalysisAndFactorisationToTheNextSolve) {
  CAIRN_REQUIRE_DATA("posegraph/se-sync/intel.g2o");
  with_chordal_start("intel.g2o", [&](auto start) {
    OptimizerOptions options;
    options.edge_weights.assign(start.edges.size(), 1.0);
    options.reuse_step_fraction = 1.0;  // as GNC's warm-started solves (GncOptions)
    OptimizerWorkspace workspace;
    auto carried = start;
    ASSERT_TRUE(optimize(carried, options, &workspace).is_solution_usable());
    EXPECT_EQ(workspace.analyses, 1);
    for (std::size_t e = 0; e < start.edges.size(); ++e) {
      if (start.edges[e].kind == EdgeKind::kLoopClosure) options.edge_weights[e] = 0.99;
    }
    const OptimizerSummary second = optimize(carried, options, &workspace);
    auto fresh = carried;
    fresh.T_world_pose = start.T_world_pose;
    const OptimizerSummary reference = optimize(fresh, options);
    EXPECT_EQ(workspace.analyses, 1) << "no weight is 0: the analysis is kept";
    EXPECT_EQ(second.factorizations, 0) << second.brief_report();
    EXPECT_GE(second.iterations, 1);
    EXPECT_NEAR(second.final_cost, reference.final_cost, 1e-8 * reference.final_cost);
    // Every loop closure out: more than 2 % of the pattern inactive, so it is analysed anew.
    for (std::size_t e = 0; e < start.edges.size(); ++e) {
      if (start.edges[e].kind == EdgeKind::kLoopClosure) options.edge_weights[e] = 0.0;
    }
    const OptimizerSummary third = optimize(carried, options, &workspace);
    EXPECT_EQ(workspace.analyses, 2);
    EXPECT_TRUE(third.is_solution_usable());
    EXPECT_LT(third.final_cost, 1e-6 * second.final_cost) << "odometry alone is a tree: zero cost";
  });
}

// The default undamped start (initial_trust_region_radius 1e16) against Ceres' default damping
// (radius 1e4) from the same chordal start, Ceres' stopping rule: the same minimum in far fewer
// iterations, because the damping holds back the steps along the graphs' flat directions.
TEST(Optimizer, UndampedStartConvergesInFewerIterationsThanCeresDefaultDamping) {
  for (const char* file : {"CSAIL.g2o", "MIT.g2o", "manhattan.g2o", "sphere2500.g2o"}) {
    CAIRN_REQUIRE_DATA(std::string("posegraph/se-sync/") + file);
    with_chordal_start(file, [&](auto start) {
      OptimizerOptions options;
      options.function_tolerance = 1e-6;
      options.max_iterations = 50;
      auto undamped = start;
      const OptimizerSummary fast = optimize(undamped, options);
      auto damped = start;
      options.initial_trust_region_radius = 1e4;
      const OptimizerSummary slow = optimize(damped, options);
      std::printf("%s: radius 1e16 %d iterations, cost %.10g; radius 1e4 %d iterations, cost %.10g\n", file,
                  fast.iterations, fast.final_cost, slow.iterations, slow.final_cost);
      EXPECT_LE(fast.iterations, 6) << file;
      EXPECT_GE(slow.iterations, 2 * fast.iterations) << file;
      EXPECT_LE(fast.final_cost, slow.final_cost * (1.0 + 1e-6)) << file;
    });
  }
}

INSTANTIATE_TEST_SUITE_P(
    SeSync, SeSyncOptima,
    ::testing::Values(Optimum{"tinyGrid3D.g2o", 18.519386832583514}, Optimum{"smallGrid3D.g2o", 1025.3980207410884},
                      Optimum{"sphere2500.g2o", 1687.005671042642}, Optimum{"torus3D.g2o", 24227.041529068931},
                      Optimum{"cubicle.g2o", 717.13403923218959}, Optimum{"sphere_bignoise_vertex3.g2o", 2961756.505474133},
                      Optimum{"CSAIL.g2o", 31.703715883737345}, Optimum{"MIT.g2o", 61.154115524460529},
                      Optimum{"intel.g2o", 52.348227285553435}, Optimum{"manhattan.g2o", 6431.3913872099165},
                      Optimum{"city10000.g2o", 638.62461965124362}, Optimum{"kitti_00.g2o", 125.69351454148867},
                      Optimum{"kitti_02.g2o", 108.35113897942772}, Optimum{"kitti_05.g2o", 276.51437504386098}),
    [](const ::testing::TestParamInfo<Optimum>& param_info) {
      std::string name = param_info.param.file;
      name = name.substr(0, name.find('.'));
      for (char& c : name) {
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
      }
      return name;
    });

}  // namespace
}  // namespace cairn::backend

namespace cairn::backend {
namespace {

// Square world with exact measurements plus as many random false loop closures as true ones:
// GNC must reject exactly the false ones and land on the truth; least squares must not.
TEST(Gnc, RejectsEveryFalseLoopClosureAndKeepsTheTrueOnes) {
  for (const bool three_d : {false, true}) {
    auto run = [&](auto tag) {
      using Group = decltype(tag);
      std::vector<Group> truth;
      auto graph = square_world<Group>(4, truth);
      std::size_t true_loops = 0;
      for (const auto& e : graph.edges) true_loops += (e.to - e.from != 1);
      const std::size_t original_edges = graph.edges.size();
      add_false_loop_closures(graph, OutlierOptions{static_cast<int>(true_loops), 7, 10.0});

      auto least_squares = make_problem(graph, "square+outliers");
      initialize_odometry(least_squares);
      optimize(least_squares, OptimizerOptions{});
      double ls_error = 0.0;
      for (std::size_t k = 0; k < truth.size(); ++k) {
        ls_error = std::max(ls_error, (truth[k].translation() - least_squares.T_world_pose[k].translation()).norm());
      }
      EXPECT_GT(ls_error, 1.0) << "least squares should be bent by the false loop closures";

      auto problem = make_problem(graph, "square+outliers");
      initialize_odometry(problem);
      const GncSummary summary = optimize_gnc(problem, GncOptions{});
      std::size_t false_rejected = 0;
      std::size_t true_rejected = 0;
      for (const std::size_t e : summary.rejected_edges) (e >= original_edges ? false_rejected : true_rejected)++;
      EXPECT_EQ(false_rejected, true_loops) << summary.message;
      EXPECT_EQ(true_rejected, 0u);
      for (std::size_t k = 0; k < truth.size(); ++k) {
        EXPECT_LT((truth[k].translation() - problem.T_world_pose[k].translation()).norm(), 1e-6) << k;
      }
    };
    if (three_d) {
      run(core::SE3());
    } else {
      run(core::SE2());
    }
  }
}

// OptimizerOptions::should_stop (SIGINT in the CLI) ends the solve before the next iteration,
// at the last accepted point: a usable, consistent estimate whose cost is the summary's.
TEST(Optimizer, ShouldStopEndsAtTheLastAcceptedStep) {
  CAIRN_REQUIRE_DATA("posegraph/se-sync/intel.g2o");
  const io::GraphFile file = io::read_graph(test::data_path("posegraph/se-sync/intel.g2o").string());
  const auto& graph = std::get<io::PoseGraph2D>(file.graph);
  auto full = make_problem(graph, "intel");
  const OptimizerSummary complete = optimize(full, OptimizerOptions{});
  ASSERT_GT(complete.iterations, 3);

  auto problem = make_problem(graph, "intel");
  OptimizerOptions options;
  int polls = 0;
  options.should_stop = [&] { return ++polls > 2; };
  const OptimizerSummary stopped = optimize(problem, options);
  EXPECT_EQ(stopped.termination, TerminationType::kInterrupted);
  EXPECT_TRUE(stopped.is_solution_usable());
  EXPECT_EQ(stopped.iterations, 2);
  EXPECT_EQ(to_string(stopped.termination), "interrupted");
  EXPECT_LT(stopped.final_cost, stopped.initial_cost);
  EXPECT_GT(stopped.final_cost, complete.final_cost);
  EXPECT_NEAR(evaluate_cost(problem, options), stopped.final_cost, 1e-9 * stopped.final_cost);

  // Stopped before the first iteration: the start, untouched.
  auto untouched = make_problem(graph, "intel");
  const auto start = untouched.T_world_pose;
  options.should_stop = [] { return true; };
  const OptimizerSummary at_once = optimize(untouched, options);
  EXPECT_EQ(at_once.termination, TerminationType::kInterrupted);
  EXPECT_EQ(at_once.iterations, 0);
  for (std::size_t k = 0; k < start.size(); ++k) {
    EXPECT_EQ(start[k].translation(), untouched.T_world_pose[k].translation()) << k;
  }
}

// GNC stopped mid-graduation skips its later stages and says so; its weights stay binary and
// its rejected edges are those with weight 0.
TEST(Gnc, ShouldStopSkipsTheRemainingStages) {
  std::vector<core::SE2> truth;
  auto graph = square_world<core::SE2>(4, truth);
  add_false_loop_closures(graph, OutlierOptions{20, 7, 10.0});
  auto problem = make_problem(graph, "square+outliers");
  initialize_odometry(problem);
  GncOptions options;
  int polls = 0;
  options.inner.should_stop = [&] { return ++polls > 3; };
  const GncSummary summary = optimize_gnc(problem, options);
  EXPECT_TRUE(summary.interrupted);
  EXPECT_NE(summary.message.find("interrupted"), std::string::npos) << summary.message;
  EXPECT_FALSE(summary.restarted);
  EXPECT_EQ(summary.readmitted_by_innovation, 0);
  ASSERT_EQ(summary.weights.size(), problem.edges.size());
  std::size_t zero = 0;
  for (const double w : summary.weights) {
    EXPECT_TRUE(w == 0.0 || w == 1.0) << w;
    zero += w == 0.0;
  }
  EXPECT_EQ(zero, summary.rejected_edges.size());

  auto uninterrupted = make_problem(graph, "square+outliers");
  initialize_odometry(uninterrupted);
  EXPECT_FALSE(optimize_gnc(uninterrupted, GncOptions{}).interrupted);
}

}  // namespace
}  // namespace cairn::backend

namespace cairn::backend {
namespace {

// Marginal covariances from the sparse factorisation equal the blocks of the dense inverse of
// J^T J built here independently from numeric Jacobians.
TEST(Covariance, MatchesTheDenseInverseOfTheNormalMatrix) {
  std::vector<core::SE2> truth;
  auto graph = square_world<core::SE2>(2, truth);
  auto problem = make_problem(graph, "square");
  optimize(problem, OptimizerOptions{});
  const int n = problem.size() - 1;  // pose 0 fixed
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  for (const auto& e : problem.edges) {
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(3, 3 * n);
    for (int side = 0; side < 2; ++side) {
      const int p = side == 0 ? e.i : e.j;
      if (p == 0) continue;
      for (int k = 0; k < 3; ++k) {
        core::SE2::Tangent d = core::SE2::Tangent::Zero();
        d[k] = 1e-6;
        auto plus = problem.T_world_pose;
        auto minus = problem.T_world_pose;
        plus[static_cast<std::size_t>(p)] = plus[static_cast<std::size_t>(p)] * core::SE2::exp(d);
        minus[static_cast<std::size_t>(p)] = minus[static_cast<std::size_t>(p)] * core::SE2::exp(-d);
        J.col(3 * (p - 1) + k) =
            (GeodesicFactor<core::SE2>::evaluate(plus[static_cast<std::size_t>(e.i)], plus[static_cast<std::size_t>(e.j)], e, nullptr, nullptr) -
             GeodesicFactor<core::SE2>::evaluate(minus[static_cast<std::size_t>(e.i)], minus[static_cast<std::size_t>(e.j)], e, nullptr, nullptr)) /
            2e-6;
      }
    }
    H += J.transpose() * J;
  }
  const Eigen::MatrixXd dense = H.inverse();
  const auto marginals = marginal_covariances(problem, {0, 5, n});
  ASSERT_TRUE(marginals.has_value());
  EXPECT_EQ(marginals->covariance[0], Eigen::Matrix3d::Zero());
  for (const int p : {5, n}) {
    const Eigen::Matrix3d expected = dense.block(3 * (p - 1), 3 * (p - 1), 3, 3);
    const Eigen::Matrix3d got = marginals->covariance[p == 5 ? 1 : 2];
    EXPECT_LT((got - expected).cwiseAbs().maxCoeff(), 1e-6 * expected.cwiseAbs().maxCoeff()) << got << "\n" << expected;
  }
}

}  // namespace
}  // namespace cairn::backend
