#pragma once
/// \file
/// Random false loop closures, as in the robust back-end experiments of Suenderhauf & Protzel
/// ("Switchable constraints for robust pose graph SLAM", IROS 2012; the Vertigo package's
/// "random" outliers): an edge between two random non-consecutive poses with a random relative
/// pose and the information matrix of a randomly chosen existing edge, so it looks as confident
/// as a real measurement.

#include <cstdint>
#include <string>

#include "cairn/io/pose_graph.hpp"

namespace cairn::backend {

struct OutlierOptions {
  /// Number of false loop closures to add (appended after the file's edges). >= 0.
  int count = 0;
  std::uint64_t seed = 1;
  /// Translations drawn uniformly in [-extent, extent] per axis, metres. > 0.
  double translation_extent_m = 10.0;
};

/// Every reason `options` cannot be honoured on `graph`, one per line ("" = none): a count below
/// 0, an extent that is not a finite number > 0, fewer than 3 poses or no edge to copy an
/// information matrix from, or more false loop closures than the graph has distinct ordered pairs
/// of non-consecutive poses (beyond that every one would repeat another). Checked before any
/// allocation.
template <class Group>
std::string outlier_request_problems(const io::PoseGraphT<Group>& graph, const OutlierOptions& options);

/// Adds false loop closures (throws std::invalid_argument with outlier_request_problems() when
/// the request cannot be honoured); rotations are uniform on SO(2) / SO(3) (Shoemake 1992 for SO(3)).
/// Deterministic for a given seed (own uniform generator, no std distributions).
template <class Group>
void add_false_loop_closures(io::PoseGraphT<Group>& graph, const OutlierOptions& options);

}  // namespace cairn::backend
