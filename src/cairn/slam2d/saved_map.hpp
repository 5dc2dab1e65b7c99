#pragma once
/// \file
/// A finished 2D map as `cairn slam2d --save-map` keeps it for reuse (pure localisation,
/// `cairn localize2d`): every submap's probability grid and points at the final, optimised
/// poses, the keyframe poses, and the settings the grids were built with. Slam2d::export_map()
/// fills it; map_file.hpp writes and reads it.
///
/// Frames: `T_world_submap` places a submap's grid and points (both in the submap frame) in the
/// map's world frame, the frame of the trajectory `cairn slam2d` wrote.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "cairn/core/se2.hpp"
#include "cairn/core/time.hpp"
#include "cairn/slam2d/point_map.hpp"
#include "cairn/slam2d/probability_grid.hpp"
#include "cairn/slam2d/range_scan.hpp"

namespace cairn::slam2d {

struct SavedSubmap {
  core::SE2 T_world_submap;  ///< the submap's first keyframe (its anchor), optimised
  /// Hits and misses of the submap's keyframes rendered at their optimised poses relative to
  /// the anchor (so the grid agrees with the final map, not with the drifting front end).
  ProbabilityGrid grid;
  std::vector<Eigen::Vector2d> points_submap;  ///< hit points, voxel-filtered, submap frame
  int segment = 0;                             ///< map segment the submap belongs to
  int first_keyframe = 0;                      ///< index into SavedMap2D::keyframes
  int keyframe_count = 0;
};

struct SavedKeyframe {
  core::Timestamp time;
  core::SE2 T_world_laser;  ///< optimised
  int segment = 0;
};

struct SavedMap2D {
  /// What the grids and point sets were built with; a localiser must match scans the same way.
  ProbabilityGridOptions grid;
  PointMapOptions map_points;
  ScanFilterOptions filter;
  std::vector<SavedSubmap> submaps;
  std::vector<SavedKeyframe> keyframes;
  /// Where the map came from (the log's path as given), for the report; may be empty.
  std::string source;
};

}  // namespace cairn::slam2d
