// End-to-end landmark SLAM on the simulator's `landmarks` scenario (in memory): convergence with
// known association, graph vs EKF, NEES over Monte-Carlo seeds, association with clutter, bad
// observations. Every number asserted is measured against the simulator's ground truth.

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <vector>

#include "cairn/filter/chi_square.hpp"
#include "cairn/landmarks/clutter.hpp"
#include "cairn/landmarks/landmark_slam.hpp"
#include "simulated_run.hpp"

namespace cairn::landmarks {
namespace {

using testing::simulated_run;

// Dead reckoning's position error against ground truth (RMSE at the ground-truth times): what
// SLAM must beat.
double dead_reckoning_ate(const LandmarkRun& run) {
  double sum = 0.0;
  std::size_t n = 0;
  for (const TimedPose& truth : run.ground_truth) {
    const auto odometry = odometry_at(run.odometry, truth.time);
    if (!odometry) continue;
    sum += (odometry->head<2>() - truth.pose.head<2>()).squaredNorm();
    ++n;
  }
  return std::sqrt(sum / static_cast<double>(n));
}

LandmarkSlamOptions options_for(Method method, Association association, int checkpoints = 4) {
  LandmarkSlamOptions options;
  options.method = method;
  options.association = association;
  options.nees_checkpoints = checkpoints;
  return options;
}

TEST(LandmarkSlam, BothMethodsConvergeWithKnownAssociationAndGraphIsNoWorse) {
  for (const std::uint64_t seed : {1u, 2u, 3u}) {
    const LandmarkRun run = simulated_run(seed);
    const double dead_reckoning = dead_reckoning_ate(run);
    const LandmarkSlamResult ekf = run_landmark_slam(run, options_for(Method::kEkf, Association::kKnown, 1));
    const LandmarkSlamResult graph = run_landmark_slam(run, options_for(Method::kGraph, Association::kKnown, 1));
    std::printf("seed %lu: dead reckoning ATE %.4f m; EKF ATE %.4f m (landmarks %.4f m); graph ATE %.4f m "
                "(landmarks %.4f m, %d LM iterations, %s)\n",
                static_cast<unsigned long>(seed), dead_reckoning, ekf.report.ate_rmse_m, ekf.report.landmark_rmse_m,
                graph.report.ate_rmse_m, graph.report.landmark_rmse_m, graph.report.graph_summary.iterations,
                graph.report.graph_summary.message.c_str());
    EXPECT_EQ(ekf.report.ate_poses, run.ground_truth.size());
    EXPECT_EQ(ekf.report.landmarks, run.true_landmarks.size());
    EXPECT_EQ(graph.report.landmarks, run.true_landmarks.size());
    // Converged: centimetre-level errors where dead reckoning drifts by the better part of a metre.
    EXPECT_GT(dead_reckoning, 0.3);
    EXPECT_LT(ekf.report.ate_rmse_m, 0.1);
    EXPECT_LT(graph.report.ate_rmse_m, 0.1);
    EXPECT_LT(ekf.report.landmark_rmse_m, 0.1);
    EXPECT_LT(graph.report.landmark_rmse_m, 0.1);
    EXPECT_EQ(graph.report.graph_summary.status, backend::LandmarkGraphStatus::kConverged);
    // The smoother uses every observation for every pose; the filter only the past ones.
    EXPECT_LE(graph.report.ate_rmse_m, ekf.report.ate_rmse_m);
  }
}

struct NeesTable {
  std::vector<double> time_s;
  std::vector<double> ekf_pose, graph_pose, ekf_landmark, graph_landmark;
};

// Adds one run's NEES at each checkpoint, divided by the number of runs (a running mean).
void add_run(NeesTable* table, const LandmarkSlamReport& ekf, const LandmarkSlamReport& graph, int runs) {
  if (table->time_s.empty()) {
    for (const NeesPoint& p : ekf.nees) table->time_s.push_back(p.time_s);
    const std::size_t n = table->time_s.size();
    table->ekf_pose.assign(n, 0.0);
    table->graph_pose.assign(n, 0.0);
    table->ekf_landmark.assign(n, 0.0);
    table->graph_landmark.assign(n, 0.0);
  }
  for (std::size_t c = 0; c < table->time_s.size(); ++c) {
    table->ekf_pose[c] += ekf.nees[c].pose_nees / runs;
    table->graph_pose[c] += graph.nees[c].pose_nees / runs;
    table->ekf_landmark[c] += ekf.nees[c].landmark_nees_mean / runs;
    table->graph_landmark[c] += graph.nees[c].landmark_nees_mean / runs;
  }
}

// Mean NEES over Monte-Carlo seeds (noise varies, the world stays) at each checkpoint.
NeesTable monte_carlo_nees(int runs, int checkpoints, const std::function<void(sim::Scenario&)>& adjust) {
  NeesTable table;
  for (int r = 0; r < runs; ++r) {
    const LandmarkRun run = simulated_run(static_cast<std::uint64_t>(100 + r), adjust);
    const auto ekf = run_landmark_slam(run, options_for(Method::kEkf, Association::kKnown, checkpoints)).report;
    const auto graph = run_landmark_slam(run, options_for(Method::kGraph, Association::kKnown, checkpoints)).report;
    add_run(&table, ekf, graph, runs);
  }
  return table;
}

void print_table(const char* title, const NeesTable& t, int runs) {
  const filter::ChiSquareBand pose_band = filter::mean_chi_square_band(3.0, runs, 0.95);
  std::printf("%s: mean NEES over %d seeds; pose 95%% band [%.3f, %.3f] (chi2(3 N)/N), landmark mean expected 2\n", title,
              runs, pose_band.lower, pose_band.upper);
  std::printf("  time_s   EKF_pose  graph_pose  EKF_landmarks  graph_landmarks\n");
  for (std::size_t c = 0; c < t.time_s.size(); ++c) {
    std::printf("  %6.1f  %8.3f  %10.3f  %13.3f  %15.3f\n", t.time_s[c], t.ekf_pose[c], t.graph_pose[c], t.ekf_landmark[c],
                t.graph_landmark[c]);
  }
}

bool all_inside(const std::vector<double>& values, const filter::ChiSquareBand& band) {
  for (const double v : values) {
    if (!(v >= band.lower && v <= band.upper)) return false;
  }
  return true;
}

// NEES of pose (3 dof) and landmarks (mean of 2-dof values) averaged over 8 seeds at 6 evenly
// spaced steps, for both methods, in three settings. What is asserted is what was measured on
// this data (docs/landmark-slam.md has the tables); the seeds are fixed, so it is deterministic.
TEST(LandmarkSlam, NeesOverMonteCarloSeeds) {
  constexpr int kRuns = 8;
  const filter::ChiSquareBand band = filter::mean_chi_square_band(3.0, kRuns, 0.95);

  const NeesTable dense = monte_carlo_nees(kRuns, 6, {});
  print_table("default landmarks scenario (60 landmarks, 10 m range)", dense, kRuns);
  // Many landmarks in view: both stay inside the band throughout.
  EXPECT_TRUE(all_inside(dense.ekf_pose, band));
  EXPECT_TRUE(all_inside(dense.graph_pose, band));

  const NeesTable sparse = monte_carlo_nees(kRuns, 6, [](sim::Scenario& s) {
    s.landmark_field.landmarks = 15;
    s.landmarks.max_range_m = 6.0;
  });
  print_table("sparse variant (15 landmarks, 6 m range)", sparse, kRuns);
  // Few landmarks and odometry biases neither method models: the EKF's pose NEES leaves the
  // band, and the landmarks' NEES grows above its mean of 2 for both, less for the graph.
  EXPECT_FALSE(all_inside(sparse.ekf_pose, band));
  EXPECT_GT(sparse.ekf_landmark.back(), 3.0);
  EXPECT_LE(sparse.graph_landmark.back(), sparse.ekf_landmark.back());

  const NeesTable unbiased = monte_carlo_nees(kRuns, 6, [](sim::Scenario& s) {
    s.landmark_field.landmarks = 15;
    s.landmarks.max_range_m = 6.0;
    s.odometry.scale_error = 0.0;
    s.odometry.yaw_scale_error = 0.0;
    s.odometry.yaw_bias_rad_per_m = 0.0;
    s.odometry.slip_rate_per_s = 0.0;
  });
  print_table("sparse variant, odometry without biases or slips (only the white noise both methods model)", unbiased,
              kRuns);
  // With the noise model right, both stay inside the band over this 206 s run.
  EXPECT_TRUE(all_inside(unbiased.ekf_pose, band));
  EXPECT_TRUE(all_inside(unbiased.graph_pose, band));
}

// A landmark world in which no two landmarks are closer than `min_separation_m` (the sensor
// cannot tell apart two posts 0.18 m apart at 10 m, as in the default world: see docs).
std::uint64_t resolvable_world_seed(double min_separation_m) {
  for (std::uint64_t world_seed = 1; world_seed < 200; ++world_seed) {
    sim::LandmarkFieldOptions field;
    field.world_seed = world_seed;
    const sim::WorldWithRoute world = sim::landmark_field_world(field);
    double closest = 1e9;
    const auto& l = world.world.landmarks;
    for (std::size_t a = 0; a < l.size(); ++a) {
      for (std::size_t b = a + 1; b < l.size(); ++b) closest = std::min(closest, (l[a].position - l[b].position).norm());
    }
    if (closest >= min_separation_m) return world_seed;
  }
  return 0;
}

AssociationCounts counts_with_clutter(std::uint64_t seed, std::uint64_t world_seed, Association association) {
  LandmarkRun run = simulated_run(seed, [&](sim::Scenario& s) {
    if (world_seed != 0) s.landmark_field.world_seed = world_seed;
  });
  ClutterOptions clutter;
  clutter.spurious_fraction = 0.1;
  clutter.seed = seed;
  const std::size_t added = add_spurious_observations(&run.observations, clutter);
  const LandmarkSlamResult result = run_landmark_slam(run, options_for(Method::kEkf, association, 1));
  const AssociationCounts& a = result.report.association_counts;
  std::printf("seed %lu world %lu %s: %zu observations (%zu spurious); %zu correct, %zu wrong (%zu spurious accepted), "
              "%zu spurious rejected, %zu landmarks (%zu duplicates, %zu from clutter), %zu candidates expired; ATE %.4f m\n",
              static_cast<unsigned long>(seed), static_cast<unsigned long>(world_seed),
              std::string(to_string(association)).c_str(), a.observations, added, a.paired_correct, a.paired_wrong,
              a.spurious_paired, a.spurious_rejected, a.landmarks_created, a.landmarks_duplicated,
              a.landmarks_from_spurious, a.candidates_expired, result.report.ate_rmse_m);
  EXPECT_EQ(a.spurious_observations, added);
  EXPECT_EQ(a.observations, run.observations.size());
  EXPECT_LT(result.report.ate_rmse_m, 0.1);
  return a;
}

// Measured: JCBB never pairs an observation of one real landmark with another, and creates no
// landmark from clutter. It does accept a few clutter observations (0 and 3 of ~2,300 here, NN:
// 0 and 4): uniform clutter that falls inside a landmark's 99% gate in a step where that
// landmark was not detected (5%), or closer to its prediction than the real observation, is
// indistinguishable from a real observation for any gating method. We assert the measured bound.
TEST(LandmarkSlam, JcbbMakesNoWrongAssociationWithTenPercentClutter) {
  const std::uint64_t world_seed = resolvable_world_seed(1.0);
  ASSERT_NE(world_seed, 0u);
  for (const std::uint64_t seed : {1u, 2u}) {
    const AssociationCounts jcbb = counts_with_clutter(seed, world_seed, Association::kJcbb);
    const AssociationCounts nn = counts_with_clutter(seed, world_seed, Association::kNearestNeighbour);
    EXPECT_EQ(jcbb.paired_wrong - jcbb.spurious_paired, 0u);  // no real landmark taken for another
    EXPECT_LE(jcbb.spurious_paired, 3u);
    EXPECT_EQ(jcbb.landmarks_from_spurious, 0u);
    EXPECT_EQ(jcbb.landmarks_duplicated, 0u);
    EXPECT_GT(jcbb.paired_correct, 15000u);
    // Nearly all clutter is rejected by the gate and the confirmation rule, but not always.
    EXPECT_GE(jcbb.spurious_rejected + 5, jcbb.spurious_observations);
    EXPECT_LE(jcbb.paired_wrong, nn.paired_wrong);
  }
}

TEST(LandmarkSlam, DefaultWorldWithAnUnresolvablePairIsCountedNotHidden) {
  // Landmarks 23 and 40 of the default world are 0.18 m apart: measured, not asserted away.
  const AssociationCounts jcbb = counts_with_clutter(1, 0, Association::kJcbb);
  const AssociationCounts nn = counts_with_clutter(1, 0, Association::kNearestNeighbour);
  // Measured on seed 1: JCBB 32 wrong pairings and no clutter accepted; NN 37 wrong, 4 of them
  // clutter. (A diagnostic run traced every wrong JCBB pairing to landmarks 23 and 40.)
  EXPECT_EQ(jcbb.spurious_paired, 0u);
  EXPECT_LE(jcbb.paired_wrong, 40u);
  EXPECT_GE(nn.paired_wrong, jcbb.paired_wrong);
  EXPECT_GE(nn.spurious_paired, jcbb.spurious_paired);
}

TEST(LandmarkSlam, BadObservationsAreCountedAndLeaveTheEstimateIntact) {
  LandmarkRun run = simulated_run(1);
  const LandmarkSlamResult clean = run_landmark_slam(run, options_for(Method::kEkf, Association::kKnown, 1));
  // Corrupt copies of three observations, inserted beside the originals.
  std::vector<Observation> bad;
  for (const std::size_t i : {100u, 5000u, 12000u}) bad.push_back(run.observations[i]);
  bad[0].range_m = std::numeric_limits<double>::quiet_NaN();
  bad[1].range_m = -2.0;
  bad[2].bearing_rad = std::numeric_limits<double>::infinity();
  LandmarkRun corrupted = run;
  corrupted.observations.insert(corrupted.observations.end(), bad.begin(), bad.end());
  std::stable_sort(corrupted.observations.begin(), corrupted.observations.end(),
                   [](const Observation& a, const Observation& b) { return a.time < b.time; });
  for (const Method method : {Method::kEkf, Method::kGraph}) {
    for (const Association association : {Association::kKnown, Association::kJcbb}) {
      const LandmarkSlamResult r = run_landmark_slam(corrupted, options_for(method, association, 1));
      EXPECT_EQ(r.report.association_counts.rejected_invalid, 3u) << to_string(method) << " " << to_string(association);
      EXPECT_TRUE(std::isfinite(r.report.ate_rmse_m));
      EXPECT_LT(r.report.ate_rmse_m, 0.1);
    }
  }
  // The EKF with known association sees exactly the clean observations: identical result.
  const LandmarkSlamResult ekf = run_landmark_slam(corrupted, options_for(Method::kEkf, Association::kKnown, 1));
  EXPECT_EQ(ekf.report.ate_rmse_m, clean.report.ate_rmse_m);
  EXPECT_EQ(ekf.report.ekf_counters.updates, clean.report.ekf_counters.updates);
}

}  // namespace
}  // namespace cairn::landmarks

