// The 2D SLAM pipeline end to end, on the simulator (exact ground truth, every failure mode on
// demand) and on the real Freiburg benchmark logs (relations files as ground truth). The numbers
// the issue asks for are checked here; docs/benchmarks.md records the measured values.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <random>

#include "cairn/eval/ape.hpp"
#include "cairn/eval/relations.hpp"
#include "cairn/io/carmen_log.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/sim/scenario.hpp"
#include "cairn/slam2d/outputs.hpp"
#include "cairn/slam2d/slam.hpp"
#include "test_data.hpp"

namespace cairn::slam2d {
namespace {

namespace fs = std::filesystem;

fs::path temp_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("cairn-test-slam2d-" + name + "-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

struct SimRun {
  sim::SimulationResult truth;
  io::Trajectory reference;  ///< the ground truth as a trajectory (body poses)
  std::unique_ptr<Slam2d> slam;
  std::vector<eval::Relation> relations;
  double ate_rmse_m = 0.0;
  double odometry_ate_rmse_m = 0.0;
  eval::RelationsResult relations_result;
};

std::map<std::int64_t, core::SE2> truth_by_stamp(const sim::SimulationResult& truth) {
  std::map<std::int64_t, core::SE2> out;
  for (const auto& sample : truth.truth) out[sample.stamp.nanoseconds()] = sample.T_world_body;
  return out;
}

core::SE3 lift(const core::SE2& T) {
  return core::SE3(core::SO3::from_rpy(0.0, 0.0, T.angle()), Eigen::Vector3d(T.x(), T.y(), 0.0));
}

double ate(const io::Trajectory& reference, const io::Trajectory& estimate) {
  eval::ApeOptions options;
  options.alignment.method = eval::AlignmentMethod::kSE2;
  const eval::ApeResult result = eval::evaluate_ape(reference, estimate, options);
  EXPECT_TRUE(result.outcome.ok()) << result.outcome.message;
  return result.statistics.rmse;
}

// Simulates `scenario` with `seed`, writes its files (the log goes through the CARMEN reader
// exactly as `cairn slam2d` reads it) and runs the pipeline scan by scan.
SimRun run_simulated(const std::string& scenario_name, std::uint64_t seed, const Slam2dOptions& options = {},
                     const std::function<void(sim::Scenario&)>& adjust = {}) {
  auto scenario = sim::make_scenario(scenario_name);
  EXPECT_TRUE(scenario.has_value());
  if (adjust) adjust(*scenario);
  SimRun run;
  run.truth = sim::simulate(*scenario, seed);
  const fs::path dir = temp_dir(scenario_name + "-" + std::to_string(seed));
  sim::write_outputs(run.truth, *scenario, seed, dir.string());
  const io::CarmenLog log = io::read_carmen_log((dir / "log.clf").string());
  run.relations = eval::read_relations((dir / "log.relations").string());
  run.slam = std::make_unique<Slam2d>(options);
  for (const auto& scan : log.scans) run.slam->add_scan(scan);
  run.slam->finish();
  io::Trajectory odometry;
  for (const auto& sample : run.truth.truth) {
    run.reference.stamps.push_back(sample.stamp);
    run.reference.poses.push_back(lift(sample.T_world_body));
  }
  for (const auto& scan : log.scans) {
    odometry.stamps.push_back(scan.time);
    odometry.poses.push_back(lift(scan.T_odom_laser));
  }
  run.ate_rmse_m = ate(run.reference, to_trajectory(*run.slam));
  run.odometry_ate_rmse_m = ate(run.reference, odometry);
  run.relations_result = eval::evaluate_relations(run.relations, to_matrix_trajectory(*run.slam));
  EXPECT_TRUE(run.relations_result.outcome.ok()) << run.relations_result.outcome.message;
  fs::remove_all(dir);
  return run;
}

struct LoopCheck {
  int accepted = 0;
  int false_accepted = 0;
};

// An accepted loop closure is false when its relative pose differs from the ground truth's by
// more than 0.3 m or 3 degrees.
LoopCheck check_loops(const SimRun& run) {
  const auto truth = truth_by_stamp(run.truth);
  LoopCheck check;
  for (const LoopCandidate& c : run.slam->summary().candidates) {
    if (!c.accepted || c.rejected_by_gnc) continue;
    ++check.accepted;
    const core::SE2 T_true = truth.at(c.anchor_time.nanoseconds()).inverse() * truth.at(c.time.nanoseconds());
    const core::SE2 error = T_true.inverse() * c.T_anchor_keyframe;
    if (error.translation().norm() > 0.3 || std::abs(error.angle()) > 3.0 * M_PI / 180.0) ++check.false_accepted;
  }
  return check;
}

// Issue 9: simulated office loop, 180 beams over 180 degrees, range noise 1 cm, 1 % max-range
// dropouts, odometry drifting more than 1 m; five seeds: relations error below Cartographer's
// best published row (0.0229 m, 0.352 deg) and ATE RMSE below 5 cm.
TEST(Slam2dSimulation, OfficeFiveSeeds) {
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const SimRun run = run_simulated("office", seed);
    EXPECT_GT(run.truth.dead_reckoning_max_error_m, 1.0) << "seed " << seed << ": odometry must drift more than 1 m";
    const auto& r = run.relations_result;
    std::printf("office seed %llu: ATE %.4f m (odometry %.3f m), relations %.4f m %.3f deg, loops %zu\n",
                static_cast<unsigned long long>(seed), run.ate_rmse_m, run.odometry_ate_rmse_m,
                r.translation_absolute_m.mean, r.rotation_absolute_deg.mean, run.slam->summary().loops_accepted);
    EXPECT_LT(r.translation_absolute_m.mean, 0.0229) << "seed " << seed;
    EXPECT_LT(r.rotation_absolute_deg.mean, 0.352) << "seed " << seed;
    EXPECT_LT(run.ate_rmse_m, 0.05) << "seed " << seed;
    EXPECT_EQ(check_loops(run).false_accepted, 0) << "seed " << seed;
  }
}

// Corridor of identical doors every 4 m, ten seeds: no false loop closure accepted, true ones
// close, and the result beats dead reckoning.
TEST(Slam2dSimulation, CorridorAliasingTenSeedsNoFalseLoops) {
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const SimRun run = run_simulated("corridor-aliasing", seed);
    const LoopCheck loops = check_loops(run);
    std::printf("corridor seed %llu: %d loops accepted, %d false; ATE %.3f m (odometry %.3f m)\n",
                static_cast<unsigned long long>(seed), loops.accepted, loops.false_accepted, run.ate_rmse_m,
                run.odometry_ate_rmse_m);
    EXPECT_EQ(loops.false_accepted, 0) << "seed " << seed;
    EXPECT_GT(loops.accepted, 0) << "seed " << seed << ": the true loops must close";
    EXPECT_LT(run.ate_rmse_m, run.odometry_ate_rmse_m) << "seed " << seed;
  }
}

// Open hall (LiDAR max range 10 m, mostly nothing in reach): the pipeline must say degraded,
// not report confident matches.
TEST(Slam2dSimulation, OpenHallReportsDegraded) {
  const SimRun run = run_simulated("open-hall", 1);
  const auto& s = run.slam->summary();
  EXPECT_GT(s.scans_degraded + s.scans_lost, s.scans * 9 / 10);
  bool named = false;
  for (const auto& event : s.health_events) named = named || event.reason.find("too few returns") != std::string::npos;
  EXPECT_TRUE(named) << "the health events should say why";
  EXPECT_EQ(check_loops(run).false_accepted, 0);
}

// People walking through the office: ghost trails are occupied cells where the world has no
// wall. Measured as the fraction of occupied cells (p >= 0.65) farther than 0.15 m from every
// wall and pillar of the simulated world, after SE(2)-free comparison (the estimate starts in
// the world frame: odometry starts at the true pose).
double ghost_fraction(const SimRun& run) {
  const ProbabilityGrid grid = run.slam->render_map(ProbabilityGridOptions{});
  const auto& world = run.truth.world.world;
  auto distance_to_world = [&](const Eigen::Vector2d& p) {
    double best = 1e9;
    for (const auto& wall : world.walls) {
      const Eigen::Vector2d ab = wall.b - wall.a;
      const double t = std::clamp((p - wall.a).dot(ab) / std::max(ab.squaredNorm(), 1e-12), 0.0, 1.0);
      best = std::min(best, (wall.a + t * ab - p).norm());
    }
    for (const auto& circle : world.circles) best = std::min(best, std::abs((p - circle.center).norm() - circle.radius_m));
    return best;
  };
  int occupied = 0, ghosts = 0;
  for (int j = 0; j < grid.height(); ++j) {
    for (int i = 0; i < grid.width(); ++i) {
      if (!grid.cell_known(i, j) || grid.cell_probability(i, j) < 0.65) continue;
      ++occupied;
      const Eigen::Vector2d centre = grid.origin() + (Eigen::Vector2d(i, j).array() + 0.5).matrix() * grid.resolution();
      if (distance_to_world(centre) > 0.15) ++ghosts;
    }
  }
  return occupied > 0 ? static_cast<double>(ghosts) / occupied : 1.0;
}

TEST(Slam2dSimulation, PeopleLeaveNoGhostTrails) {
  const SimRun people = run_simulated("office-people", 1);
  const SimRun empty = run_simulated("office", 1);
  const double with_people = ghost_fraction(people);
  const double without = ghost_fraction(empty);
  std::printf("ghost cells: %.4f with 8 people, %.4f without (fraction of occupied cells > 0.15 m from any wall)\n",
              with_people, without);
  EXPECT_LT(with_people, 0.01);
  EXPECT_LT(people.ate_rmse_m, 0.05);
}

// Runs the office (seed 1) with `corrupt` applied to the log first; returns the run's summary,
// health events and ATE.
struct CorruptedRun {
  Slam2dSummary summary;
  double ate_m = 0.0;
};
CorruptedRun run_corrupted_office(const std::function<void(io::CarmenLog&)>& corrupt) {
  auto scenario = sim::make_scenario("office");
  EXPECT_TRUE(scenario.has_value());
  const sim::SimulationResult truth = sim::simulate(*scenario, 1);
  const fs::path dir = temp_dir("corrupted");
  sim::write_outputs(truth, *scenario, 1, dir.string());
  io::CarmenLog log = io::read_carmen_log((dir / "log.clf").string());
  fs::remove_all(dir);
  corrupt(log);
  Slam2d slam;
  for (const auto& scan : log.scans) slam.add_scan(scan);
  slam.finish();
  io::Trajectory reference;
  for (const auto& sample : truth.truth) {
    reference.stamps.push_back(sample.stamp);
    reference.poses.push_back(lift(sample.T_world_body));
  }
  return {slam.summary(), ate(reference, to_trajectory(slam))};
}

// A 3 m jump of the odometry at scan 600 (a kidnapping, or a wheel encoder glitch): the match at
// the predicted pose fails; the scan is relocalised in the recent map (branch and bound over the
// loop window, verified like a loop closure), the event is reported, and the run stays accurate.
TEST(Slam2dSimulation, OdometryJumpIsReportedAndCorrected) {
  const CorruptedRun run = run_corrupted_office([](io::CarmenLog& log) {
    const core::SE2 jump(3.0, 0.0, 0.0);
    for (std::size_t k = 600; k < log.scans.size(); ++k) log.scans[k].T_odom_laser = jump * log.scans[k].T_odom_laser;
  });
  bool reported = false;
  for (const auto& e : run.summary.health_events) reported = reported || (e.scan == 600 && e.to != Health::kOk);
  std::printf("odometry jump: reported %d, %zu lost scans, %zu relocalisations, ATE %.4f m\n", reported ? 1 : 0,
              run.summary.scans_lost, run.summary.relocalisations, run.ate_m);
  for (const auto& e : run.summary.health_events) {
    if (e.scan >= 595 && e.scan < 700) std::printf("  scan %zu: %s\n", e.scan, e.reason.c_str());
  }
  EXPECT_TRUE(reported) << "the failed match at the jump must change the health state";
  EXPECT_LT(run.ate_m, 0.05);
}

// Sensor malfunction: 60 scans (6 s) of random ranges. Matching fails again and again, so the
// state must become lost (pose from odometry, no confident wrong pose), the garbage must stay out
// of the map, and once real scans return the pipeline must recover.
TEST(Slam2dSimulation, GarbageScansMakeItLostThenItRecovers) {
  const CorruptedRun run = run_corrupted_office([](io::CarmenLog& log) {
    std::mt19937 random(3);
    std::uniform_real_distribution<float> range(0.2f, 20.0f);
    for (std::size_t k = 900; k < 960; ++k) {
      for (float& r : log.scans[k].ranges_m) r = range(random);
    }
  });
  bool recovered = false;
  for (const auto& e : run.summary.health_events) recovered = recovered || (e.from == Health::kLost && e.scan >= 960);
  std::printf("garbage scans: %zu lost scans, %zu relocalisations, recovered %d, %zu segments, %zu merges, ATE %.4f m\n",
              run.summary.scans_lost, run.summary.relocalisations, recovered ? 1 : 0, run.summary.segments.size(),
              run.summary.merges.size(), run.ate_m);
  for (const auto& e : run.summary.health_events)
    if (e.scan >= 895 && e.scan < 1000) std::printf("  scan %zu: %s -> %s: %s\n", e.scan, std::string(to_string(e.from)).c_str(),
                                                     std::string(to_string(e.to)).c_str(), e.reason.c_str());
  EXPECT_GE(run.summary.scans_lost, 40u);
  EXPECT_LE(run.summary.scans_lost, 70u);
  EXPECT_TRUE(recovered);
  // Lost starts a new map segment; back among mapped walls it is found again and merged.
  ASSERT_GE(run.summary.segments.size(), 2u);
  EXPECT_GE(run.summary.merges.size(), 1u);
  for (const SegmentInfo& segment : run.summary.segments) {
    EXPECT_EQ(segment.merged_with, 0) << "segment " << segment.id;
    EXPECT_EQ(segment.why_not_merged, "") << "segment " << segment.id;
  }
  // Garbage does not match even itself: the seeds are dropped on probation, so the odometry
  // across the loss is trusted and may corroborate the merge (the office is half-turn
  // symmetric: the twin placement is supported by the scans as long as the true one).
  EXPECT_TRUE(run.summary.segments[1].odometry_link_trusted);
  EXPECT_LT(run.ate_m, 0.05);
}

// The same garbage, but the log ends 20 real scans after it: the new segment has had no time to
// merge, and the report says why for it (SegmentInfo::why_not_merged, issue 41), consistently with
// what its keyframes' merge searches found; the first segment has no such line.
TEST(Slam2dSimulation, ASegmentThatDidNotMergeSaysWhy) {
  std::size_t last_scan = 0;
  const CorruptedRun run = run_corrupted_office([&](io::CarmenLog& log) {
    std::mt19937 random(3);
    std::uniform_real_distribution<float> range(0.2f, 20.0f);
    for (std::size_t k = 900; k < 960; ++k) {
      for (float& r : log.scans[k].ranges_m) r = range(random);
    }
    log.scans.resize(980);
    last_scan = log.scans.size();
  });
  ASSERT_EQ(last_scan, 980u);
  ASSERT_GE(run.summary.segments.size(), 2u);
  std::size_t unmerged = 0;
  for (const SegmentInfo& segment : run.summary.segments) {
    std::printf("segment %d: %zu scans, merged with %d, %zu merge searches: %s\n", segment.id, segment.scans, segment.merged_with,
                segment.merge_searches, segment.why_not_merged.c_str());
    if (segment.merged_with == 0) {
      EXPECT_EQ(segment.why_not_merged, "") << "segment " << segment.id;
      continue;
    }
    ++unmerged;
    std::size_t decided = 0;
    for (const LoopCandidate& c : run.summary.candidates) {
      if (c.merge_decision.empty()) continue;
      // Its own keyframes' candidates: keyframes from its first on, before the next segment's.
      const bool own = c.keyframe >= segment.first_keyframe && c.keyframe < segment.first_keyframe + segment.keyframes;
      decided += own ? 1 : 0;
    }
    const std::string& why = segment.why_not_merged;
    const std::string category = why.substr(0, why.find(':'));
    EXPECT_TRUE(category == "no merge search" || category == "no candidate" || category == "ambiguous" || category == "not enough support" ||
                category == "failed verification")
        << why;
    if (category == "no merge search") {
      EXPECT_EQ(segment.merge_searches, 0u);
    }
    if (category == "no merge search" || category == "no candidate") {
      EXPECT_EQ(decided, 0u) << why;
    } else {
      EXPECT_GT(decided, 0u) << why;
    }
  }
  EXPECT_GE(unmerged, 1u) << "the log ends before the new segment could merge";
}

// Issue 20, kidnapping (the scenario's defaults, seed 1): at 55 s the robot is carried 17.5 m into
// a room it never saw, in an office whose floor plan is symmetric under a half turn, while the
// odometry shows nothing. Tracking must say lost within half a second, start a new map segment and
// be mapping again (ok) within another second; nothing accepted (loop closures, or matches that
// merge segments) may contradict the ground truth. Whether the segments merge is printed, not
// asserted: from inside an unmapped twin of a mapped room no single view can tell them apart
// (docs/slam2d.md, Map segments; bench/slam2d_recovery.py runs ten seeds and drop places).
TEST(Slam2dScenarios, KidnappingStartsASegmentAndAcceptsNothingFalse) {
  const SimRun run = run_simulated("kidnapping", 1);
  const auto& s = run.slam->summary();
  std::optional<std::size_t> lost_at, ok_again_at;
  for (const auto& e : s.health_events) {
    if (!lost_at && e.to == Health::kLost && e.scan >= 551) lost_at = e.scan;
    if (lost_at && !ok_again_at && e.from == Health::kLost && e.to == Health::kOk) ok_again_at = e.scan;
  }
  const LoopCheck loops = check_loops(run);
  std::printf("kidnapping: lost at scan %zu, ok again at %zu, %zu segments, %zu merges, %zu merge refusals, %d loops "
              "accepted (%d false), ATE %.3f m\n",
              lost_at.value_or(0), ok_again_at.value_or(0), s.segments.size(), s.merges.size(), s.merges_refused_as_ambiguous,
              loops.accepted, loops.false_accepted, run.ate_rmse_m);
  ASSERT_TRUE(lost_at.has_value()) << "the kidnapping (scan 551) must make the state lost";
  EXPECT_LE(*lost_at, 556u);
  ASSERT_TRUE(ok_again_at.has_value());
  EXPECT_LE(*ok_again_at, *lost_at + 10);
  EXPECT_GE(s.segments.size(), 2u);
  EXPECT_EQ(loops.false_accepted, 0);
}

// Issue 20, kidnapping seed 4 of bench/slam2d_recovery.py (dropped in top-room-3 heading 2.4 rad,
// 5.3 m from where it was picked up): the scan after the drop half-matches the corridor map, and
// an ICP restart without the odometry prior slid 6.2 m along the corridor (position sigma 0.71 m)
// into a look-alike room; the next scans matched there at 98 %, and 9 loop closures up to 11 m
// off followed (measured 2026-11-25). A restart must now pin the position: the kidnapping is
// declared lost and a new segment started, as in the other nine seeds, and nothing false accepted.
TEST(Slam2dScenarios, KidnappingIntoALookAlikeRoomAcceptsNothingFalse) {
  const SimRun run = run_simulated("kidnapping", 4, {}, [](sim::Scenario& scenario) {
    scenario.kidnap.drop_place = "top-room-3";
    scenario.kidnap.drop_heading_rad = 2.4;
  });
  const auto& s = run.slam->summary();
  const LoopCheck loops = check_loops(run);
  std::optional<std::size_t> lost_at;
  for (const auto& e : s.health_events) {
    if (!lost_at && e.to == Health::kLost && e.scan >= 551) lost_at = e.scan;
  }
  std::printf("kidnapping seed 4 (top-room-3): lost at scan %zu, %zu segments, %zu merges, %d loops accepted (%d false), ATE %.3f m\n",
              lost_at.value_or(0), s.segments.size(), s.merges.size(), loops.accepted, loops.false_accepted, run.ate_rmse_m);
  EXPECT_EQ(loops.false_accepted, 0);
  ASSERT_TRUE(lost_at.has_value()) << "the kidnapping (scan 551) must make the state lost";
  EXPECT_LE(*lost_at, 556u);
}

// Issue 20, kidnapping in the furnished office (seed 7 of bench/slam2d_recovery.py's furnished
// rows: carried into bottom-room-2, heading 4.2 rad, then twice round the ring). The furniture
// breaks the plan's half-turn symmetry, so the place is decidable: the segment started after the
// drop must merge with the first one at the true placement (every accepted match, merges
// included, within 0.3 m / 3 degrees of the truth) and the run end in one map. The scans between
// the drop and the new segment's seed are placed by the stale odometry (12.5 m off, said lost),
// so the map is judged from the seed on. Before 2026-11-28 the true placement was dropped each
// time the robot drove where the first segment had never been (tests there found nothing) and
// never gathered the 40 m of support a merge away from the odometry link needs: 0 merges in the
// 10 furnished drops, one or two rounds.
TEST(Slam2dScenarios, KidnappingInAFurnishedOfficeMergesAtTheTruePlace) {
  const SimRun run = run_simulated("kidnapping", 7, {}, [](sim::Scenario& scenario) {
    scenario.office.furnished = true;
    scenario.kidnap.drop_place = "bottom-room-2";
    scenario.kidnap.drop_heading_rad = 4.2;
    scenario.kidnap.rings_after = 2;
  });
  const auto& s = run.slam->summary();
  const LoopCheck loops = check_loops(run);
  ASSERT_GE(s.segments.size(), 2u);
  const core::Timestamp seeded = run.slam->trajectory()[s.segments[1].first_scan].time;
  io::Trajectory after_seed;
  const io::Trajectory estimate = to_trajectory(*run.slam);
  for (std::size_t k = 0; k < estimate.stamps.size(); ++k) {
    if (estimate.stamps[k] < seeded) continue;
    after_seed.stamps.push_back(estimate.stamps[k]);
    after_seed.poses.push_back(estimate.poses[k]);
  }
  const double ate_after_seed = ate(run.reference, after_seed);
  std::printf("furnished kidnapping seed 7: segment 1 from scan %zu (odometry link trusted %d), %zu merges (first at scan %zu, moved "
              "%.2f m), %d loops accepted (%d false), ATE %.3f m (from the seed on %.3f m)\n",
              s.segments[1].first_scan, s.segments[1].odometry_link_trusted ? 1 : 0, s.merges.size(),
              s.merges.empty() ? 0 : s.merges.front().scan, s.merges.empty() ? 0.0 : s.merges.front().moved_m, loops.accepted,
              loops.false_accepted, run.ate_rmse_m, ate_after_seed);
  EXPECT_LE(s.segments[1].first_scan, 556u) << "the kidnapping (scan 551) must start a new segment";
  EXPECT_FALSE(s.segments[1].odometry_link_trusted) << "a loss on consistent scans may be a carry";
  EXPECT_GE(s.merges.size(), 1u);
  for (const SegmentInfo& segment : s.segments) EXPECT_EQ(segment.merged_with, 0) << "segment " << segment.id << " stayed apart";
  EXPECT_EQ(loops.false_accepted, 0);
  EXPECT_LT(ate_after_seed, 0.05);
}

// Issue 20, building-yard (seed 1): out through door A into a yard where most scans see nothing
// within range, 260 s and 257 m of odometry only, back in through door B. Scans without returns
// are no evidence of being lost: the yard is degraded, never lost; back inside, matching works
// again and the building closes onto its first lap without a false loop closure.
TEST(Slam2dScenarios, BuildingYardIsDegradedOutsideAndRecoversInside) {
  const SimRun run = run_simulated("building-yard", 1);
  const auto& s = run.slam->summary();
  const std::vector<ScanResult> trajectory = run.slam->trajectory();
  std::size_t ok_inside = 0;
  const std::size_t inside_from = trajectory.size() - 400;  // the last 45 s are inside (segments.txt)
  for (std::size_t k = inside_from; k < trajectory.size(); ++k) ok_inside += trajectory[k].health == Health::kOk ? 1 : 0;
  const LoopCheck loops = check_loops(run);
  std::printf("building-yard: %zu degraded, %zu lost scans; %zu of the last 400 ok; %d loops (%d false); ATE %.3f m "
              "(odometry %.3f m)\n",
              s.scans_degraded, s.scans_lost, ok_inside, loops.accepted, loops.false_accepted, run.ate_rmse_m, run.odometry_ate_rmse_m);
  EXPECT_EQ(s.scans_lost, 0u);
  EXPECT_GT(s.scans_degraded, 2000u);
  EXPECT_GE(ok_inside, 360u);
  EXPECT_EQ(loops.false_accepted, 0);
  EXPECT_LT(run.ate_rmse_m, run.odometry_ate_rmse_m);
}

// Issue 41, the sparse open stretch (outdoor-stretch with 10 features along the path instead of 4,
// seed 1; docs/slam2d.md, Known limits): on the way back a scan may hold 10-20 returns of a post or
// bench just come into range and little the local map holds. Such scans failed to match (inlier
// fraction 0.09-0.24 at scans 4525-4529), five in a row made the state lost, and the second segment
// (76 scans lost) never merged. Cast from the odometry prediction their rays cross nothing mapped:
// they see new structure, are degraded and follow the odometry. The same run with the rule off
// (new_space_max_rays_through < 0) is the control: lost again.
TEST(Slam2dScenarios, SparseOpenStretchSeesNewStructureAndIsNotLost) {
  const auto ten_features = [](sim::Scenario& scenario) { scenario.outdoor.features = 10; };
  const SimRun run = run_simulated("outdoor-stretch", 1, {}, ten_features);
  Slam2dOptions off;
  off.new_space_max_rays_through = -1.0;
  const SimRun control = run_simulated("outdoor-stretch", 1, off, ten_features);
  const auto& s = run.slam->summary();
  const LoopCheck loops = check_loops(run);
  std::printf("sparse open stretch: %zu lost, %zu degraded (%zu new structure), %zu segments, %d loops (%d false), ATE %.3f m; "
              "rule off: %zu lost, %zu segments, ATE %.3f m\n",
              s.scans_lost, s.scans_degraded, s.scans_new_space, s.segments.size(), loops.accepted, loops.false_accepted,
              run.ate_rmse_m, control.slam->summary().scans_lost, control.slam->summary().segments.size(), control.ate_rmse_m);
  EXPECT_GT(control.slam->summary().scans_lost, 0u) << "the control must reproduce the loss";
  EXPECT_EQ(s.scans_lost, 0u);
  EXPECT_GE(s.scans_new_space, 1u);
  EXPECT_EQ(s.segments.size(), 1u);
  EXPECT_EQ(loops.false_accepted, 0);
}

// Real data: the Freiburg benchmark logs with one configuration (the defaults) for both.
struct RealResult {
  eval::RelationsResult relations;
  Slam2dSummary summary;
};

RealResult run_real(const std::string& name) {
  const std::string log_path = test::data_path("laser2d/" + name + "/" + name + ".clf.bz2").string();
  const io::CarmenLog log = io::read_carmen_log(log_path);
  Slam2d slam;
  for (const auto& scan : log.scans) slam.add_scan(scan);
  slam.finish();
  RealResult result;
  result.summary = slam.summary();
  const fs::path relations = test::data_path("laser2d/" + name + "/" + name + ".relations");
  if (fs::exists(relations)) {
    result.relations = eval::evaluate_relations(eval::read_relations(relations.string()), to_matrix_trajectory(slam));
    EXPECT_TRUE(result.relations.outcome.ok()) << result.relations.outcome.message;
    std::printf("%s: relations %.4f +- %.4f m, %.3f +- %.3f deg; %zu loops accepted, %.1f s\n", name.c_str(),
                result.relations.translation_absolute_m.mean, result.relations.translation_absolute_m.std,
                result.relations.rotation_absolute_deg.mean, result.relations.rotation_absolute_deg.std,
                result.summary.loops_accepted, result.summary.total_s);
  }
  for (const LoopCandidate& c : result.summary.candidates) {
    if (c.accepted) {
      EXPECT_EQ(c.reason, "accepted");  // every accepted loop passed verification
    }
  }
  return result;
}

TEST(Slam2dRealData, AcesBelowCartographer) {
  CAIRN_REQUIRE_DATA("laser2d/aces/aces.clf.bz2");
  const RealResult r = run_real("aces");
  EXPECT_LT(r.relations.translation_absolute_m.mean, 0.0375);  // Hess et al. 2016, Table II
  EXPECT_LT(r.relations.rotation_absolute_deg.mean, 0.373);
}

TEST(Slam2dRealData, IntelBelowCartographer) {
  CAIRN_REQUIRE_DATA("laser2d/intel/intel.clf.bz2");
  const RealResult r = run_real("intel");
  EXPECT_LT(r.relations.translation_absolute_m.mean, 0.0229);
  EXPECT_LT(r.relations.rotation_absolute_deg.mean, 0.453);
}

TEST(Slam2dRealData, MitCsailRunsToCompletion) {
  CAIRN_REQUIRE_DATA("laser2d/mit-csail/mit-csail.clf.bz2");
  const RealResult r = run_real("mit-csail");
  EXPECT_GT(r.summary.scans, 1900u);
  EXPECT_EQ(r.summary.scans_lost, 0u);
}

// A truncated log: a clear error naming the line, or with skip_malformed_records the bad
// record is counted and the rest processed.
TEST(Slam2dInput, TruncatedLogNamesTheLineOrIsSkippedLeniently) {
  const fs::path dir = temp_dir("truncated");
  const fs::path path = dir / "cut.clf";
  {
    std::ofstream out(path);
    out << "ODOM 0 0 0 0 0 0 1.0 host 1.0\n";
    out << "FLASER 3 1.0 1.1 1.2 0 0 0 0 0 0 1.1 host 1.1\n";
    out << "FLASER 3 1.0 1.1\n";  // cut in the middle
    out << "FLASER 3 1.0 1.1 1.2 0.1 0 0 0.1 0 0 1.3 host 1.3\n";
  }
  try {
    io::read_carmen_log(path.string());
    ADD_FAILURE() << "a truncated record must not be accepted";
  } catch (const io::ParseError& e) {
    EXPECT_EQ(e.line(), 3u) << e.what();
  }
  io::CarmenReadOptions lenient;
  lenient.skip_malformed_records = true;
  io::CarmenReadReport report;
  const io::CarmenLog log = io::read_carmen_log(path.string(), &report, lenient);
  EXPECT_EQ(log.scans.size(), 2u);
  EXPECT_EQ(report.malformed_records, 1u);
  EXPECT_NE(report.first_malformed.find(":3:"), std::string::npos) << report.first_malformed;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace cairn::slam2d
