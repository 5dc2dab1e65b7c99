#pragma once
/// \file
/// Structure of a pose graph as `cairn info` reports it: poses, edges, odometry chain versus
/// loop closures, connected components, initial guess.

#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "cairn/io/graph_io.hpp"
#include "cairn/io/pose_graph.hpp"

namespace cairn::io {

struct GraphStatistics {
  int dimension = 0;
  /// Distinct poses: VERTEX lines when present, otherwise the ids the edges refer to.
  std::size_t poses = 0;
  std::size_t vertices = 0;
  std::size_t edges = 0;
  /// Edges between consecutive ids (|to - from| = 1): the odometry chain, by the convention of
  /// every benchmark graph cairn ships with. All other edges count as loop closures.
  std::size_t odometry_edges = 0;
  std::size_t loop_closure_edges = 0;
  /// Edges between the same pair of poses as an earlier edge (either direction).
  std::size_t duplicate_edges = 0;
  /// Connected components of the graph over all poses (an isolated vertex is one component).
  std::size_t connected_components = 0;
  /// Poses of the largest component.
  std::size_t largest_component = 0;
  /// Vertices no edge touches.
  std::size_t isolated_vertices = 0;
  std::size_t fixed = 0;
  std::int64_t min_id = 0;
  std::int64_t max_id = 0;
  /// Ids are exactly min_id..max_id with no gap.
  bool contiguous_ids = false;
  /// VERTEX lines give an initial guess for every pose.
  bool has_initial_guess = false;
};

GraphStatistics compute_statistics(const PoseGraph& graph);

/// What `cairn info --json` says of a pose-graph file: its statistics and its read report (record
/// counts, unknown records, information matrices that were not positive definite, warnings).
nlohmann::json graph_info_json(const std::string& path, const GraphStatistics& statistics, const GraphReadReport& report);

}  // namespace cairn::io