namespace cairn::landmarks {
namespace {
// The sparse world (15 landmarks, 6 m range), odometry with only the white heading noise both
// methods model (no scale errors, biases or slips), four laps (412 s).
LandmarkRun sparse_unbiased_run(std::uint64_t seed, double yaw_rad_per_sqrt_rad, double yaw_rad_per_sqrt_m) {
  return simulated_run(seed, [&](sim::Scenario& s) {
    s.landmark_field.landmarks = 15;
    s.landmarks.max_range_m = 6.0;
    s.odometry.scale_error = 0.0;
    s.odometry.yaw_scale_error = 0.0;
    s.odometry.yaw_bias_rad_per_m = 0.0;
    s.odometry.slip_rate_per_s = 0.0;
    s.odometry.yaw_sigma_rad_per_sqrt_rad = yaw_rad_per_sqrt_rad;
    s.odometry.yaw_sigma_rad_per_sqrt_m = yaw_rad_per_sqrt_m;
    s.trajectory.laps = 4;
  });
}

// Large heading uncertainty (odometry yaw noise 0.05 rad/sqrt(rad) + 0.02 rad/sqrt(m), 2.5x and
// 2.5x the default, modelled exactly by both methods), few landmarks, four laps (412 s): the
// regime in which EKF-SLAM's linearisation makes it overconfident (Huang & Dissanayake, IEEE
// T-RO 2007; Bailey et al., IROS 2006). Measured over 8 seeds (docs/landmark-slam.md): the EKF's
// pose NEES leaves the 95% band upwards at 3 of 8 checkpoints (up to 21) and its landmark NEES
// ends 1.5x above its expected 2; the graph's pose NEES never exceeds the band (once below it:
// conservative) and its landmark NEES stays below 2.
TEST(LandmarkSlam, NeesLargeHeadingUncertaintyEkfOverconfidentGraphNot) {
  constexpr int kRuns = 8;
  const filter::ChiSquareBand band = filter::mean_chi_square_band(3.0, kRuns, 0.95);
  const double yaw_rad = 0.05, yaw_m = 0.02;
  NeesTable table;
  for (int r = 0; r < kRuns; ++r) {
    const LandmarkRun run = sparse_unbiased_run(static_cast<std::uint64_t>(100 + r), yaw_rad, yaw_m);
    auto ekf_options = options_for(Method::kEkf, Association::kKnown, 8);
    ekf_options.odometry.yaw_sigma_rad_per_sqrt_rad = yaw_rad;
    ekf_options.odometry.yaw_sigma_rad_per_sqrt_m = yaw_m;
    auto graph_options = ekf_options;
    graph_options.method = Method::kGraph;
    const auto ekf = run_landmark_slam(run, ekf_options).report;
    const auto graph = run_landmark_slam(run, graph_options).report;
    std::printf("seed %d: ATE EKF %.3f m, graph %.3f m\n", 100 + r, ekf.ate_rmse_m, graph.ate_rmse_m);
    add_run(&table, ekf, graph, kRuns);
  }
  print_table("sparse variant, no biases, large heading noise, 4 laps", table, kRuns);
  int ekf_above = 0, graph_above = 0;
  for (std::size_t c = 0; c < table.time_s.size(); ++c) {
    ekf_above += table.ekf_pose[c] > band.upper ? 1 : 0;
    graph_above += table.graph_pose[c] > band.upper ? 1 : 0;
  }
  EXPECT_GE(ekf_above, 2) << "the EKF should be overconfident at several checkpoints";
  EXPECT_EQ(graph_above, 0) << "the graph should never be overconfident beyond the band";
  EXPECT_GT(table.ekf_landmark.back(), 2.5);
  EXPECT_LT(table.graph_landmark.back(), table.ekf_landmark.back());
}
}  // namespace
}  // namespace cairn::landmarks

