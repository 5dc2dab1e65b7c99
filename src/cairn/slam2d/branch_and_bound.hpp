#pragma once
/// \file
/// Branch-and-bound correlative scan matching (Hess et al., "Real-time loop closure in 2D LIDAR
/// SLAM", ICRA 2016, sec. V-C, Algorithm 3; Olson 2009's multi-resolution idea): the exhaustive
/// search of match_exhaustive, with the same answer, over windows of metres and tens of degrees.
///
/// For each height h = 0 .. depth-1 a precomputation grid holds, per cell (i, j), the maximum of
/// the map's probability over the 2^h x 2^h cells [i, i + 2^h) x [j, j + 2^h) (Hess eq. (14)), so
/// the score of a node covering 2^h x 2^h translations is an upper bound of its leaves' scores
/// (eq. (15)). Depth-first search with the best child first; nodes whose bound is not above the
/// best leaf found so far (initially the minimum score) are pruned.
///
/// Scores are the mean probability of the scan's points; unknown cells count as
/// `unknown_probability` (low, so a scan is not rewarded for landing in unexplored space).
///
/// `excluded_*`: a second search can skip every leaf within a distance of a given pose; the best
/// remaining score measures how ambiguous the best match is (the corridor of identical doors).

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "cairn/core/page_arena.hpp"
#include "cairn/core/se2.hpp"
#include "cairn/slam2d/probability_grid.hpp"

namespace cairn::slam2d {

struct BranchAndBoundOptions {
  double linear_search_window_m = 7.0;     ///< half-width in x and y (Cartographer's 7 m); >= 0
  double angular_search_window_rad = 0.5236;  ///< half-width, 30 degrees; >= 0
  int depth = 7;                           ///< precomputation grids (Cartographer's 7); >= 1
  double unknown_probability = 0.1;        ///< score of unknown cells, in [0, 1]
  /// The angle step is Hess et al.'s eq. (7) with d_max = this quantile of the scan's ranges:
  /// 1 (the farthest point, the paper's choice) moves no point by more than a cell between two
  /// angles; 0.9 lets the farthest tenth move up to a few cells and halves the angles (the
  /// ICP refinement after a search recovers the sub-step angle). In (0, 1].
  double angular_step_range_quantile = 1.0;
};

/// The precomputation grids of one map (built once per finished submap).
class PrecomputationGridStack {
 public:
  /// With `arena`, the levels live in its huge-page chunks (core::PageArena: for stacks kept for
  /// a whole run); without, on the heap.
  PrecomputationGridStack(const ProbabilityGrid& grid, const BranchAndBoundOptions& options, core::PageArena* arena = nullptr);

  int depth() const { return static_cast<int>(levels_.size()); }
  double resolution() const { return resolution_; }
  /// Max over [i, i + 2^h) x [j, j + 2^h) of cell probabilities, cell indices global
  /// (floor(p / resolution)); in [0, 1].
  double value(int height, long i, long j) const { return raw_value(height, i, j) / 255.0; }
  /// The same maximum as stored: probability * 255 rounded up (scores sum these exactly).
  std::uint8_t raw_value(int height, long i, long j) const {
    const Level& level = levels_[static_cast<std::size_t>(height)];
    const long li = i - level.offset_i;
    const long lj = j - level.offset_j;
    if (li < 0 || lj < 0 || li >= level.width || lj >= level.height) return outside_;
    return storage_.data[level.start + static_cast<std::size_t>(lj * level.width + li)];
  }
  std::size_t memory_bytes() const;

  /// One level's storage, for scoring loops that hoist the lookups (raw_value's arithmetic).
  struct LevelView {
    const std::uint8_t* values = nullptr;
    long offset_i = 0;
    long offset_j = 0;
    long width = 0;
    long height = 0;
    std::uint8_t outside = 0;
  };
  LevelView level(int height) const {
    const Level& l = levels_[static_cast<std::size_t>(height)];
    return {storage_.data + l.start, l.offset_i, l.offset_j, l.width, l.height, outside_};
  }

 private:
  struct Level {
    long offset_i = 0;  ///< global index of column 0
    long offset_j = 0;
    int width = 0;
    int height = 0;
    std::size_t start = 0;  ///< of its width x height values in storage_, row by row
  };
  double resolution_ = 0.05;
  std::uint8_t outside_ = 0;
  std::vector<Level> levels_;
  /// Every level's values, probability * 255 rounded up (keeps the bound), in one block.
  core::PageArena::Block storage_;
};

struct BranchAndBoundResult {
  bool found = false;        ///< a pose scored above min_score
  core::SE2 T_map_sensor;
  double score = 0.0;
  long nodes_scored = 0;
};

/// Best pose within the windows around `initial` scoring above `min_score`. With `excluded`,
/// leaves within `excluded_distance_m` and `excluded_angle_rad` of it are skipped.
BranchAndBoundResult match_branch_and_bound(const PrecomputationGridStack& stack,
                                            const std::vector<Eigen::Vector2d>& points_sensor,
                                            const core::SE2& initial, double min_score,
                                            const BranchAndBoundOptions& options,
                                            const core::SE2* excluded = nullptr, double excluded_distance_m = 0.0,
                                            double excluded_angle_rad = 0.0);

}  // namespace cairn::slam2d
