#pragma once
/// \file
/// Finding a scan in a finished map and deciding whether to believe it: the search and
/// verification shared by loop closure, relocalisation, map merging (slam.hpp) and pure
/// localisation in a saved map.
///
///  1. Branch-and-bound correlative search of the scan's matching points in the map's grid
///     around an initial pose (Hess et al. ICRA 2016, sec. V-C), above a minimum score.
///  2. Verification: ICP refinement against the map's points without a prior (enough inliers,
///     small RMS, no large move away from the search's pose, every direction constrained), then
///     an ambiguity search: another pose farther than `loop_ambiguity_distance_m` (or rotated
///     more than `loop_ambiguity_angle_rad`) scoring within `loop_ambiguity_margin` of the best
///     rejects the match (repeated structure such as identical doors).
///
/// `global_window` spans a whole map: translations over its observed extent and every heading,
/// for a robot that may be anywhere in it (a kidnapping, a new map segment whose odometry
/// link is not trusted, the first scan of a localisation session).

#include <Eigen/Core>
#include <vector>

#include "cairn/core/se2.hpp"
#include "cairn/slam2d/branch_and_bound.hpp"
#include "cairn/slam2d/point_map.hpp"
#include "cairn/slam2d/probability_grid.hpp"
#include "cairn/slam2d/slam.hpp"

namespace cairn::slam2d {

/// Search of `matching` (sensor frame) in a map (precomputation grids + points, one frame) over
/// `window` around `initial`, then the verification above with `options`' loop_* thresholds and
/// ICP settings. Fills the match fields of `candidate` (score, second score, inliers, RMS,
/// degeneracy, T_anchor_keyframe = the verified pose in the map's frame, accepted, reason).
/// Returns false when the search finds nothing above `min_score` (candidate then untouched).
/// `search_points`, when given, replaces `matching` in the two branch-and-bound searches (a
/// range-limited subset for whole-submap searches); ICP always verifies with `matching`.
/// The ambiguity search spans at least `ambiguity_window_m` / `ambiguity_window_rad` (the
/// uncertainty of the estimate the search started from, which may exceed the search window:
/// in a building whose rooms repeat every 7 m, a 7 m window after 11 m of drift holds only the
/// wrong room).
bool search_and_verify(const PrecomputationGridStack& stack, const PointMap& map_points,
                       const std::vector<Eigen::Vector2d>& matching, const core::SE2& initial,
                       const BranchAndBoundOptions& window, double min_score, const Slam2dOptions& options,
                       LoopCandidate& candidate, const std::vector<Eigen::Vector2d>* search_points = nullptr,
                       double ambiguity_window_m = 0.0, double ambiguity_window_rad = 0.0);

/// The observed extent of `grid` (corners of its observed cells); false when none is observed.
bool observed_extent(const ProbabilityGrid& grid, Eigen::Vector2d& lower, Eigen::Vector2d& upper);

/// A search window over the box [lower, upper] (a map's observed extent, in the map's frame)
/// plus `margin_m`, and every heading; the pose to search around is the box's centre, heading 0.
void global_window(const Eigen::Vector2d& lower, const Eigen::Vector2d& upper, double margin_m,
                   const BranchAndBoundOptions& base, BranchAndBoundOptions& window, core::SE2& initial);

}  // namespace cairn::slam2d
