// 3D LiDAR SLAM (lidar3d/slam.hpp) on the simulator's LiDAR scenarios, with their ground truth:
// the street driven twice, the second lap reversed on the opposite lane (loops must be found,
// reverse ones included, and none may be false); the garage of identical bays (no revisit: every
// accepted loop is false, over 10 seeds); the featureless tunnel (must be reported degraded along
// its axis).

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "cairn/lidar3d/outputs.hpp"
#include "cairn/lidar3d/slam.hpp"
#include "cairn/sim/scenario.hpp"
#include "cairn/sim/street_run.hpp"
#include "sim_clouds.hpp"

namespace cairn::lidar3d {
namespace {

struct SimRun {
  std::vector<SlamScanResult> scans;
  LidarSlamSummary summary;
  std::vector<core::SE3> T_world_lidar_middle;  ///< ground truth at each sweep's middle
  std::vector<core::SE3> T_world_lidar_stamp;   ///< ground truth at each scan's stamp (sweep start)
  std::vector<core::SE3> trajectory;            ///< the final estimate at the stamps
  sim::SimulationResult simulation;
};

/// Scans [blind_begin, blind_end) arrive empty (a covered or disconnected sensor).
SimRun run_scenario(const sim::Scenario& scenario, std::uint64_t seed, const LidarSlamOptions& options = {},
                    std::size_t blind_begin = 0, std::size_t blind_end = 0) {
  SimRun out;
  out.simulation = sim::simulate(scenario, seed);
  const sim::SimulationResult& s = out.simulation;
  LidarSlam slam(options);
  // The sweep's middle: half a revolution of trajectory samples after its start.
  const double sample_period = s.truth.size() > 1 ? s.truth[1].stamp.seconds() - s.truth[0].stamp.seconds() : 0.01;
  const auto half = static_cast<std::size_t>(std::lround(0.5 * scenario.lidar3d.period_s / sample_period));
  for (std::size_t k = 0; k < s.clouds.size(); ++k) {
    const bool blind = k >= blind_begin && k < blind_end;
    const io::PointCloud cloud = blind ? io::PointCloud{} : test::to_point_cloud(s.clouds[k]);
    out.scans.push_back(slam.add_scan(cloud, s.truth[s.scan_samples[k]].stamp.seconds()));
    const std::size_t middle = std::min(s.scan_samples[k] + half, s.truth.size() - 1);
    out.T_world_lidar_middle.push_back(sim::lidar_pose(s.truth[middle].T_world_body, scenario.lidar3d));
    out.T_world_lidar_stamp.push_back(sim::lidar_pose(s.truth[s.scan_samples[k]].T_world_body, scenario.lidar3d));
  }
  slam.finish();
  out.trajectory = slam.trajectory();
  out.summary = slam.summary();
  return out;
}

// Scan index of a keyframe: keyframes are numbered in order of the scans that made them.
std::vector<std::size_t> keyframe_scans(const SimRun& r) {
  std::vector<std::size_t> out;
  for (std::size_t k = 0; k < r.scans.size(); ++k) {
    if (r.scans[k].keyframe) out.push_back(k);
  }
  return out;
}

struct LoopCheck {
  int accepted = 0;
  int false_accepted = 0;
  int reverse_accepted = 0;
  int same_direction_accepted = 0;
  double worst_translation_m = 0.0;
  double worst_rotation_deg = 0.0;
};

// An accepted loop is false when its relative pose is more than 1 m or 5 degrees from the truth
// (both at the sweeps' middles, where keyframes are registered).
LoopCheck check_loops(const SimRun& r) {
  LoopCheck c;
  const std::vector<std::size_t> kf = keyframe_scans(r);
  for (const LoopCandidateRecord& record : r.summary.candidates) {
    if (!record.accepted || record.rejected_by_gnc) continue;
    ++c.accepted;
    const std::size_t q = kf[static_cast<std::size_t>(record.query_keyframe)];
    const std::size_t k = kf[static_cast<std::size_t>(record.candidate_keyframe)];
    const core::SE3 truth = r.T_world_lidar_middle[k].inverse() * r.T_world_lidar_middle[q];
    const core::SE3 error = truth.inverse() * record.T_candidate_query;
    const double t = error.translation().norm();
    const double a = error.so3().log().norm() * 180.0 / std::numbers::pi;
    c.worst_translation_m = std::max(c.worst_translation_m, t);
    c.worst_rotation_deg = std::max(c.worst_rotation_deg, a);
    if (t > 1.0 || a > 5.0) ++c.false_accepted;
    const double relative_yaw = std::abs(truth.so3().log().z());
    (relative_yaw > 0.5 * std::numbers::pi ? c.reverse_accepted : c.same_direction_accepted)++;
  }
  return c;
}

TEST(LidarSlamSimulation, FindsTheStreetLoopsIncludingReverseOnesAndNoFalseOne) {
  const sim::Scenario scenario = *sim::make_scenario("street-3d-loops");
  const SimRun r = run_scenario(scenario, 1);
  const LoopCheck c = check_loops(r);
  const TrajectoryErrors e = evaluate_trajectory(r.T_world_lidar_stamp, r.trajectory);
  std::printf("street-3d-loops seed 1: %zu keyframes, %zu candidates verified, %d accepted (%d reverse, %d same "
              "direction), %d false; worst loop error %.3f m %.2f deg; %zu true loop pairs in the ground truth; "
              "ATE %.3f m\n",
              r.summary.keyframes, r.summary.candidates.size(), c.accepted, c.reverse_accepted, c.same_direction_accepted,
              c.false_accepted, c.worst_translation_m, c.worst_rotation_deg, r.simulation.true_loops.size(),
              e.ate_rmse_m.value_or(-1.0));
  EXPECT_LT(e.ate_rmse_m.value_or(1e9), 0.6);
  // Recall, reported beside the false loops: of the keyframes that have a true partner keyframe
  // (within 5 m, outside the 50 most recent the search leaves out), how many got a loop closure.
  const std::vector<std::size_t> kf = keyframe_scans(r);
  std::vector<char> has_partner(kf.size(), 0), closed(kf.size(), 0);
  for (std::size_t q = 0; q < kf.size(); ++q) {
    for (std::size_t k = 0; q >= 50 && k + 50 <= q; ++k) {
      if ((r.T_world_lidar_middle[kf[q]].translation() - r.T_world_lidar_middle[kf[k]].translation()).norm() <= 5.0) {
        has_partner[q] = 1;
        break;
      }
    }
  }
  for (const LoopCandidateRecord& record : r.summary.candidates) {
    if (record.accepted && !record.rejected_by_gnc) closed[static_cast<std::size_t>(record.query_keyframe)] = 1;
  }
  int eligible = 0, found = 0;
  for (std::size_t q = 0; q < kf.size(); ++q) {
    eligible += has_partner[q];
    found += has_partner[q] && closed[q];
  }
  std::printf("recall: %d of %d keyframes with a true partner got a loop closure (%.0f %%)\n", found, eligible,
              eligible > 0 ? 100.0 * found / eligible : 0.0);
  EXPECT_EQ(c.false_accepted, 0);
  EXPECT_GE(c.reverse_accepted, 1) << "the reversed lap on the opposite lane must close loops";
  EXPECT_GE(c.same_direction_accepted, 1) << "the end of the first lap meets its start";
  for (const SlamScanResult& s : r.scans) EXPECT_NE(s.odometry.health, Health::kLost);
}

TEST(LidarSlamSimulation, AfterBeingLostANewMapSegmentIsMergedByALoopClosure) {
  // Half a second without returns in the middle of the first lap: the odometry is lost, starts a
  // new map segment from its prediction, and the segments are joined only by a weak edge until
  // the reversed second lap closes loops across the break.
  const sim::Scenario scenario = *sim::make_scenario("street-3d-loops");
  const SimRun r = run_scenario(scenario, 1, {}, 200, 205);
  int lost = 0, segment_changes = 0;
  for (std::size_t k = 0; k < r.scans.size(); ++k) {
    lost += r.scans[k].odometry.health == Health::kLost ? 1 : 0;
    if (k > 0 && r.scans[k].odometry.segment != r.scans[k - 1].odometry.segment) ++segment_changes;
  }
  const std::vector<std::size_t> kf = keyframe_scans(r);
  int across = 0;
  for (const LoopCandidateRecord& record : r.summary.candidates) {
    if (!record.accepted || record.rejected_by_gnc) continue;
    const int a = r.scans[kf[static_cast<std::size_t>(record.query_keyframe)]].odometry.segment;
    const int b = r.scans[kf[static_cast<std::size_t>(record.candidate_keyframe)]].odometry.segment;
    across += a != b ? 1 : 0;
  }
  const LoopCheck c = check_loops(r);
  const TrajectoryErrors e = evaluate_trajectory(r.T_world_lidar_stamp, r.trajectory);
  std::printf("street-3d-loops seed 1, scans 200-204 blind: %d lost, %d segment change(s), %d loops accepted, %d "
              "across segments, %d false; ATE %.3f m, end-point error %.3f m\n",
              lost, segment_changes, c.accepted, across, c.false_accepted, e.ate_rmse_m.value_or(-1.0), e.end_point_error_m);
  EXPECT_EQ(lost, 5);
  EXPECT_EQ(segment_changes, 1);
  EXPECT_GE(across, 1) << "a loop closure must join the segments";
  EXPECT_EQ(c.false_accepted, 0);
}

/// No loop closure accepted in the garage of identical bays over seeds first..last (nothing is
/// revisited there, so every loop would be false), and the bays look alike to the descriptor.
void expect_no_false_loop_in_the_garage(std::uint64_t first, std::uint64_t last) {
  const sim::Scenario scenario = *sim::make_scenario("garage-3d");
  int verified = 0, accepted = 0;
  for (std::uint64_t seed = first; seed <= last; ++seed) {
    const SimRun r = run_scenario(scenario, seed);
    ASSERT_TRUE(r.simulation.true_loops.empty());  // nothing is revisited: every loop would be false
    for (const LoopCandidateRecord& record : r.summary.candidates) accepted += record.accepted ? 1 : 0;
    verified += static_cast<int>(r.summary.candidates.size());
    EXPECT_EQ(r.summary.loops_accepted, 0u) << "seed " << seed;
  }
  std::printf("garage-3d seeds %d-%d: %d candidates below the descriptor threshold verified, %d accepted\n",
              static_cast<int>(first), static_cast<int>(last), verified, accepted);
  EXPECT_GT(verified, 0) << "the bays must look alike to the descriptor, or this tests nothing";
}

// Three seeds in `make test` (about 40 s); the ten-seed sweep (about 130 s) on demand:
//   build/tests/lidar3d/test_lidar3d_simulation --gtest_also_run_disabled_tests --gtest_filter='*DISABLED_NoFalseLoop*'
TEST(LidarSlamSimulation, NoFalseLoopInTheGarageOverThreeSeeds) { expect_no_false_loop_in_the_garage(1, 3); }
TEST(LidarSlamSimulation, DISABLED_NoFalseLoopInTheGarageOverTenSeeds) { expect_no_false_loop_in_the_garage(1, 10); }

TEST(LidarSlamSimulation, TheTunnelIsReportedDegradedAlongItsAxis) {
  const sim::Scenario scenario = *sim::make_scenario("tunnel-3d");
  LidarSlamOptions dense;
  dense.odometry.front_end = FrontEnd::kDense;
  const SimRun r = run_scenario(scenario, 1, dense);
  ASSERT_TRUE(r.simulation.passage_scans && r.simulation.passage_scans->any_blind);
  const sim::PassageScans& p = *r.simulation.passage_scans;
  int degraded_along_axis = 0, blind = 0;
  for (std::size_t k = p.first_blind; k <= p.last_blind; ++k) {
    ++blind;
    const OdometryScanResult& o = r.scans[k].odometry;
    if (o.health == Health::kDegraded && o.degenerate_axis == "x (forward)") ++degraded_along_axis;
  }
  const core::SE3 end_error = r.T_world_lidar_middle.back().inverse() * r.T_world_lidar_middle.front() *
                              r.scans.front().odometry.T_world_registered.inverse() * r.scans.back().odometry.T_world_registered;
  std::printf("tunnel-3d seed 1, dense front end: %d of %d scans out of range of both portals degraded along x "
              "(forward); end-point error %.1f m over %.0f m\n",
              degraded_along_axis, blind, end_error.translation().norm(), r.simulation.path_length_m);
  EXPECT_GE(degraded_along_axis, blind * 9 / 10);
  // No scan is lost: the estimate may drift along the axis, but it says so instead of failing.
  for (const SlamScanResult& s : r.scans) EXPECT_NE(s.odometry.health, Health::kLost);

  // LOAM's features with the degenerate direction left to the prediction carry the pose through:
  // edges only pull across their lines and planes along their normals, so nothing holds the pose
  // back, and the speed the poles of the approach gave is kept (measured 13.6 m at the end, of
  // 230 m; 171 m with the defaults above).
  const SimRun l = run_scenario(scenario, 1);  // the default: the scans carry rings, so LOAM
  const TrajectoryErrors e = evaluate_trajectory(l.T_world_lidar_stamp, l.trajectory);
  std::printf("tunnel-3d seed 1, LOAM front end with remapping: end-point error %.1f m\n", e.end_point_error_m);
  EXPECT_LT(e.end_point_error_m, 30.0);
  int loam_degraded = 0;
  for (std::size_t k = p.first_blind; k <= p.last_blind; ++k) {
    loam_degraded += l.scans[k].odometry.degenerate_axis == "x (forward)" ? 1 : 0;
  }
  EXPECT_GE(loam_degraded, blind * 9 / 10);
}

}  // namespace
}  // namespace cairn::lidar3d
