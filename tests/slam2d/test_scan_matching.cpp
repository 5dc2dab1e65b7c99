// The probability grid and the exhaustive correlative matcher on a synthetic room: a scan taken
// at a known pose, matched from a displaced guess against a map built from another pose, comes
// back to within two cells and two angular steps (the lattice of the search plus the map's own
// quantisation; sub-cell accuracy is the job of the continuous refinement that follows).

#include <gtest/gtest.h>

#include <cmath>

#include <random>

#include "cairn/slam2d/branch_and_bound.hpp"
#include "cairn/slam2d/correlative_scan_matcher.hpp"
#include "cairn/slam2d/icp.hpp"
#include "cairn/slam2d/place_search.hpp"

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

// slam2d grows a submap's grid keyframe by keyframe (ProbabilityGrid::reserve around each) where
// it once reserved the whole submap at once: the cells, their extent and the precomputation
// grids must not depend on how the memory grew (only the same updates in the same order).
TEST(ProbabilityGrid, CellsDoNotDependOnHowTheGridGrew) {
  std::vector<core::SE2> poses;
  for (int k = 0; k < 12; ++k) poses.emplace_back(1.0 + 0.5 * k, 1.5 + 0.25 * std::sin(k), 0.3 * k);
  // Ranges cut to 3 m, so the rays of later poses leave the first poses' extent.
  std::vector<std::vector<Eigen::Vector2d>> scans;
  for (const core::SE2& T : poses) {
    std::vector<Eigen::Vector2d> points;
    for (const Eigen::Vector2d& p : room_scan(T)) points.push_back(p.norm() > 3.0 ? Eigen::Vector2d(3.0 * p.normalized()) : p);
    scans.push_back(points);
  }
  ProbabilityGrid at_once, per_scan, doubling;
  Eigen::Vector2d lower = Eigen::Vector2d::Constant(1e9), upper = Eigen::Vector2d::Constant(-1e9);
  for (std::size_t k = 0; k < poses.size(); ++k) {
    for (const auto& p : scans[k]) {
      lower = lower.cwiseMin(poses[k] * p);
      upper = upper.cwiseMax(poses[k] * p);
    }
  }
  at_once.reserve(lower, upper);
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const std::vector<bool> hits(scans[k].size(), true);
    Eigen::Vector2d scan_lower = poses[k].translation(), scan_upper = poses[k].translation();
    for (const auto& p : scans[k]) {
      scan_lower = scan_lower.cwiseMin(poses[k] * p);
      scan_upper = scan_upper.cwiseMax(poses[k] * p);
    }
    per_scan.reserve(scan_lower - Eigen::Vector2d::Constant(0.5), scan_upper + Eigen::Vector2d::Constant(0.5));
    at_once.insert(poses[k], scans[k], hits);
    per_scan.insert(poses[k], scans[k], hits);
    doubling.insert(poses[k], scans[k], hits);
  }
  // The layouts do differ.
  for (const ProbabilityGrid* other : {&per_scan, &doubling}) {
    ASSERT_TRUE(other->offset_i() != at_once.offset_i() || other->offset_j() != at_once.offset_j() ||
                other->width() != at_once.width() || other->height() != at_once.height());
  }
  const ProbabilityGrid* grids[] = {&at_once, &per_scan, &doubling};
  Eigen::Vector2d extent_lower[3], extent_upper[3];
  for (int g = 0; g < 3; ++g) ASSERT_TRUE(observed_extent(*grids[g], extent_lower[g], extent_upper[g]));
  for (int g = 1; g < 3; ++g) {
    EXPECT_EQ(extent_lower[g], extent_lower[0]) << "grid " << g;  // bit for bit
    EXPECT_EQ(extent_upper[g], extent_upper[0]) << "grid " << g;
  }
  const double r = at_once.resolution();
  int known = 0;
  for (double y = extent_lower[0].y() + 0.5 * r; y < extent_upper[0].y(); y += r) {
    for (double x = extent_lower[0].x() + 0.5 * r; x < extent_upper[0].x(); x += r) {
      const Eigen::Vector2d p(x, y);
      known += at_once.known(p) ? 1 : 0;
      for (int g = 1; g < 3; ++g) {
        ASSERT_EQ(grids[g]->known(p), at_once.known(p)) << "grid " << g << " at " << p.transpose();
        ASSERT_EQ(grids[g]->probability(p), at_once.probability(p)) << "grid " << g << " at " << p.transpose();
      }
    }
  }
  EXPECT_GT(known, 1000);
  // The precomputation grids, on the heap and on the page arena, byte for byte.
  core::PageArena arena;
  const PrecomputationGridStack reference(at_once, BranchAndBoundOptions{});
  const PrecomputationGridStack grown(per_scan, BranchAndBoundOptions{}, &arena);
  ASSERT_EQ(grown.depth(), reference.depth());
  EXPECT_EQ(grown.memory_bytes(), reference.memory_bytes());
  for (int h = 0; h < reference.depth(); ++h) {
    const PrecomputationGridStack::LevelView a = reference.level(h), b = grown.level(h);
    ASSERT_EQ(a.offset_i, b.offset_i);
    ASSERT_EQ(a.offset_j, b.offset_j);
    ASSERT_EQ(a.width, b.width);
    ASSERT_EQ(a.height, b.height);
    EXPECT_TRUE(std::equal(a.values, a.values + a.width * a.height, b.values)) << "level " << h;
  }
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

