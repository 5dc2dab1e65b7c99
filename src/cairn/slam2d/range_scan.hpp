#pragma once
/// \file
/// From a laser record to the points the SLAM front end uses: ranges become points in the laser
/// frame; readings outside [min_range, max_range) are no-returns (kept as free-space rays for the
/// map, never matched); the matched points are thinned by an adaptive voxel filter
/// (Hess et al. 2016, sec. IV-A; Cartographer's adaptive_voxel_filter): the largest voxel that
/// still leaves `min_points` points, so sparse and dense scans get similar weight.

#include <Eigen/Core>
#include <vector>

#include "cairn/io/carmen_log.hpp"

namespace cairn::slam2d {

struct ScanFilterOptions {
  double min_range_m = 0.1;   ///< readings below are dropped (dust, the robot itself); >= 0
  /// Readings at or beyond are no-returns. The log's own max range (PARAM) wins when smaller.
  /// 30 m suits the SICK LMS 200 logs of the Freiburg benchmark (80 m / 81.9 m max-range codes).
  double max_range_m = 30.0;
  /// Length of the free-space ray inserted for a no-return, metres (0 = none).
  double missing_ray_length_m = 5.0;
  double voxel_size_m = 0.025;  ///< fixed voxel filter applied to every scan first (0 = off)
  /// Adaptive voxel filter for matching: start at the fixed size, double while the scan keeps at
  /// least `min_points` points, up to `max_voxel_size_m`.
  int adaptive_min_points = 150;
  double adaptive_max_voxel_size_m = 0.5;
};

/// One scan in the laser frame.
struct ScanPoints {
  std::vector<Eigen::Vector2d> hits;       ///< all returns after the fixed voxel filter (for the map)
  std::vector<Eigen::Vector2d> misses;     ///< end points of free rays for no-returns
  std::vector<Eigen::Vector2d> matching;   ///< adaptively thinned returns (for scan matching)
  int raw_returns = 0;
  int no_returns = 0;
};

/// Preprocesses one record (the beam geometry comes with the record).
ScanPoints preprocess_scan(const io::LaserScan& scan, const ScanFilterOptions& options = {});

/// Keeps the first point falling into each square voxel of side `voxel_size_m` (order kept).
std::vector<Eigen::Vector2d> voxel_filter(const std::vector<Eigen::Vector2d>& points, double voxel_size_m);

}  // namespace cairn::slam2d
