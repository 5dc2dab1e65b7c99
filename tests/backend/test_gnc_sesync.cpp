/// \file
/// Issue 3's outlier criterion on SE-Sync's graphs: with as many random false loop closures
/// added as there are true ones (cairn corrupt --seed 1, Vertigo's "random" outliers), GNC with
/// default options rejects every false one, keeps at least 99 % of the true ones, and ends
/// within 0.05 m RMS in position (3D: and 0.5 deg RMS in rotation) of the outlier-free optimum;
/// least squares on the same input is visibly bent. The reference is computed here, from the
/// chordal start, by the least-squares solver (its optimum is tested against SE-Sync's
/// certified ones in test_optimizer.cpp).

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <variant>
#include <vector>

#include "cairn/backend/gnc.hpp"
#include "cairn/backend/initialization.hpp"
#include "cairn/backend/optimizer.hpp"
#include "cairn/backend/outliers.hpp"
#include "cairn/io/graph_io.hpp"
#include "test_data.hpp"

namespace cairn::backend {
namespace {

struct Case {
  const char* file;
  /// Runs only with CAIRN_LONG_TESTS=1 (minutes on two cores).
  bool long_running;
};

void PrintTo(const Case& c, std::ostream* os) { *os << c.file; }

template <class Group>
double rotation_angle(const Group& a, const Group& b) {
  const typename Group::Tangent xi = (a.inverse() * b).log();
  if constexpr (Group::kDoF == 3) {
    return std::abs(xi[2]);
  } else {
    return xi.template tail<3>().norm();
  }
}

struct Difference {
  double position_rms = 0.0;
  double rotation_rms_deg = 0.0;
};

template <class Group>
Difference difference(const std::vector<Group>& a, const std::vector<Group>& b) {
  double p = 0.0;
  double r = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    p += (a[k].translation() - b[k].translation()).squaredNorm();
    r += std::pow(rotation_angle(a[k], b[k]), 2);
  }
  const double n = static_cast<double>(a.size());
  return {std::sqrt(p / n), std::sqrt(r / n) * 180.0 / M_PI};
}

/// GNC from the odometry start on `original` plus as many false loop closures as it has true
/// ones (seed `seed`), scored against `reference`.
struct Outcome {
  std::size_t false_kept = 0;
  std::size_t true_rejected = 0;
  std::size_t true_loops = 0;
  Difference to_reference;
  GncSummary summary;
};

template <class Group>
Outcome run_corrupted(const io::PoseGraphT<Group>& original, const PoseGraphProblem<Group>& reference,
                      const std::string& relative, std::uint64_t seed, const GncOptions& options) {
  Outcome out;
  for (const auto& e : reference.edges) out.true_loops += e.kind == EdgeKind::kLoopClosure;
  auto corrupted = original;
  add_false_loop_closures(corrupted, OutlierOptions{static_cast<int>(out.true_loops), seed, 10.0});
  auto problem = make_problem(corrupted, relative);
  initialize_odometry(problem);
  out.summary = optimize_gnc(problem, options);
  std::size_t false_rejected = 0;
  for (const std::size_t e : out.summary.rejected_edges) (e >= original.edges.size() ? false_rejected : out.true_rejected)++;
  out.false_kept = out.true_loops - false_rejected;
  out.to_reference = difference<Group>(problem.T_world_pose, reference.T_world_pose);
  return out;
}

/// The outlier-free optimum from the chordal start.
template <class Group>
PoseGraphProblem<Group> reference_optimum(const io::PoseGraphT<Group>& original, const std::string& relative) {
  auto reference = make_problem(original, relative);
  initialize_chordal(reference);
  EXPECT_TRUE(optimize(reference, OptimizerOptions{}).is_solution_usable());
  return reference;
}

/// Issue 3's criterion for one outcome.
void expect_criterion(const Outcome& o, const std::string& what) {
  EXPECT_EQ(o.false_kept, 0u) << what;
  EXPECT_LE(static_cast<double>(o.true_rejected), 0.01 * static_cast<double>(o.true_loops))
      << what << ": " << o.true_rejected << " of " << o.true_loops << " true loop closures rejected";
  EXPECT_LT(o.to_reference.position_rms, 0.05) << what;
  EXPECT_LT(o.to_reference.rotation_rms_deg, 0.5) << what;
  std::printf("%s: %zu false kept, %zu of %zu true rejected, RMS %.2e m / %.2e deg, %.1f s%s\n", what.c_str(),
              o.false_kept, o.true_rejected, o.true_loops, o.to_reference.position_rms,
              o.to_reference.rotation_rms_deg, o.summary.total_s,
              o.summary.restarted ? " (restarted from the chordal relaxation)" : "");
}

class GncOnSeSync : public ::testing::TestWithParam<Case> {};

TEST_P(GncOnSeSync, RejectsEveryFalseLoopClosureAndKeepsTheTrueOnes) {
  const Case& c = GetParam();
  const std::string relative = std::string("posegraph/se-sync/") + c.file;
  CAIRN_REQUIRE_DATA(relative);
  if (c.long_running && std::getenv("CAIRN_LONG_TESTS") == nullptr) {
    GTEST_SKIP() << c.file << " takes minutes on two cores: run with CAIRN_LONG_TESTS=1 (see docs/backend.md)";
  }
  const io::GraphFile file = io::read_graph(test::data_path(relative).string());
  std::visit(
      [&](const auto& original) {
        using Group = std::decay_t<decltype(original.vertices[0].T_world_pose)>;
        auto reference = make_problem(original, relative);
        initialize_chordal(reference);
        ASSERT_TRUE(optimize(reference, OptimizerOptions{}).is_solution_usable());

        std::size_t true_loops = 0;
        for (const auto& e : reference.edges) true_loops += e.kind == EdgeKind::kLoopClosure;
        auto corrupted = original;
        add_false_loop_closures(corrupted, OutlierOptions{static_cast<int>(true_loops), 1, 10.0});
        const std::size_t true_edges = original.edges.size();

        // Least squares from the same (odometry) start, 20 iterations (each factorises a matrix the
        // false loop closures have filled in; bent far beyond 1 m long before).
        auto least_squares = make_problem(corrupted, relative);
        initialize_odometry(least_squares);
        OptimizerOptions ls_options;
        ls_options.max_iterations = 20;
        optimize(least_squares, ls_options);
        const Difference ls = difference<Group>(least_squares.T_world_pose, reference.T_world_pose);
        EXPECT_GT(ls.position_rms, 1.0) << "least squares should be visibly bent by the false loop closures";

        auto problem = make_problem(corrupted, relative);
        initialize_odometry(problem);
        const GncSummary summary = optimize_gnc(problem, GncOptions{});
        std::size_t false_rejected = 0;
        std::size_t true_rejected = 0;
        for (const std::size_t e : summary.rejected_edges) (e >= true_edges ? false_rejected : true_rejected)++;
        const Difference gnc = difference<Group>(problem.T_world_pose, reference.T_world_pose);
        RecordProperty("true_rejected", std::to_string(true_rejected));
        RecordProperty("position_rms_m", std::to_string(gnc.position_rms));
        RecordProperty("least_squares_position_rms_m", std::to_string(ls.position_rms));
        RecordProperty("gnc_s", std::to_string(summary.total_s));
        EXPECT_EQ(false_rejected, true_loops) << summary.message;
        EXPECT_LE(static_cast<double>(true_rejected), 0.01 * static_cast<double>(true_loops))
            << true_rejected << " of " << true_loops << " true loop closures rejected";
        EXPECT_LT(gnc.position_rms, 0.05);
        if constexpr (Group::kDoF == 6) {
          EXPECT_LT(gnc.rotation_rms_deg, 0.5);
        }
        std::printf("%s: %zu of %zu false rejected, %zu of %zu true rejected, RMS %.2e m / %.2e deg "
                    "(least squares %.3g m), threshold %.3g, noise variance x %.3g, %.1f s\n",
                    c.file, false_rejected, true_loops, true_rejected, true_loops, gnc.position_rms,
                    gnc.rotation_rms_deg, ls.position_rms, summary.threshold_chi2, summary.noise_variance_factor,
                    summary.total_s);
      },
      file.graph);
}

// Seeds other than 1 (measured on intel, 2026-11-24: seeds 2-5 each kept one false loop
// closure, 0.2-0.7 m RMS off, before the leave-one-out test): GNC can bend the map around a
// false loop closure until it fits. With readmission at the full threshold (readmission_factor
// 1; the default's stricter readmission keeps these out before), the leave-one-out test
// (GncOptions::reject_by_leave_one_out) is what rejects them on seeds 2 and 3.
TEST(GncLeaveOneOut, RejectsFalseLoopClosuresTheMapWasBentAround) {
  const std::string relative = "posegraph/se-sync/intel.g2o";
  CAIRN_REQUIRE_DATA(relative);
  const io::GraphFile file = io::read_graph(test::data_path(relative).string());
  const auto& original = std::get<io::PoseGraph2D>(file.graph);
  const auto reference = reference_optimum(original, relative);
  for (const std::uint64_t seed : {2u, 3u}) {
    Outcome outcome[2];
    for (const bool leave_one_out : {false, true}) {
      GncOptions options;
      options.readmission_factor = 1.0;
      options.reject_by_leave_one_out = leave_one_out;
      outcome[leave_one_out] = run_corrupted(original, reference, relative, seed, options);
    }
    EXPECT_GE(outcome[0].false_kept, 1u) << "seed " << seed << ": without the test GNC keeps a false loop closure";
    EXPECT_GT(outcome[0].to_reference.position_rms, 0.05) << "seed " << seed;
    EXPECT_GE(outcome[1].summary.rejected_by_leave_one_out, 1) << "seed " << seed;
    expect_criterion(outcome[1], "intel seed " + std::to_string(seed) + ", with leave-one-out");
  }
}

// A rejected loop closure needs a smaller innovation to come back than an accepted one needs to
// stay (GncOptions::readmission_factor, docs/backend.md). With the readmission at the full
// threshold, intel seed 4 readmits a false loop closure that bends a weakly held part of the map
// (0.47 m RMS off); so do intel 5 and manhattan 4 and 8. With the default none do.
void expect_readmission_keeps_out(const char* name, const std::vector<std::uint64_t>& seeds) {
  const std::string relative = std::string("posegraph/se-sync/") + name;
  CAIRN_REQUIRE_DATA(relative);
  const io::GraphFile file = io::read_graph(test::data_path(relative).string());
  const auto& original = std::get<io::PoseGraph2D>(file.graph);
  const auto reference = reference_optimum(original, relative);
  for (const std::uint64_t seed : seeds) {
    expect_criterion(run_corrupted(original, reference, relative, seed, GncOptions{}),
                     std::string(name) + " seed " + std::to_string(seed));
  }
  if (std::string(name) == "intel.g2o") {
    GncOptions full;
    full.readmission_factor = 1.0;
    const Outcome o = run_corrupted(original, reference, relative, 4, full);
    EXPECT_GE(o.false_kept, 1u) << "intel seed 4, readmission at the full threshold: a false loop closure comes back";
    EXPECT_GT(o.to_reference.position_rms, 0.05);
  }
}

// One seed of each graph in `make test` (intel 4 with and without the stricter readmission,
// manhattan 4); all four seeds (about 85 s) on demand:
//   build/tests/backend/test_backend --gtest_also_run_disabled_tests --gtest_filter='*DISABLED_StricterReadmission*'
TEST(GncReadmission, StricterReadmissionKeepsOutWhatBendsTheMap) {
  expect_readmission_keeps_out("intel.g2o", {4});
  expect_readmission_keeps_out("manhattan.g2o", {4});
}
TEST(GncReadmission, DISABLED_StricterReadmissionKeepsOutWhatBendsTheMapOnFourSeeds) {
  expect_readmission_keeps_out("intel.g2o", {4, 5});
  expect_readmission_keeps_out("manhattan.g2o", {4, 8});
}

// city10000, seed 4: the graduation folded two stretches (poses 833-847 and 884-896, up to 9 m
// off) while false loop closures still pulled on them; their true loop closures were then
// rejected (72 of 10,688, 0.27 m RMS) and least squares over every true edge from there stays in
// the fold (chi2 2274 against 512). The restart from the chordal relaxation of the accepted
// edges undoes it. GNC about 25 s alone, 50 s under ctest -j2 (2026-11-24); the whole test took
// 143-189 s of make test's serial time (2026-11-30), the largest share of any, so like the other
// whole city10000 runs it is not run by make test. Run it with
//   build/tests/backend/test_backend --gtest_also_run_disabled_tests --gtest_filter='GncRestart.*'
TEST(GncRestart, DISABLED_UndoesWhatTheGraduationFoldedOnCity10000) {
  const std::string relative = "posegraph/se-sync/city10000.g2o";
  CAIRN_REQUIRE_DATA(relative);
  const io::GraphFile file = io::read_graph(test::data_path(relative).string());
  const auto& original = std::get<io::PoseGraph2D>(file.graph);
  const auto reference = reference_optimum(original, relative);
  const Outcome o = run_corrupted(original, reference, relative, 4, GncOptions{});
  EXPECT_TRUE(o.summary.restarted);
  expect_criterion(o, "city10000 seed 4");
}

std::string case_name(const ::testing::TestParamInfo<Case>& param_info) {
  const std::string& file = param_info.param.file;
  return file.substr(0, file.find('.'));
}

INSTANTIATE_TEST_SUITE_P(SeSync, GncOnSeSync,
                         ::testing::Values(Case{"intel.g2o", false}, Case{"manhattan.g2o", false},
                                           Case{"sphere2500.g2o", false}),
                         case_name);
// city10000, the whole graph: 268 s of make test's serial time (GNC about 20 s of it alone, least
// squares on the corrupted graph most of the rest), so it is not run by make test (its restart
// case above is). Run it with
//   build/tests/backend/test_backend --gtest_also_run_disabled_tests --gtest_filter='DISABLED_SeSyncWhole*'
INSTANTIATE_TEST_SUITE_P(DISABLED_SeSyncWhole, GncOnSeSync, ::testing::Values(Case{"city10000.g2o", false}),
                         case_name);

}  // namespace
}  // namespace cairn::backend
