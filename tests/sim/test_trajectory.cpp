// Trajectories obey their limits, follow the route, and noise-free odometry reproduces them.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "cairn/sim/odometry.hpp"
#include "cairn/sim/trajectory.hpp"
#include "cairn/sim/world_builders.hpp"

namespace cairn::sim {
namespace {

using core::SE2;

double distance_to_path(const std::vector<TrajectorySample>& samples, const Vector2& p) {
  double best = 1e300;
  for (const auto& s : samples) best = std::min(best, (s.T_world_body.translation() - p).norm());
  return best;
}

void expect_limits_hold(const std::vector<TrajectorySample>& samples, const TrajectoryOptions& o) {
  ASSERT_GE(samples.size(), 2u);
  const double dt = o.sample_period_s;
  const double yaw_rate_limit = std::max(o.max_yaw_rate_rad_s, o.spin_yaw_rate_rad_s);
  for (std::size_t k = 1; k < samples.size(); ++k) {
    const auto& a = samples[k - 1];
    const auto& b = samples[k];
    ASSERT_EQ(b.stamp.nanoseconds() - a.stamp.nanoseconds(), static_cast<std::int64_t>(std::llround(dt * 1e9)));
    const SE2 step = a.T_world_body.inverse() * b.T_world_body;
    // Speed over the step (the mean of the endpoint speeds under constant acceleration).
    EXPECT_LE(step.translation().norm() / dt, o.max_speed_mps + 1e-6) << "sample " << k;
    EXPECT_LE(std::abs(step.angle()) / dt, yaw_rate_limit + 1e-6) << "sample " << k;
    EXPECT_LE(std::abs(b.speed_mps - a.speed_mps) / dt, o.max_acceleration_mps2 + 1e-6) << "sample " << k;
    // A unicycle never moves sideways, so the chord of a step points between the start and end
    // headings: |y| <= |x| tan|theta| (on an arc |y| = |x| tan(|theta| / 2); a step from an arc
    // onto a line comes closer to the bound). 1 nm of slack for rounding where phases join.
    EXPECT_LE(std::abs(step.y()), std::abs(step.x()) * std::tan(std::abs(step.angle())) + 1e-9) << "sample " << k;
  }
}

TEST(Trajectory, SquareRouteRespectsLimitsAndVisitsTheCorners) {
  const std::vector<Vector2> route = {{0, 0}, {10, 0}, {10, 6}, {0, 6}};
  TrajectoryOptions options;
  options.laps = 2;
  const auto samples = generate_trajectory(route, options);
  expect_limits_hold(samples, options);
  // Starts and ends at rest at the first waypoint, facing the second at the start.
  EXPECT_EQ(samples.front().T_world_body.translation(), Vector2(0, 0));
  EXPECT_EQ(samples.front().T_world_body.angle(), 0.0);
  EXPECT_EQ(samples.front().speed_mps, 0.0);
  EXPECT_NEAR((samples.back().T_world_body.translation() - Vector2(0, 0)).norm(), 0.0, 1e-9);
  EXPECT_EQ(samples.back().speed_mps, 0.0);
  // A 90 degree corner rounded with radius R passes R (sqrt 2 - 1) from the corner point.
  const double R = options.corner_radius_m;
  for (const auto& corner : {Vector2(10, 0), Vector2(10, 6), Vector2(0, 6)}) {
    EXPECT_NEAR(distance_to_path(samples, corner), R * (std::numbers::sqrt2 - 1), 0.01);
  }
  // Two laps of the 10 x 6 rectangle (64 m) with seven rounded corners (the start and the end
  // are not corners), each shorter by (2 - pi/2) R than its two square legs.
  EXPECT_NEAR(path_length(samples), 64 - 7 * (2 - std::numbers::pi / 2) * R, 0.01);
}

TEST(Trajectory, SharpCornersBecomeTurnsOnTheSpot) {
  // Out and back: the 180 degree turn at (5, 0) exceeds max_arc_turn_rad.
  const std::vector<Vector2> route = {{0, 0}, {5, 0}};
  TrajectoryOptions options;
  options.laps = 1;
  const auto samples = generate_trajectory(route, options);
  expect_limits_hold(samples, options);
  EXPECT_NEAR(distance_to_path(samples, Vector2(5, 0)), 0.0, 1e-9);
  // Somewhere the robot turns while standing at (5, 0).
  bool spun = false;
  for (const auto& s : samples) {
    if ((s.T_world_body.translation() - Vector2(5, 0)).norm() < 1e-9 && std::abs(s.yaw_rate_rad_s) > 0.1) spun = true;
  }
  EXPECT_TRUE(spun);
  EXPECT_NEAR(std::abs(samples.back().T_world_body.angle()), std::numbers::pi, 1e-9);
}

TEST(Trajectory, FastTurnsSpinAtTheRequestedRate) {
  const std::vector<Vector2> route = {{0, 0}, {10, 0}, {10, 6}, {0, 6}};
  TrajectoryOptions options;
  options.laps = 1;
  options.max_arc_turn_rad = 0.3;
  options.spin_yaw_rate_rad_s = 2.5;
  options.spin_yaw_acceleration_rad_s2 = 8.0;
  const auto samples = generate_trajectory(route, options);
  expect_limits_hold(samples, options);
  double fastest = 0.0;
  for (const auto& s : samples) fastest = std::max(fastest, std::abs(s.yaw_rate_rad_s));
  EXPECT_NEAR(fastest, 2.5, 1e-9);
}

TEST(Trajectory, InvalidOptionsAreAllReported) {
  TrajectoryOptions options;
  options.max_speed_mps = 0;
  options.laps = 0;
  std::string why;
  EXPECT_FALSE(options.is_valid(&why));
  EXPECT_NE(why.find("max_speed_mps"), std::string::npos) << why;
  EXPECT_NE(why.find("laps"), std::string::npos) << why;
}

TEST(Odometry, NoiseFreeOdometryReproducesTheGroundTruth) {
  const WorldWithRoute office = office_world();
  TrajectoryOptions options;
  const auto truth = generate_trajectory(office.route, options);
  const OdometryTrack track = simulate_odometry(truth, OdometryNoise::none(), 1);
  ASSERT_EQ(track.poses.size(), truth.size());
  double worst_m = 0.0;
  double worst_rad = 0.0;
  for (std::size_t k = 0; k < truth.size(); ++k) {
    const SE2 error = truth[k].T_world_body.inverse() * track.poses[k];
    worst_m = std::max(worst_m, error.translation().norm());
    worst_rad = std::max(worst_rad, std::abs(error.angle()));
  }
  // Only rounding accumulates over ~30,000 compositions.
  EXPECT_LT(worst_m, 1e-9);
  EXPECT_LT(worst_rad, 1e-9);
  EXPECT_EQ(track.slip_events, 0u);
}

TEST(Odometry, NoisyOdometryDriftsAndVelocitiesMatchIncrements) {
  const WorldWithRoute office = office_world();
  const auto truth = generate_trajectory(office.route, TrajectoryOptions{});
  const OdometryTrack track = simulate_odometry(truth, OdometryNoise{}, 1);
  const SE2 end_error = truth.back().T_world_body.inverse() * track.poses.back();
  EXPECT_GT(end_error.translation().norm(), 0.1);  // the default noise is not negligible
  for (std::size_t k = 1; k < truth.size(); k += 97) {
    const SE2 increment = track.poses[k - 1].inverse() * track.poses[k];
    EXPECT_NEAR(track.speed_mps[k] * 0.01, increment.x(), 1e-12);
    EXPECT_NEAR(track.yaw_rate_rad_s[k] * 0.01, increment.angle(), 1e-12);
  }
}

TEST(Trajectory, AStartHeadingIsATurnOnTheSpotBeforeDriving) {
  const std::vector<Vector2> route = {{0, 0}, {0, 5}, {4, 5}};
  TrajectoryOptions options;
  options.laps = 1;
  const auto samples = generate_trajectory(route, options, false, std::numbers::pi);
  expect_limits_hold(samples, options);
  EXPECT_EQ(samples.front().T_world_body.angle(), std::numbers::pi);
  // It turns a quarter turn (to +y) where it stands, then drives.
  std::size_t k = 0;
  while (k < samples.size() && samples[k].T_world_body.translation().norm() == 0.0) ++k;
  ASSERT_LT(k, samples.size());
  EXPECT_NEAR(core::wrap_angle(samples[k - 1].T_world_body.angle() - std::numbers::pi / 2), 0.0, 1e-3);
  EXPECT_NEAR((samples.back().T_world_body.translation() - Vector2(4, 5)).norm(), 0.0, 1e-9);
  // Facing the first leg already: no turn, the same samples as without a start heading.
  const auto plain = generate_trajectory(route, options, false);
  const auto facing = generate_trajectory(route, options, false, std::numbers::pi / 2);
  ASSERT_EQ(plain.size(), facing.size());
  EXPECT_EQ(plain.back().T_world_body.translation(), facing.back().T_world_body.translation());
}

TEST(Odometry, ACarryIsNotSeenByTheWheels) {
  // Two samples 10 ms apart 5 m apart: a carry; the odometry reports exactly no motion there.
  std::vector<TrajectorySample> truth(4);
  for (std::size_t k = 0; k < truth.size(); ++k) truth[k].stamp = core::Timestamp::from_nanoseconds(static_cast<std::int64_t>(k) * 10'000'000);
  truth[1].T_world_body = SE2(0.01, 0.0, 0.0);
  truth[2].T_world_body = SE2(5.0, 3.0, 1.0);
  truth[3].T_world_body = SE2(5.0, 3.0, 1.0) * SE2(0.01, 0.0, 0.0);
  const OdometryTrack track = simulate_odometry(truth, OdometryNoise{}, 3, {2});
  EXPECT_EQ(track.poses[2].translation(), track.poses[1].translation());
  EXPECT_EQ(track.poses[2].angle(), track.poses[1].angle());
  EXPECT_EQ(track.speed_mps[2], 0.0);
  EXPECT_NEAR((track.poses[3].translation() - track.poses[2].translation()).norm(), 0.01, 0.005);
}

}  // namespace
}  // namespace cairn::sim
