#pragma once
/// \file
/// Relative pose error (RPE), as evo's RPE metric (evo/core/metrics.py, RPE.process_data and
/// id_pairs_from_delta; evo/core/filters.py):
///  1. associate and (optionally) align, as for APE (ape.hpp);
///  2. choose index pairs (i, j) on the paired poses of the ESTIMATE (evo's default;
///     `pairs_from_reference` uses the reference instead):
///     - frames, consecutive (filter_pairs_by_index): ids 0, d, 2d, ...; pairs of neighbours
///       (0, d), (d, 2d), ...
///     - frames, all pairs: (i, i + d) for every i with i + d < n.
///     - metres, consecutive (filter_pairs_by_path): walk the poses summing |p_k - p_{k-1}|;
///       whenever the sum reaches delta (>=), record k and restart the sum at 0. Pairs of
///       neighbouring recorded ids. The stretch before the first recorded id is never a pair
///       start (evo's behaviour, kept).
///     - metres, all pairs: with D the cumulative path length, for every i the j > i whose
///       D_j - D_i is nearest to delta (first on a tie), kept when that difference is within
///       delta * relative_delta_tolerance.
///  3. per pair, E = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j) (evo rpe_base; Q reference, P estimate);
///     error under the pose relation; statistics.

#include <cstddef>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include "cairn/eval/alignment.hpp"
#include "cairn/eval/association.hpp"
#include "cairn/eval/pose_relation.hpp"
#include "cairn/eval/statistics.hpp"
#include "cairn/eval/matrix_trajectory.hpp"

namespace cairn::eval {

enum class DeltaUnit {
  /// delta counts poses (must be a whole number >= 1).
  kFrames,
  /// delta is path length in metres (> 0).
  kMeters,
};

/// "f" / "m" as evo's `-u`; "frames" and "meters"/"metres" are accepted too.
std::string_view to_string(DeltaUnit unit);
std::optional<DeltaUnit> delta_unit_from_name(std::string_view name);

struct RpeOptions {
  /// Default: translation part (m), as evo_rpe.
  PoseRelation relation = PoseRelation::kTranslationPart;
  /// Pair distance, in delta_unit. Default 1 frame (evo's default).
  double delta = 1.0;
  DeltaUnit delta_unit = DeltaUnit::kFrames;
  /// All overlapping pairs instead of consecutive ones (evo `--all_pairs`). Default off.
  bool all_pairs = false;
  /// Metres, all pairs: accept |path - delta| <= delta * this. Default 0.1 (evo rel_delta_tol).
  double relative_delta_tolerance = 0.1;
  /// Select pairs on the reference's path instead of the estimate's (evo
  /// `--pairs_from_reference`). Default off, as evo.
  bool pairs_from_reference = false;
  AssociationOptions association;
  /// Default none (evo's default). SE(3) alignment cannot change an RPE; Sim(3) can.
  AlignmentOptions alignment;

  /// True when usable; otherwise false with every problem, "; "-separated, in *why (core/problems.hpp).
  bool is_valid(std::string* why) const;
};

using IndexPair = std::pair<std::size_t, std::size_t>;

/// Step 2 on poses (see the file comment). Precondition: options valid.
std::vector<IndexPair> rpe_pairs(const std::vector<Matrix4>& poses, const RpeOptions& options);

struct RpeResult {
  Outcome outcome;
  Association association;
  Alignment alignment;
  /// Paired poses (estimate aligned); the pairs index into them.
  std::vector<Matrix4> reference;
  std::vector<Matrix4> estimate;
  std::vector<double> time_s;
  std::vector<IndexPair> pairs;
  /// errors[k] belongs to pairs[k].
  std::vector<double> errors;
  Statistics statistics;
  PoseRelation relation = PoseRelation::kTranslationPart;
};

/// Steps 1-3. Fails (outcome) like evaluate_ape, with kInvalidOptions for bad options and
/// kNoPairs when the delta selects no pair.
RpeResult evaluate_rpe(const MatrixTrajectory& reference, const MatrixTrajectory& estimate,
                       const RpeOptions& options = {});

}  // namespace cairn::eval
