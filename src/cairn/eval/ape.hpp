#pragma once
/// \file
/// Absolute pose error (APE, "ATE" for the translation part), as evo's APE metric
/// (evo/core/metrics.py, APE.process_data; evo/main_ape.py):
///  1. associate reference and estimate (association.hpp; by index without stamps);
///  2. align the paired estimate to the paired reference (alignment.hpp; none by default);
///  3. per pair, the error of E = T_est^-1 T_ref under the pose relation (pose_relation.hpp);
///  4. statistics over all pairs (statistics.hpp).

#include <vector>

#include "cairn/eval/alignment.hpp"
#include "cairn/eval/association.hpp"
#include "cairn/eval/pose_relation.hpp"
#include "cairn/eval/statistics.hpp"
#include "cairn/eval/matrix_trajectory.hpp"

namespace cairn::eval {

struct ApeOptions {
  /// What to measure. Default: translation part (m), the usual "ATE".
  PoseRelation relation = PoseRelation::kTranslationPart;
  /// How poses pair up. Default: evo's (0.01 s, no offset).
  AssociationOptions association;
  /// Default: no alignment (evo's default; `-a` is kSE3, `-as` kSim3).
  AlignmentOptions alignment;
};

struct ApeResult {
  Outcome outcome;
  Association association;
  Alignment alignment;
  /// The paired poses; the estimate after alignment. errors[k] belongs to pair k.
  std::vector<Matrix4> reference;
  std::vector<Matrix4> estimate;
  /// Seconds since the first paired reference stamp, or the pair index without stamps.
  std::vector<double> time_s;
  std::vector<double> errors;
  /// Valid when outcome.ok().
  Statistics statistics;
  PoseRelation relation = PoseRelation::kTranslationPart;
};

/// Per-pair APE of paired, already aligned poses. Precondition: equal sizes.
std::vector<double> ape_errors(const std::vector<Matrix4>& reference, const std::vector<Matrix4>& estimate,
                               PoseRelation relation);

/// Steps 1-4 above. Fails (outcome) on empty input, mismatched lengths without stamps,
/// unsorted stamps, NaN, no common stamps, or a degenerate alignment.
ApeResult evaluate_ape(const MatrixTrajectory& reference, const MatrixTrajectory& estimate,
                       const ApeOptions& options = {});

}  // namespace cairn::eval
