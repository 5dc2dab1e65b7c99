// LiDAR-inertial SLAM (lidar3d/lidar_inertial_slam.hpp) on the simulator's 3D worlds with their
// simulated IMU (sim/imu.hpp, EuRoC's ADIS16448 noise): the featureless tunnel that LiDAR-only
// odometry cannot measure along its axis, a 458 deg/s spin inside it, and the street with loops.
// Every expected value is the simulator's ground truth; the LiDAR-only run is printed beside.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "cairn/lidar3d/lidar_inertial_slam.hpp"
#include "cairn/lidar3d/outputs.hpp"
#include "cairn/sim/scenario.hpp"
#include "cairn/sim/street_run.hpp"

namespace cairn::lidar3d {
namespace {

struct SimRun {
  std::vector<LidarInertialScan> scans;
  std::vector<core::SE3> truth_at_stamps;  ///< T_world_lidar at each scan's stamp
  std::vector<core::SE3> trajectory;       ///< the final estimate at the stamps
  sim::SimulationResult simulation;
  LidarSlamSummary summary;
  std::optional<InertialInitialization> initialization;  ///< with the IMU
};

/// Runs LiDAR-only (with_imu false) or LiDAR-inertial SLAM on a simulated scenario.
SimRun run_scenario(const sim::Scenario& scenario, std::uint64_t seed, bool with_imu, LidarSlamOptions options = {}) {
  SimRun out;
  out.simulation = sim::simulate(scenario, seed);
  const sim::SimulationResult& s = out.simulation;
  if (with_imu) options.odometry.registration.remap_degenerate_directions = true;
  LidarSlam slam(options);
  InertialFusionOptions fusion_options;
  fusion_options.noise = scenario.imu.noise;
  fusion_options.T_imu_lidar = sim::lidar_pose(core::SE2(), scenario.lidar3d);  // T_body_lidar
  LidarInertialSlam lio(slam, fusion_options);
  if (with_imu) {
    for (const inertial::ImuSample& sample : s.imu.samples) lio.add_imu(sample);
  }
  for (std::size_t k = 0; k < s.clouds.size(); ++k) {
    io::PointCloud cloud;
    for (const sim::LidarPoint& p : s.clouds[k]) {
      cloud.points.push_back(p.position.cast<float>());
      cloud.time_s.push_back(static_cast<float>(p.time_offset_s));
      cloud.ring.push_back(static_cast<std::uint16_t>(p.ring));
    }
    const double time_s = s.truth[s.scan_samples[k]].stamp.seconds();
    if (with_imu) {
      out.scans.push_back(lio.add_scan(cloud, time_s));
    } else {
      out.scans.push_back(LidarInertialScan{slam.add_scan(cloud, time_s), std::nullopt});
    }
    out.truth_at_stamps.push_back(sim::lidar_pose(s.truth[s.scan_samples[k]].T_world_body, scenario.lidar3d));
  }
  slam.finish();
  if (with_imu && lio.fusion().initialized()) out.initialization = lio.fusion().initialization();
  out.trajectory = slam.trajectory();
  out.summary = slam.summary();
  return out;
}

int count_health(const SimRun& r, Health health) {
  int n = 0;
  for (const auto& s : r.scans) n += s.slam.odometry.health == health ? 1 : 0;
  return n;
}

TEST(LidarInertialSimulation, CarriesTheTunnelWithoutLosingAScan) {
  const sim::Scenario scenario = *sim::make_scenario("tunnel-3d");
  const SimRun lio = run_scenario(scenario, 1, true);
  const SimRun lidar = run_scenario(scenario, 1, false);
  const TrajectoryErrors e_lio = evaluate_trajectory(lio.truth_at_stamps, lio.trajectory);
  const TrajectoryErrors e_lidar = evaluate_trajectory(lidar.truth_at_stamps, lidar.trajectory);
  const double path = lio.simulation.path_length_m;
  std::printf("tunnel-3d seed 1 over %.0f m: LiDAR-inertial end-point error %.2f m (%.2f %%), ATE %.2f m; LiDAR-only "
              "%.2f m (%.2f %%), ATE %.2f m\n",
              path, e_lio.end_point_error_m, 100.0 * e_lio.end_point_error_m / path, e_lio.ate_rmse_m.value_or(-1),
              e_lidar.end_point_error_m, 100.0 * e_lidar.end_point_error_m / path, e_lidar.ate_rmse_m.value_or(-1));
  int fused = 0;
  for (const auto& scan : lio.scans) fused += scan.inertial ? 1 : 0;
  // The last sweep ends after the simulated IMU's last sample, so that scan has no prediction.
  EXPECT_GE(fused, static_cast<int>(lio.scans.size()) - 1);
  // Issue 38 asks for 1 % of the distance. Measured (seed 1, this test) 0.98 %, against 5.9 %
  // LiDAR-only; but seeds 2-5 give 6.1, 4.0, 13.2 and 7.9 % (LiDAR-only 14.4, 3.6, 6.9 and 9.6 %), so
  // neither the 1 % nor "better than LiDAR-only" holds in general and neither is asserted here:
  // docs/lidar3d.md, "LiDAR-inertial". What holds on every seed is asserted: nothing lost, the axis
  // named, the IMU carrying it.
  EXPECT_EQ(count_health(lio, Health::kLost), 0);
  // Out of range of both portals the registration still names the axis it cannot see; the IMU carries it.
  const sim::PassageScans& p = *lio.simulation.passage_scans;
  int degenerate = 0, blind = 0;
  for (std::size_t k = p.first_blind; k <= p.last_blind; ++k) {
    ++blind;
    degenerate += lio.scans[k].inertial && lio.scans[k].inertial->degenerate ? 1 : 0;
  }
  EXPECT_GE(degenerate, blind * 9 / 10);
}

// tunnel-3d starts from a standstill at 1.5 m/s^2 at the IMU's first sample: over the static
// window the IMU's block means agree (a constant acceleration reads as a 8.7 deg tilt), only the
// LiDAR sees the motion. The stillness must be withdrawn and gravity found by the window.
TEST(LidarInertialSimulation, ConstantAccelerationAtTheStartIsNotTakenForATilt) {
  const sim::Scenario scenario = *sim::make_scenario("tunnel-3d");
  const SimRun lio = run_scenario(scenario, 2, true);
  const sim::SimulationResult& s = lio.simulation;
  // The truth: moving within the IMU's first second.
  ASSERT_GT((s.truth[s.scan_samples[10]].T_world_body.translation() - s.truth[s.scan_samples[0]].T_world_body.translation()).norm(), 0.5);
  ASSERT_TRUE(lio.initialization.has_value());
  EXPECT_FALSE(lio.initialization->still);
  EXPECT_TRUE(lio.initialization->overruled_by_lidar) << lio.initialization->message;
  // Gravity (z down in the simulator's world) in the estimate's world, through the first scan's
  // pose, against the window's final estimate.
  // (the last sweep ends after the IMU's last sample: the last fused state is the one before)
  const auto last = std::find_if(lio.scans.rbegin(), lio.scans.rend(), [](const LidarInertialScan& x) { return x.inertial.has_value(); });
  ASSERT_TRUE(lio.scans.front().inertial && last != lio.scans.rend());
  const Matrix3 R_estimate_truth =
      lio.scans.front().inertial->T_world_lidar.so3().matrix() * lio.truth_at_stamps.front().so3().inverse().matrix();
  const Vector3 gravity_truth = R_estimate_truth * Vector3(0.0, 0.0, -1.0);
  const Vector3 gravity_estimate = last->inertial->gravity_world.normalized();
  const double tilt_deg = std::acos(std::clamp(gravity_truth.dot(gravity_estimate), -1.0, 1.0)) * 180.0 / M_PI;
  std::printf("tunnel-3d seed 2: gravity's direction off by %.2f deg (%s)\n", tilt_deg, lio.initialization->message.c_str());
  // An accelerometer bias of b tilts gravity by up to b / g (EuRoC's ADIS16448: ~0.1 m/s^2, 0.6 deg).
  EXPECT_LT(tilt_deg, 1.0);
}

/// The rotation error (deg) of the estimated motion from scan a to scan b against the truth's.
double relative_rotation_error_deg(const SimRun& r, std::size_t a, std::size_t b) {
  const core::SE3 truth = r.truth_at_stamps[a].inverse() * r.truth_at_stamps[b];
  const core::SE3 estimate = r.trajectory[a].inverse() * r.trajectory[b];
  return (truth.so3().inverse() * estimate.so3()).angle() * 180.0 / M_PI;
}

// A 360 deg turn on the spot in 0.99 s (peak 458 deg/s) inside the tunnel: the IMU predicts each
// sweep's rotation and deskews it, so the registration starts near the truth.
TEST(LidarInertialSimulation, TracksAFastSpinInTheTunnel) {
  const sim::Scenario scenario = *sim::make_scenario("tunnel-spin-3d");
  const SimRun lio = run_scenario(scenario, 1, true);
  const SimRun lidar = run_scenario(scenario, 1, false);
  ASSERT_TRUE(lio.simulation.spin.has_value());
  const sim::SpinEvent& spin = *lio.simulation.spin;
  // The scans around the spin: the last before it starts and the first after it ends.
  std::size_t before = 0, after = lio.scans.size() - 1;
  for (std::size_t k = 0; k < lio.scans.size(); ++k) {
    const double t = lio.scans[k].slam.odometry.time_s;
    if (t <= spin.start_time_s) before = k;
    if (t >= spin.end_time_s + 0.1 && after == lio.scans.size() - 1) after = k;
  }
  int lio_lost = 0, lidar_lost = 0;
  for (std::size_t k = before; k <= after; ++k) {
    lio_lost += lio.scans[k].slam.odometry.health == Health::kLost ? 1 : 0;
    lidar_lost += lidar.scans[k].slam.odometry.health == Health::kLost ? 1 : 0;
  }
  const double lio_error = relative_rotation_error_deg(lio, before, after);
  const double lidar_error = relative_rotation_error_deg(lidar, before, after);
  const TrajectoryErrors e_lio = evaluate_trajectory(lio.truth_at_stamps, lio.trajectory);
  const TrajectoryErrors e_lidar = evaluate_trajectory(lidar.truth_at_stamps, lidar.trajectory);
  std::printf("tunnel-spin-3d seed 1, spin of %.0f deg peaking at %.0f deg/s, scans %zu-%zu: LiDAR-inertial rotation error "
              "across it %.2f deg, %d lost, end-point error %.2f m; LiDAR-only %.2f deg, %d lost, end-point error %.2f m\n",
              spin.angle_rad * 180.0 / M_PI, spin.peak_yaw_rate_rad_s * 180.0 / M_PI, before, after, lio_error, lio_lost,
              e_lio.end_point_error_m, lidar_error, lidar_lost, e_lidar.end_point_error_m);
  EXPECT_GE(spin.peak_yaw_rate_rad_s, 2.0 * M_PI);
  EXPECT_EQ(lio_lost, 0);
  EXPECT_LT(lio_error, 1.0);
  // The stop and the spin lengthen the stretch the registration cannot see along the axis: measured
  // 10.1 m (4.4 %) at the end, against 187 m LiDAR-only (docs/lidar3d.md).
  EXPECT_LT(e_lio.end_point_error_m, 0.1 * e_lidar.end_point_error_m);
}

// The street with loops (turns, loop closures): the IMU must not make it worse.
TEST(LidarInertialSimulation, StreetWithLoopsNoWorseThanLidarOnly) {
  const sim::Scenario scenario = *sim::make_scenario("street-3d-loops");
  const SimRun lio = run_scenario(scenario, 1, true);
  const SimRun lidar = run_scenario(scenario, 1, false);
  const TrajectoryErrors e_lio = evaluate_trajectory(lio.truth_at_stamps, lio.trajectory);
  const TrajectoryErrors e_lidar = evaluate_trajectory(lidar.truth_at_stamps, lidar.trajectory);
  std::printf("street-3d-loops seed 1: LiDAR-inertial ATE %.3f m, end-point %.3f m, %zu loops; LiDAR-only ATE %.3f m, "
              "end-point %.3f m, %zu loops\n",
              e_lio.ate_rmse_m.value_or(-1.0), e_lio.end_point_error_m, lio.summary.loops_accepted,
              e_lidar.ate_rmse_m.value_or(-1.0), e_lidar.end_point_error_m, lidar.summary.loops_accepted);
  ASSERT_TRUE(e_lio.ate_rmse_m && e_lidar.ate_rmse_m);
  EXPECT_LE(*e_lio.ate_rmse_m, *e_lidar.ate_rmse_m * 1.05 + 0.01);
  EXPECT_EQ(count_health(lio, Health::kLost), 0);
}

}  // namespace
}  // namespace cairn::lidar3d
