#pragma once
/// \file
/// Exhaustive correlative scan matching (Olson, "Real-time correlative scan matching", ICRA
/// 2009; Hess et al., "Real-time loop closure in 2D LIDAR SLAM", ICRA 2016, sec. IV): every pose
/// of a search window around an initial guess is scored by the mean occupancy probability of the
/// scan's points in the grid; the best one wins. The angular step follows Hess 2016 eq. (7),
/// delta_theta = arccos(1 - r^2 / (2 d_max^2)), so no point moves more than one cell r between
/// neighbouring angles. This is the reference the faster branch-and-bound search is tested
/// against.

#include <Eigen/Core>
#include <vector>

#include "cairn/slam2d/probability_grid.hpp"

namespace cairn::slam2d {

struct CorrelativeMatcherOptions {
  double linear_search_window_m = 0.3;    ///< half-width of the x and y windows; >= 0
  double angular_search_window_rad = 0.35; ///< half-width of the angle window; >= 0
};

struct MatchResult {
  core::SE2 T_map_sensor;
  double score = 0.0;        ///< mean probability of the points at the best pose, in [0, 1]
  long candidates = 0;       ///< poses scored
  double angular_step_rad = 0.0;
};

/// Preconditions: at least one point.
MatchResult match_exhaustive(const ProbabilityGrid& grid, const std::vector<Eigen::Vector2d>& points_sensor,
                             const core::SE2& initial_T_map_sensor, const CorrelativeMatcherOptions& options = {});

}  // namespace cairn::slam2d