namespace cairn::landmarks {
namespace {
// Very large heading noise (0.08 rad/sqrt(rad) + 0.03 rad/sqrt(m)): solved only at the 8 NEES
// checkpoints, the graph extends half a lap of dead reckoning before each solve. With the
// graph's own LM (before it moved onto the least-squares engine, 2026-11-24) seed 106 then
// ended in a wrong minimum (ATE 35 m); the engine's LM (Ceres' damping rule) finds the right
// one on all 8 seeds, and seeds 102 and 103 still end at worse ones from checkpoints only
// (0.220 and 0.314 m against 0.167 and 0.193 m, docs/landmark-slam.md). Solving the growing graph every 100 steps (10 s, the
// default graph_solve_every_steps) keeps every seed at least as good as checkpoint-only solves
// and below the EKF.
TEST(LandmarkSlam, PeriodicGraphSolvesSurviveVeryLargeHeadingNoise) {
  const double yaw_rad = 0.08, yaw_m = 0.03;
  int checkpoint_only_worse = 0;
  for (int r = 0; r < 8; ++r) {
    const LandmarkRun run = sparse_unbiased_run(static_cast<std::uint64_t>(100 + r), yaw_rad, yaw_m);
    auto options = options_for(Method::kGraph, Association::kKnown, 8);
    options.odometry.yaw_sigma_rad_per_sqrt_rad = yaw_rad;
    options.odometry.yaw_sigma_rad_per_sqrt_m = yaw_m;
    ASSERT_EQ(options.graph_solve_every_steps, 100);
    const auto periodic = run_landmark_slam(run, options).report;
    options.graph_solve_every_steps = 0;
    const auto checkpoints_only = run_landmark_slam(run, options).report;
    auto ekf_options = options;
    ekf_options.method = Method::kEkf;
    const auto ekf = run_landmark_slam(run, ekf_options).report;
    std::printf("seed %d: graph ATE %.3f m (solved at checkpoints only: %.3f m), EKF %.3f m\n", 100 + r,
                periodic.ate_rmse_m, checkpoints_only.ate_rmse_m, ekf.ate_rmse_m);
    EXPECT_LT(periodic.ate_rmse_m, 0.5) << "seed " << 100 + r;
    EXPECT_LE(periodic.ate_rmse_m, checkpoints_only.ate_rmse_m + 1e-3) << "seed " << 100 + r;
    EXPECT_LE(periodic.ate_rmse_m, ekf.ate_rmse_m) << "seed " << 100 + r;
    checkpoint_only_worse += checkpoints_only.ate_rmse_m > periodic.ate_rmse_m + 0.05 ? 1 : 0;
  }
  // Periodic solves still matter on some seed (if this changes, re-measure the docs).
  EXPECT_GE(checkpoint_only_worse, 1);
}

// LandmarkSlamOptions::should_stop (SIGINT in the CLI) ends the run after a step: the result is
// the run up to there, complete (one pose per step processed, landmarks, NEES at the steps
// reached) and marked interrupted; an uninterrupted run is not marked.
TEST(LandmarkSlam, ShouldStopGivesTheResultSoFarMarkedInterrupted) {
  const LandmarkRun run = simulated_run(1);
  for (const auto& [method, association] :
       {std::pair{Method::kEkf, Association::kKnown}, std::pair{Method::kGraph, Association::kKnown},
        std::pair{Method::kGraph, Association::kJcbb}}) {
    LandmarkSlamOptions options = options_for(method, association);
    const LandmarkSlamResult full = run_landmark_slam(run, options);
    EXPECT_FALSE(full.report.interrupted);
    EXPECT_EQ(full.report.steps, full.report.steps_in_run);
    ASSERT_GT(full.report.steps, 400u);

    int polls = 0;
    options.should_stop = [&] { return ++polls > 300; };
    const LandmarkSlamResult part = run_landmark_slam(run, options);
    const std::string name = std::string(to_string(method)) + "/" + std::string(to_string(association));
    EXPECT_TRUE(part.report.interrupted) << name;
    EXPECT_EQ(part.report.steps_in_run, full.report.steps);
    EXPECT_GT(part.report.steps, 200u) << name;
    EXPECT_LE(part.report.steps, 301u) << name;
    ASSERT_EQ(part.trajectory.size(), part.report.steps) << name;
    EXPECT_EQ(part.trajectory.back().time, full.trajectory[part.report.steps - 1].time) << name;
    EXPECT_GT(part.landmarks.size(), 0u) << name;
    EXPECT_LE(part.landmarks.size(), full.landmarks.size()) << name;
    // NEES at the checkpoints reached (graph SLAM: also at the last step, where it solved).
    for (const NeesPoint& p : part.report.nees) EXPECT_LT(p.step, part.report.steps) << name;
    if (method == Method::kGraph) {
      ASSERT_FALSE(part.report.nees.empty()) << name;
      EXPECT_EQ(part.report.nees.back().step, part.report.steps - 1) << name;
    }
    EXPECT_TRUE(std::isfinite(part.report.ate_rmse_m)) << name;
    EXPECT_LT(part.report.ate_rmse_m, 1.0) << name;  // the estimate so far is still an estimate
  }
}

}  // namespace
}  // namespace cairn::landmarks
