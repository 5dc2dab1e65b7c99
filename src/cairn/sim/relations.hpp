#pragma once
/// \file
/// Freiburg-style relations (Kuemmerle et al., "On measuring the accuracy of SLAM algorithms",
/// Autonomous Robots 27(4), 2009): reference relative poses between pairs of scans, taken here
/// from the simulator's exact ground truth.
///
/// Two kinds, as in the benchmark's relation files:
///  - short: a chain along the run, from each chosen scan to the first scan at least
///    short_interval_s later (local accuracy);
///  - long: pairs of scans at least long_min_separation_s apart whose true poses are within
///    long_max_distance_m and long_max_heading_difference_rad of each other (revisits: the
///    global consistency a loop closure restores), drawn at random (seeded) among all such
///    pairs of the scans sampled every long_candidate_spacing_s, at most long_count of them.
///
/// File format, one relation per line, as aces.relations:
///   t_i t_j x y z roll pitch yaw
/// t_i, t_j: scan times written exactly as the CARMEN log's ipc_timestamp (6 decimals);
/// (x, y, yaw) = T_i_j = T_world_i^-1 T_world_j, the pose of scan j in the frame of scan i
/// (metres, radians), written as the shortest text that reads back to the same double;
/// z roll pitch = 0 0 0.

#include <cstdint>
#include <string>
#include <vector>

#include "cairn/core/se2.hpp"
#include "cairn/core/time.hpp"
#include "cairn/sim/trajectory.hpp"

namespace cairn::sim {

struct RelationsOptions {
  /// Time between the two scans of a short relation, seconds (> 0).
  double short_interval_s = 1.0;
  /// Long relations: how many at most, and which pairs qualify (see the file comment).
  int long_count = 200;
  double long_min_separation_s = 30.0;
  double long_max_distance_m = 3.0;
  double long_max_heading_difference_rad = 1.5;
  double long_candidate_spacing_s = 1.0;

  bool is_valid(std::string* why) const;
};

struct Relation {
  core::Timestamp from;
  core::Timestamp to;
  /// T_from_to from the ground truth.
  core::SE2 T_from_to;
};

/// Relations over the scans truth[scan_samples[k]]: the short chain first, then the long ones
/// in the order drawn. Precondition: options.is_valid().
std::vector<Relation> make_relations(const std::vector<TrajectorySample>& truth,
                                     const std::vector<std::size_t>& scan_samples, const RelationsOptions& options,
                                     std::uint64_t seed);

/// Writes the relations atomically. Throws io::ParseError when the file cannot be written.
void write_relations(const std::string& path, const std::vector<Relation>& relations);

}  // namespace cairn::sim
