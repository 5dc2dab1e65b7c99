// The probability grid and the exhaustive correlative matcher on a synthetic room: a scan taken
// at a known pose, matched from a displaced guess against a map built from another pose, comes
// back to within two cells and two angular steps (the lattice of the search plus the map's own
// quantisation; sub-cell accuracy is the job of the continuous refinement that follows).

#include <gtest/gtest.h>

#include <cmath>

#include "cairn/slam2d/correlative_scan_matcher.hpp"

namespace cairn::slam2d {
namespace {

// Ranges from `pose` to the walls of an axis-aligned 8 m x 6 m room with a 1 m pillar, by ray
// casting in closed form; 360 beams over 360 degrees.
std::vector<Eigen::Vector2d> room_scan(const core::SE2& T_room_sensor) {
  std::vector<Eigen::Vector2d> points;
  for (int k = 0; k < 360; ++k) {
    const double a = k * M_PI / 180.0;
    const Eigen::Vector2d d_room = T_room_sensor.so2() * Eigen::Vector2d(std::cos(a), std::sin(a));
    const Eigen::Vector2d o = T_room_sensor.translation();
    double t = 1e9;
    for (const double wall : {0.0, 8.0}) {
      if (std::abs(d_room.x()) > 1e-12) {
        const double s = (wall - o.x()) / d_room.x();
        if (s > 0) t = std::min(t, s);
      }
    }
    for (const double wall : {0.0, 6.0}) {
      if (std::abs(d_room.y()) > 1e-12) {
        const double s = (wall - o.y()) / d_room.y();
        if (s > 0) t = std::min(t, s);
      }
    }
    // Pillar: the box [5, 6] x [2, 3], slab method.
    double t0 = 0.0, t1 = 1e9;
    bool inside = true;
    for (int axis = 0; axis < 2; ++axis) {
      const double lo = axis == 0 ? 5.0 : 2.0;
      const double hi = lo + 1.0;
      if (std::abs(d_room[axis]) < 1e-12) {
        if (o[axis] < lo || o[axis] > hi) inside = false;
        continue;
      }
      double a0 = (lo - o[axis]) / d_room[axis];
      double a1 = (hi - o[axis]) / d_room[axis];
      if (a0 > a1) std::swap(a0, a1);
      t0 = std::max(t0, a0);
      t1 = std::min(t1, a1);
    }
    if (inside && t0 <= t1 && t0 > 0) t = std::min(t, t0);
    points.push_back(t * Eigen::Vector2d(std::cos(a), std::sin(a)));
  }
  return points;
}

TEST(ProbabilityGrid, HitsBecomeOccupiedAndRaysFree) {
  ProbabilityGrid grid;
  const core::SE2 T(2.0, 3.0, 0.0);
  const auto points = room_scan(T);
  grid.insert(T, points, std::vector<bool>(points.size(), true));
  EXPECT_GT(grid.probability(T * points[90]), 0.54);  // one hit on the wall ahead of beam 90: p = 0.55
  EXPECT_LT(grid.probability(Eigen::Vector2d(3.0, 3.0)), 0.5);  // free space on the ray
  EXPECT_FALSE(grid.known(Eigen::Vector2d(-5.0, -5.0)));
  EXPECT_DOUBLE_EQ(grid.probability(Eigen::Vector2d(-5.0, -5.0)), 0.5);
}

TEST(CorrelativeScanMatcher, RecoversADisplacedPose) {
  ProbabilityGrid grid;
  const core::SE2 T_map_first(2.0, 3.0, 0.1);
  for (int repeat = 0; repeat < 3; ++repeat) {
    const auto points = room_scan(T_map_first);
    grid.insert(T_map_first, points, std::vector<bool>(points.size(), true));
  }
  const core::SE2 truth(2.6, 2.8, 0.25);
  const auto scan = room_scan(truth);
  const core::SE2 guess(2.45, 2.95, 0.1);  // 0.15 m and 0.15 rad off
  const MatchResult result = match_exhaustive(grid, scan, guess);
  EXPECT_LT((result.T_map_sensor.translation() - truth.translation()).norm(), 2.0 * grid.resolution());
  EXPECT_LT(std::abs(core::wrap_angle(result.T_map_sensor.angle() - truth.angle())), 2.0 * result.angular_step_rad);
  // The guess itself scores clearly worse than the match.
  const MatchResult at_guess = match_exhaustive(grid, scan, guess, CorrelativeMatcherOptions{0.0, 0.0});
  EXPECT_LT(at_guess.score + 0.05, result.score);
  EXPECT_GT(result.candidates, 1000);
}

}  // namespace
}  // namespace cairn::slam2d
