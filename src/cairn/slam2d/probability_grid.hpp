#pragma once
/// \file
/// 2D occupancy probability grid with log-odds updates (Thrun, Burgard & Fox, "Probabilistic
/// Robotics", 2005, sec. 9.2), the map the scan matcher scores against. Cells are square, of side
/// `resolution_m`; a point p lies in the cell with global index floor(p / r), whatever the grid's
/// current extent.
/// The grid grows to contain every inserted ray.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "cairn/core/se2.hpp"

namespace cairn::slam2d {

struct ProbabilityGridOptions {
  double resolution_m = 0.05;      ///< cell side, metres; > 0
  double hit_probability = 0.55;   ///< p(occupied | hit), in (0.5, 1) (Cartographer's default)
  double miss_probability = 0.49;  ///< p(occupied | ray passed through), in (0, 0.5)
  double min_probability = 0.12;   ///< clamp, keeps cells revisable
  double max_probability = 0.97;
};

class ProbabilityGrid {
 public:
  explicit ProbabilityGrid(const ProbabilityGridOptions& options = {});

  /// Makes the grid contain the box [lower, upper] (map frame) at once, so that inserting rays
  /// within it never regrows the grid (each doubling copies the whole grid: measured 5 % of
  /// `cairn slam2d`'s CPU time on MIT CSAIL with perf, 2026-11-25). An empty grid is allocated to
  /// the box's cells exactly; a non-empty one grows, in one copy, on the sides the box crosses
  /// (by at least a quarter of its side there). Cell values never depend on the extent (cells
  /// are indexed globally), only width(), height(), origin() do.
  void reserve(const Eigen::Vector2d& lower, const Eigen::Vector2d& upper);

  /// Inserts a scan taken at `T_map_sensor`: `points_sensor` are the hit points in the sensor
  /// frame; cells on each ray are updated as misses, the end cell as a hit. Points flagged as
  /// no-return (`hit[k] == false`) only update misses along the ray.
  void insert(const core::SE2& T_map_sensor, const std::vector<Eigen::Vector2d>& points_sensor,
              const std::vector<bool>& hit);

  /// Occupancy probability at a point (nearest cell); `0.5` for unknown cells.
  double probability(const Eigen::Vector2d& point_map) const;
  /// Whether the cell containing `point_map` has been observed.
  bool known(const Eigen::Vector2d& point_map) const;

  double resolution() const { return options_.resolution_m; }
  int width() const { return width_; }
  int height() const { return height_; }
  /// Lower-left corner of cell (0, 0).
  Eigen::Vector2d origin() const {
    return Eigen::Vector2d(static_cast<double>(offset_i_), static_cast<double>(offset_j_)) * options_.resolution_m;
  }
  /// Probability of cell (i, j); 0.5 if unknown or outside.
  double cell_probability(int i, int j) const;
  /// Whether cell (i, j) has been observed (false outside).
  bool cell_known(int i, int j) const;
  /// Row j of the stored log-odds (width() values; as cell_log_odds, 0 where unknown) and of the
  /// observed flags (nonzero: observed), for loops over many cells; 0 <= j < height().
  const float* log_odds_row(int j) const { return log_odds_.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(width_); }
  const std::uint8_t* known_row(int j) const { return known_.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(width_); }
  /// The probability cell_probability() returns for an observed cell of log-odds `l`.
  static double probability_of_log_odds(float l);
  /// Bounding box [i0, i1] x [j0, j1] of the observed cells; false if none is observed.
  bool known_bounds(int& i0, int& j0, int& i1, int& j1) const;
  /// Global index floor(x / r) of column 0 and floor(y / r) of row 0.
  long offset_i() const { return offset_i_; }
  long offset_j() const { return offset_j_; }
  const ProbabilityGridOptions& options() const { return options_; }

  /// Raw access for saving and restoring a grid (map_file.hpp). The stored log-odds of cell
  /// (i, j), log(p / (1 - p)) as a float, within [min_log_odds(), max_log_odds()] up to float
  /// rounding; 0 for unknown cells and outside the grid.
  float cell_log_odds(int i, int j) const;
  /// Clamp bounds in log-odds: log-odds of options().min_probability and max_probability.
  double min_log_odds() const { return min_log_odds_; }
  double max_log_odds() const { return max_log_odds_; }
  /// A grid with the given cells, as cell_log_odds() and cell_known() would return them:
  /// `width` x `height` cells whose column 0 / row 0 have global indices `offset_i` / `offset_j`,
  /// row-major (index j * width + i). Unknown cells must hold log-odds 0. Preconditions
  /// (CAIRN_ASSERT; a reader validates file data before calling): width, height >= 0 (both 0
  /// or both > 0), |offset| < 1e8, vector sizes width * height, every known value finite and
  /// within the clamp bounds (1e-5 of float slack).
  static ProbabilityGrid from_cells(const ProbabilityGridOptions& options, long offset_i, long offset_j, int width,
                                    int height, std::vector<float> log_odds, std::vector<std::uint8_t> known);

 private:
  /// Throws std::out_of_range: a point more than 1e8 cells from the origin.
  [[noreturn]] void throw_too_far(const Eigen::Vector2d& point_map) const;
  void grow_to_contain(const Eigen::Vector2d& point_map);
  /// Re-lays the cells over global columns [low_i, high_i) x rows [low_j, high_j) (a superset).
  void resize_to(long low_i, long low_j, long high_i, long high_j);
  bool cell_of(const Eigen::Vector2d& point_map, int& i, int& j) const;
  void update(int i, int j, double log_odds_change);

  ProbabilityGridOptions options_;
  double min_log_odds_ = 0.0;  ///< clamp bounds, log-odds of min/max_probability
  double max_log_odds_ = 0.0;
  long offset_i_ = 0;  ///< global index floor(x / r) of cell column 0
  long offset_j_ = 0;
  int width_ = 0;
  int height_ = 0;
  std::vector<float> log_odds_;
  std::vector<std::uint8_t> known_;
};

}  // namespace cairn::slam2d
