#pragma once
/// \file
/// Steps shared by APE and RPE: associate, gather the paired poses, align.

#include <vector>

#include "cairn/eval/alignment.hpp"
#include "cairn/eval/association.hpp"
#include "cairn/eval/matrix_trajectory.hpp"

namespace cairn::eval {

struct PairedPoses {
  Outcome outcome;
  Association association;
  Alignment alignment;
  std::vector<Matrix4> reference;
  /// After alignment.
  std::vector<Matrix4> estimate;
  /// Seconds since the first paired reference stamp, or the pair index without stamps.
  std::vector<double> time_s;
};

/// Associates, gathers, aligns; the first failure ends it (outcome says which).
PairedPoses pair_and_align(const MatrixTrajectory& reference, const MatrixTrajectory& estimate,
                           const AssociationOptions& association, const AlignmentOptions& alignment);

}  // namespace cairn::eval