// Branch and bound must find the exhaustive search's best score (Hess 2016: "the same result"),
// up to the 1/255 quantisation of the precomputation grids, while scoring far fewer poses.
TEST(BranchAndBound, FindsTheExhaustiveOptimum) {
  ProbabilityGrid grid;
  const core::SE2 T_map_first(2.0, 3.0, 0.1);
  for (int repeat = 0; repeat < 3; ++repeat) {
    const auto points = room_scan(T_map_first);
    grid.insert(T_map_first, points, std::vector<bool>(points.size(), true));
  }
  BranchAndBoundOptions options;
  options.linear_search_window_m = 0.3;
  options.angular_search_window_rad = 0.35;
  options.unknown_probability = 0.5;  // what match_exhaustive scores unknown cells with
  const PrecomputationGridStack stack(grid, options);
  std::mt19937 random(7);
  std::uniform_real_distribution<double> offset(-0.2, 0.2);
  for (int trial = 0; trial < 10; ++trial) {
    const core::SE2 truth(2.6 + offset(random), 2.8 + offset(random), 0.25 + offset(random));
    const auto scan = room_scan(truth);
    const core::SE2 guess(truth.x() + 0.5 * offset(random), truth.y() + 0.5 * offset(random), truth.angle() + 0.5 * offset(random));
    const MatchResult exhaustive = match_exhaustive(grid, scan, guess, CorrelativeMatcherOptions{0.3, 0.35});
    const BranchAndBoundResult fast = match_branch_and_bound(stack, scan, guess, 0.0, options);
    ASSERT_TRUE(fast.found);
    EXPECT_NEAR(fast.score, exhaustive.score, 1.0 / 255.0 + 1e-9) << "trial " << trial;
    EXPECT_LT((fast.T_map_sensor.translation() - truth.translation()).norm(), 2.0 * grid.resolution());
    EXPECT_LT(fast.nodes_scored * 5, exhaustive.candidates) << "branch and bound should prune most of the window";
  }
}

// A pose inside the excluded region is never returned: the ambiguity search of loop
// verification relies on it.
TEST(BranchAndBound, ExclusionSkipsTheBestMatch) {
  ProbabilityGrid grid;
  const core::SE2 T(2.0, 3.0, 0.1);
  for (int repeat = 0; repeat < 3; ++repeat) {
    const auto points = room_scan(T);
    grid.insert(T, points, std::vector<bool>(points.size(), true));
  }
  BranchAndBoundOptions options;
  options.linear_search_window_m = 1.0;
  const PrecomputationGridStack stack(grid, options);
  const auto scan = room_scan(T);
  const BranchAndBoundResult best = match_branch_and_bound(stack, scan, T, 0.0, options);
  ASSERT_TRUE(best.found);
  const BranchAndBoundResult other = match_branch_and_bound(stack, scan, T, 0.0, options, &best.T_map_sensor, 0.5, 0.2);
  ASSERT_TRUE(other.found);
  const bool outside = (other.T_map_sensor.translation() - best.T_map_sensor.translation()).norm() > 0.5 ||
                       std::abs(core::wrap_angle(other.T_map_sensor.angle() - best.T_map_sensor.angle())) > 0.2;
  EXPECT_TRUE(outside);
  EXPECT_LT(other.score, best.score - 0.1);  // a room with a pillar has one good pose
}

std::vector<Eigen::Vector2d> transform(const core::SE2& T, const std::vector<Eigen::Vector2d>& points) {
  std::vector<Eigen::Vector2d> out;
  for (const auto& p : points) out.push_back(T * p);
  return out;
}

