#pragma once
/// \file
/// Ground truth for testing 3D LiDAR SLAM on the simulated scans: which scan pairs are true
/// loop closures, and which scans lie inside a world's passage (tunnel, garage).

#include <cstddef>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/sim/world_3d.hpp"

namespace cairn::sim {

struct LoopTruthOptions {
  /// A pair of scans is a true loop closure when their sensor positions (at the sweep starts)
  /// are at most max_distance_m apart, metres (> 0) ...
  double max_distance_m = 5.0;
  /// ... and their times differ by at least min_separation_s, seconds (>= 0).
  double min_separation_s = 20.0;
};

struct TrueLoop {
  /// Scan indices, earlier < later.
  std::size_t earlier = 0;
  std::size_t later = 0;
  /// Horizontal and vertical distance together (3D), metres.
  double distance_m = 0.0;
  /// |yaw(later) - yaw(earlier)| wrapped to [0, pi]: near pi for a reverse revisit.
  double heading_difference_rad = 0.0;
  double time_difference_s = 0.0;
};

/// Every pair meeting `options`, sorted by (later, earlier). O(n^2) in the number of scans.
std::vector<TrueLoop> find_true_loops(const std::vector<core::SE3>& T_world_lidar, const std::vector<double>& times_s,
                                      const LoopTruthOptions& options);

/// The scans inside a passage. A scan is inside when its sensor position at the sweep start,
/// projected on the axis, lies between the entry (0) and the exit (length_m).
struct PassageScans {
  Passage3D passage;
  /// False when no scan is inside (then the indices below mean nothing).
  bool any_inside = false;
  std::size_t first_inside = 0;
  std::size_t last_inside = 0;
  double first_inside_time_s = 0.0;
  double last_inside_time_s = 0.0;
  /// Scans farther than the LiDAR's max range from both ends along the axis (nothing but the
  /// passage's own walls in range); `any_blind` false when there are none.
  bool any_blind = false;
  std::size_t first_blind = 0;
  std::size_t last_blind = 0;
};

PassageScans find_passage_scans(const Passage3D& passage, const std::vector<core::SE3>& T_world_lidar,
                                const std::vector<double>& times_s, double max_range_m);

}  // namespace cairn::sim
