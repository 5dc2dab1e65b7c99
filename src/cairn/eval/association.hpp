#pragma once
/// \file
/// Pairing the poses of a reference and an estimated trajectory, as evo does
/// (evo/core/sync.py, associate_trajectories and matching_time_indices):
///
///  - The SHORTER trajectory (fewer poses; the estimate when both are equally long) is walked
///    in order. For each of its stamps the nearest stamp of the longer trajectory is found
///    (the earlier one on a tie, as numpy.argmin returns the first minimum), after adding
///    `offset_s` to the estimate's stamps. The pair is kept when the difference is at most
///    `max_time_difference_s`.
///  - A stamp of the longer trajectory can therefore be used by more than one pair, and the
///    pairs come in the shorter trajectory's order.
///  - Without stamps on either side, poses pair by index (KITTI files), which needs equal
///    lengths. With stamps on one side only, the same rule applies.
///
/// The comparison is done as evo does it, in double-precision seconds: each stamp becomes the
/// double nearest to its decimal value (what evo's float() parse gives), the offset is added in
/// double, and |difference| <= max_time_difference_s is tested in double. TUM stamps have 4-6
/// decimals, so differences of exactly 0.01 s occur (fr2/desk has them); whether they pass
/// depends on that rounding, and integer nanoseconds would pair differently from evo.

#include <cstddef>
#include <vector>

#include "cairn/core/time.hpp"

#include "cairn/eval/status.hpp"
#include "cairn/eval/matrix_trajectory.hpp"

namespace cairn::eval {

struct AssociationOptions {
  /// Largest |t_estimate + offset - t_reference| that still pairs two poses, seconds, >= 0.
  /// Default 0.01 s: evo's `--t_max_diff` default.
  double max_time_difference_s = 0.01;
  /// Added to every estimate stamp before matching, seconds (evo's `--t_offset`). Default 0.
  double offset_s = 0.0;
  /// Pair by index even when both trajectories have stamps (lengths must agree). Default off.
  bool by_index = false;
};

/// Index pairs: reference.poses[reference_indices[k]] belongs with
/// estimate.poses[estimate_indices[k]].
struct Association {
  Outcome outcome;
  std::vector<std::size_t> reference_indices;
  std::vector<std::size_t> estimate_indices;
  /// True when the pairs came from timestamps, false when by index.
  bool by_time = false;
  /// Poses of the shorter trajectory: the most pairs possible.
  std::size_t max_pairs = 0;

  std::size_t size() const { return reference_indices.size(); }
};

/// Pairs `reference` and `estimate` (see the file comment). Fails with kEmpty, kSizeMismatch,
/// kUnsortedStamps, kNotFinite, kInvalidOptions or kNoOverlap, saying which.
Association associate(const MatrixTrajectory& reference, const MatrixTrajectory& estimate,
                      const AssociationOptions& options = {});

/// The double evo holds for a stamp: the nearest double to its exact decimal value.
double evo_seconds(core::Timestamp stamp);

}  // namespace cairn::eval