TEST(Icp, RecoversADisplacedPoseToTheMillimetre) {
  const core::SE2 T_map_first(2.0, 3.0, 0.1);
  PointMap map;
  map.build(transform(T_map_first, room_scan(T_map_first)));
  const core::SE2 truth(2.3, 2.9, 0.2);
  const auto scan = room_scan(truth);
  const core::SE2 guess(2.4, 2.85, 0.15);
  const IcpResult result = match_icp(map, scan, guess, nullptr);
  EXPECT_LT((result.T_map_sensor.translation() - truth.translation()).norm(), 0.005);
  EXPECT_LT(std::abs(core::wrap_angle(result.T_map_sensor.angle() - truth.angle())), 0.002);
  EXPECT_GT(result.inlier_fraction, 0.9);
  EXPECT_GT(result.degeneracy, 0.1);  // walls in both directions
}

// Two parallel walls 60 m long: the axis is unobservable. The match must say so (degeneracy
// near 0) and take the along-corridor position from the prior, correcting only across.
TEST(Icp, CorridorIsDegenerateAndFollowsThePrior) {
  auto corridor_scan = [](const core::SE2& T) {
    std::vector<Eigen::Vector2d> points;
    for (int k = 0; k < 180; ++k) {
      const double a = -M_PI / 2 + k * M_PI / 180.0;
      const Eigen::Vector2d d = T.so2() * Eigen::Vector2d(std::cos(a), std::sin(a));
      if (std::abs(d.y()) < 1e-9) continue;
      const double wall = d.y() > 0 ? 1.2 : -1.2;
      const double t = (wall - T.y()) / d.y();
      const Eigen::Vector2d hit = T.translation() + t * d;
      if (t > 0 && t < 30.0 && std::abs(hit.x()) < 30.0) points.push_back(t * Eigen::Vector2d(std::cos(a), std::sin(a)));
    }
    return points;
  };
  const core::SE2 T_map_first(0.0, 0.0, 0.0);
  PointMap map;
  std::vector<Eigen::Vector2d> dense;
  for (double x = -30.0; x <= 30.0; x += 0.02) {
    dense.emplace_back(x, 1.2);
    dense.emplace_back(x, -1.2);
  }
  map.build(dense);
  const core::SE2 truth(1.0, 0.1, 0.02);
  const core::SE2 prior(1.3, 0.2, 0.0);  // 0.3 m ahead along the axis, 0.1 m across
  const IcpResult result = match_icp(map, corridor_scan(truth), prior, &prior);
  EXPECT_LT(result.degeneracy, 0.01);
  // The direction it names is the corridor's axis, x in the map frame (either sign).
  EXPECT_NEAR(std::abs(result.degenerate_direction.x()), 1.0, 1e-6);
  EXPECT_TRUE(result.remapped);
  EXPECT_NEAR(result.T_map_sensor.x(), prior.x(), 1e-6);  // unobservable: the prior's value
  EXPECT_NEAR(result.T_map_sensor.y(), truth.y(), 0.005);  // observable: corrected
  EXPECT_NEAR(result.T_map_sensor.angle(), truth.angle(), 0.002);
}

// The degenerate direction in words, relative to the laser (by hand: a laser turned 90 degrees
// left sees the map's x axis as its sideways axis and the map's y axis as its forward one).
TEST(Icp, NamesADirectionRelativeToTheLaser) {
  const core::SE2 facing_y(0.0, 0.0, M_PI / 2);
  EXPECT_EQ(name_direction(Eigen::Vector2d(1.0, 0.0), facing_y), "translation along the laser's sideways axis");
  EXPECT_EQ(name_direction(Eigen::Vector2d(0.0, -1.0), facing_y), "translation along the laser's forward axis");
  const core::SE2 facing_x(5.0, -2.0, 0.0);
  EXPECT_EQ(name_direction(Eigen::Vector2d(std::sqrt(0.5), std::sqrt(0.5)), facing_x),
            "translation along the axis 45 degrees counterclockwise from the laser's forward axis");
  EXPECT_EQ(name_direction(Eigen::Vector2d(std::sqrt(0.5), -std::sqrt(0.5)), facing_x),
            "translation along the axis 135 degrees counterclockwise from the laser's forward axis");
  EXPECT_EQ(name_direction(Eigen::Vector2d::Zero(), facing_x), "one translation direction");
}

}  // namespace
}  // namespace cairn::slam2d
