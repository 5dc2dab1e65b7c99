#include "cairn/slam2d/place_search.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "cairn/core/so2.hpp"
#include "cairn/slam2d/icp.hpp"

namespace cairn::slam2d {

bool search_and_verify(const PrecomputationGridStack& stack, const PointMap& map_points,
                       const std::vector<Eigen::Vector2d>& matching, const core::SE2& initial,
                       const BranchAndBoundOptions& window, double min_score, const Slam2dOptions& options,
                       LoopCandidate& candidate, const std::vector<Eigen::Vector2d>* search_points,
                       double ambiguity_window_m, double ambiguity_window_rad) {
  const std::vector<Eigen::Vector2d>& searched = search_points != nullptr ? *search_points : matching;
  const BranchAndBoundResult best = match_branch_and_bound(stack, searched, initial, min_score, window);
  if (!best.found) return false;
  candidate.search_window_m = window.linear_search_window_m;
  candidate.score = best.score;
  // Verification 1: refine by ICP against the map's points (no prior) and check the fit.
  IcpOptions refine = options.icp;
  refine.prior_translation_sigma_m = 0.0;
  const IcpResult icp = match_icp(map_points, matching, best.T_map_sensor, nullptr, refine);
  candidate.inlier_fraction = icp.inlier_fraction;
  candidate.rms_m = icp.rms_m;
  candidate.degeneracy = icp.degeneracy;
  candidate.T_anchor_keyframe = icp.T_map_sensor;
  candidate.accepted = false;
  const double moved = (icp.T_map_sensor.translation() - best.T_map_sensor.translation()).norm();
  if (icp.inlier_fraction < options.loop_min_inlier_fraction) {
    candidate.reason = "ICP inlier fraction below minimum";
  } else if (icp.inliers < options.loop_min_inliers) {
    candidate.reason = "too few points to verify (" + std::to_string(icp.inliers) + " inliers, " +
                       std::to_string(options.loop_min_inliers) + " needed)";
  } else if (icp.rms_m > options.loop_max_rms_m) {
    candidate.reason = "ICP residual above maximum";
  } else if (moved > 2.0 * options.grid.resolution_m + 0.05) {
    candidate.reason = "ICP moved away from the branch-and-bound match";
  } else if (icp.degeneracy < options.loop_min_degeneracy) {
    candidate.reason = "degenerate: the match does not constrain every direction (corridor)";
  } else {
    // Verification 2: ambiguity. Is there a pose elsewhere in the window nearly as good?
    BranchAndBoundOptions wide = window;
    wide.linear_search_window_m = std::max({window.linear_search_window_m, options.loop_ambiguity_window_m, ambiguity_window_m});
    wide.angular_search_window_rad = std::min(std::max(window.angular_search_window_rad, ambiguity_window_rad), std::numbers::pi);
    const BranchAndBoundResult other =
        match_branch_and_bound(stack, searched, initial, best.score - options.loop_ambiguity_margin, wide, &best.T_map_sensor,
                               options.loop_ambiguity_distance_m, options.loop_ambiguity_angle_rad);
    candidate.second_score = other.found ? other.score : 0.0;
    if (other.found) {
      candidate.reason = "ambiguous: another pose scores within the margin";
    } else {
      candidate.accepted = true;
      candidate.reason = "accepted";
    }
  }
  return true;
}

bool observed_extent(const ProbabilityGrid& grid, Eigen::Vector2d& lower, Eigen::Vector2d& upper) {
  int i0 = 0, j0 = 0, i1 = 0, j1 = 0;
  if (!grid.known_bounds(i0, j0, i1, j1)) return false;
  // In global cell indices, so the extent does not depend on where the grid's memory starts
  // (a grid grown keyframe by keyframe and one reserved at once give the same bytes): the
  // corner of the first observed cell, then the observed size.
  const double r = grid.resolution();
  const Eigen::Vector2d corner = Eigen::Vector2d(static_cast<double>(grid.offset_i() + i0), static_cast<double>(grid.offset_j() + j0)) * r;
  lower = corner;
  upper = corner + Eigen::Vector2d(i1 - i0 + 1, j1 - j0 + 1) * r;
  return true;
}

void global_window(const Eigen::Vector2d& lower, const Eigen::Vector2d& upper, double margin_m,
                   const BranchAndBoundOptions& base, BranchAndBoundOptions& window, core::SE2& initial) {
  window = base;
  window.linear_search_window_m = 0.5 * (upper - lower).maxCoeff() + margin_m;
  window.angular_search_window_rad = std::numbers::pi;
  initial = core::SE2(core::SO2(0.0), 0.5 * (lower + upper));
}

}  // namespace cairn::slam2d
